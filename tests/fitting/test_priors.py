"""A Gaussian prior on the solver's vector (``fitting/solver/hold.py``, ``compiled.py``): what a spatially varying
fit's smoothness prior draws each texel with (``svbrdf/smoothing.py``).

A heavy prior holds its entries at its mean, a prior of weight 0 changes nothing, the reported cost is the data's
alone (the prior's part left out) whether the fit holds parameters or not, and a hold moved onto its bounds keeps its
prior.
"""

import warnings

import numpy as np
import pytest

from brdffit import BrdfInputError, data_synth
from brdffit.fitting.many.batch import fit_many
from brdffit.fitting.options import holding_of
from brdffit.fitting.single.fit import start_vector
from brdffit.fitting.solver.hold import at_bounds, free_hold
from brdffit.physics.models.registry import get_model

WARD = {"rho_d": [0.3, 0.25, 0.2], "rho_s": [0.08, 0.08, 0.08], "alpha": 0.15}


@pytest.fixture(scope="module")
def three():
    """Three small Ward datasets (1% noise, 400 samples each)."""
    datasets = []
    for seed in range(3):
        wi, wo = data_synth.uniform_random(400, seed=seed)
        datasets.append(data_synth.synthesize("ward", WARD, wi, wo, noise=0.01, seed=seed))
    return datasets


def _fits(datasets, fixed=None, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_many(datasets, "ward", "log", progress=False, holding=holding_of(None, fixed=fixed), **options)


def _log_cost(result, samples) -> float:
    """The log loss's rᵀr of ``result`` on ``samples``, computed here from its BRDF: residuals ln(1 + f cos θi) −
    ln(1 + y cos θi)."""
    cosine = samples.wi[:, 2:3]
    return float(
        np.sum((np.log1p(result.predict(samples.wi, samples.wo) * cosine) - np.log1p(samples.values * cosine)) ** 2)
    )


@pytest.mark.parametrize("fixed", [None, {"rho_d": [0.3, 0.25, 0.2]}])
def test_a_heavy_prior_holds_its_entries_at_its_mean_and_the_cost_is_the_datas(three, fixed):
    """alpha's coordinate (its logarithm) drawn to ln 0.3 with a weight 10¹⁰ times the data's curvature there ends
    at 0.3 to 1e-6; the other entries are free (the albedos move to fit the data under that alpha); the reported
    cost is the data's rᵀr at the parameters returned (1e-10: two summation orders), with or without held albedos."""
    plain = _fits(three, fixed=fixed)
    model = get_model("ward")
    size = model.unconstrained.size(3)
    mean = np.zeros(size)
    mean[-1] = np.log(0.3)
    weight = np.zeros(size)
    weight[-1] = 1e10
    drawn = _fits(three, fixed=fixed, start=[fit.params for fit in plain], priors=[(mean, weight)] * 3)
    for fit, samples in zip(drawn, three, strict=True):
        assert fit.params["alpha"] == pytest.approx(0.3, rel=1e-6)
        assert fit.cost == pytest.approx(_log_cost(fit, samples), rel=1e-10)
        if fixed:
            assert fit.params["rho_d"] == pytest.approx(fixed["rho_d"], rel=1e-12)


def test_each_dataset_has_its_own_prior(three):
    """Three means, one per dataset: each ends at its own (a mix-up of the stacked rows would not)."""
    plain = _fits(three)
    size = get_model("ward").unconstrained.size(3)
    priors = []
    for alpha in (0.1, 0.2, 0.3):
        mean, weight = np.zeros(size), np.zeros(size)
        mean[-1], weight[-1] = np.log(alpha), 1e10
        priors.append((mean, weight))
    drawn = _fits(three, start=[fit.params for fit in plain], priors=priors)
    assert [fit.params["alpha"] for fit in drawn] == pytest.approx([0.1, 0.2, 0.3], rel=1e-6)


def test_a_prior_beyond_a_bound_ends_on_the_bound(three):
    """alpha bounded to [0.05, 0.2] and drawn hard to 0.3: the fit ends on 0.2, the on-bound solve kept by the data's
    cost and the prior's together."""
    plain = _fits(three)
    size = get_model("ward").unconstrained.size(3)
    mean, weight = np.zeros(size), np.zeros(size)
    mean[-1], weight[-1] = np.log(0.3), 1e6
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        drawn = fit_many(
            three, "ward", "log", progress=False, holding=holding_of(None, bounds={"alpha": (0.05, 0.2)}),
            start=[fit.params for fit in plain], priors=[(mean, weight)] * 3,
        )  # fmt: skip
    assert [fit.params["alpha"] for fit in drawn] == pytest.approx([0.2] * 3, rel=1e-9)


def test_a_prior_of_weight_zero_changes_nothing(three):
    plain = _fits(three)
    model = get_model("ward")
    means = [start_vector(model, fit.params, 3) + 1.0 for fit in plain]
    again = _fits(three, start=[fit.params for fit in plain], priors=[(mean, np.zeros(mean.size)) for mean in means])
    for before, after in zip(plain, again, strict=True):
        assert after.params["alpha"] == pytest.approx(before.params["alpha"], rel=1e-9)
        assert after.cost == pytest.approx(before.cost, rel=1e-9)


def test_a_prior_lies_between_the_datas_optimum_and_its_mean(three):
    """A prior as heavy as the data's own curvature along alpha's coordinate: the optimum of the sum lies strictly
    between the data's optimum and the prior's mean, and the data's cost there is higher than at its own optimum."""
    plain = _fits(three)
    model = get_model("ward")
    size = model.unconstrained.size(3)
    mean, weight = np.zeros(size), np.zeros(size)
    mean[-1], weight[-1] = np.log(0.3), 10.0
    drawn = _fits(three, start=[fit.params for fit in plain], priors=[(mean, weight)] * 3)
    for before, after in zip(plain, drawn, strict=True):
        assert before.params["alpha"] < after.params["alpha"] < 0.3
        assert after.cost > before.cost


def test_a_hold_moved_onto_its_bounds_keeps_its_prior():
    hold = free_hold(3)._replace(bounded=np.array([0.0, 1.0, 0.0]), low=np.zeros(3), high=np.ones(3))
    hold = hold._replace(prior_mean=np.full(3, 0.5), prior_weight=np.array([1.0, 0.0, 2.0]))
    moved = at_bounds(np.array([0.2, 0.999, 0.4]), hold)
    assert moved.free[1] == 0.0 and moved.value[1] == 1.0  # on its upper bound
    np.testing.assert_array_equal(moved.prior_weight, hold.prior_weight)
    np.testing.assert_array_equal(moved.prior_mean, hold.prior_mean)


def test_priors_must_be_one_per_dataset_with_a_start_and_the_vectors_length(three):
    size = get_model("ward").unconstrained.size(3)
    starts = [{"rho_d": [0.3] * 3, "rho_s": [0.1] * 3, "alpha": 0.2}] * 3
    with pytest.raises(BrdfInputError, match="2 priors for 3 datasets"):
        _fits(three, start=starts, priors=[(np.zeros(size), np.zeros(size))] * 2)
    with pytest.raises(BrdfInputError, match="dataset 0 has a prior but no start"):
        _fits(three, priors=[(np.zeros(size), np.zeros(size))] * 3)
    with pytest.raises(BrdfInputError, match=r"dataset 0's prior has a mean of shape \(3,\)"):
        _fits(three, start=starts, priors=[(np.zeros(3), np.zeros(size))] * 3)
