"""lmfit's figures on a result (``FitResult.ndata``, ``nvarys``, ``chisqr``, ``redchi``, ``aic``, ``bic``;
``fitting/single/criteria.py``): written out here from their definitions (Akaike 1974, Schwarz 1978, lmfit's
``MinimizerResult``), equal to ``brdffit compare``'s, and read back from a result file."""

import json
import math

import numpy as np
import pytest

from brdffit import FitWarning, Samples, compare, data_synth, fit, load_result

WARD = {"rho_d": [0.15, 0.1, 0.05], "rho_s": [0.04, 0.035, 0.03], "alpha": 0.15}
GEOMETRY = data_synth.uniform_random(400, seed=3)


def ward_samples(**extra) -> Samples:
    samples = data_synth.synthesize("ward", WARD, *GEOMETRY, noise=0.02, seed=2)
    return Samples.from_arrays(samples.wi, samples.wo, samples.values, channels=samples.channels, **extra)


def test_the_figures_are_their_definitions_without_sigma():
    result = fit(ward_samples(), "ward")
    n, k, cost = 400 * 3, 3 + 3 + 1, result.cost  # rho_d and rho_s per channel, alpha
    assert (result.ndata, result.nvarys, result.chisqr) == (n, k, cost)
    # float64 sums in another order: a few ulps of |AIC| ~ 1e4
    assert result.redchi == pytest.approx(cost / (n - k), rel=1e-14)
    assert result.aic == pytest.approx(n * math.log(cost / n) + 2 * k, rel=1e-13)
    assert result.bic == pytest.approx(n * math.log(cost / n) + k * math.log(n), rel=1e-13)


def test_with_sigma_the_deviance_is_the_chi_square_and_zero_weights_are_not_counted():
    samples = data_synth.synthesize("ward", WARD, *GEOMETRY, noise=0.02, seed=2)
    weight = np.ones(400)
    weight[:100] = 0.0
    sigmas = 0.02 * samples.values
    result = fit(ward_samples(sigma=sigmas, weight=weight), "ward")
    n, k = 300 * 3, 7
    assert result.sigma and (result.ndata, result.nvarys) == (n, k)
    assert result.aic == pytest.approx(result.cost + 2 * k, rel=1e-13)
    assert result.bic == pytest.approx(result.cost + k * math.log(n), rel=1e-13)
    assert 0.5 < result.redchi < 2.0  # the noise is the sigma given: χ²/ν near 1


def test_held_parameters_are_not_counted():
    with pytest.warns(FitWarning):  # a plastic fitted as a metal: k on its end
        conductor = fit(ward_samples(), "cook-torrance", fresnel="conductor", max_steps=5)
    # kd (3), m, eta (3), k (3); ks (3) held at 1 by default
    assert conductor.nvarys == 3 + 1 + 3 + 3 and conductor.fixed == {"ks": [1.0] * 3}


def test_the_figures_are_compares():
    samples = ward_samples()
    comparison = compare(samples, ["lambert", "ward"], folds=2)
    for score in comparison.models:
        assert (score.k, score.aic, score.bic) == (score.result.nvarys, score.result.aic, score.result.bic)
    ward = next(score for score in comparison.models if score.spec == "ward")
    alone = fit(samples, "ward")
    assert ward.aic == pytest.approx(alone.aic, rel=1e-9)  # one fit, one optimum: to the solver's tolerance


def test_a_result_file_keeps_them_and_an_older_file_counts_every_sample(tmp_path):
    result = fit(ward_samples(), "ward")
    result.save(tmp_path / "ward.json")
    back = load_result(tmp_path / "ward.json")
    assert (back.ndata, back.nvarys, back.aic, back.bic) == (result.ndata, result.nvarys, result.aic, result.bic)
    content = json.loads((tmp_path / "ward.json").read_text())
    assert content["fit"]["n_values"] == 1200 and content["fit"]["sigma"] is False
    for name in ("n_values", "sigma"):
        del content["fit"][name]
    (tmp_path / "older.json").write_text(json.dumps(content))
    older = load_result(tmp_path / "older.json")
    assert older.n_values is None and older.ndata == result.n_samples * 3 and older.aic == result.aic
