"""Fixed and bounded parameters (``fitting/single/constraints.py``, ``fitting/solver/hold.py``): what a user holds stays
held.

The acceptance cases of the issue: a dielectric Cook-Torrance with ``eta`` fixed at its truth recovers the rest
and narrows the Laplace errors of ``ks``; the ``ks``/``f0`` pair that near-normal data cannot separate stops being
degenerate when one of them is fixed. Then the pieces: the map's derivative, the start search's held least
squares, bounds, Lafortune's directions, batches, the result file, MCMC and every error.
"""

import json
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import nnls

import brdffit
from brdffit import BrdfInputError, data_synth, get_model
from brdffit.fitting.single.constraints import check_names, constraints_for
from brdffit.fitting.solver.hold import Hold, on_bound, respected, slopes, theta_of, z_of
from brdffit.fitting.starts.grid import nonnegative_least_squares

DIELECTRIC = {"kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5], "m": 0.2, "eta": 1.5}
SCHLICK = {"kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5], "m": 0.2, "f0": 0.04}
#: Recovery tolerance of tests/fitting/test_recovery.py: albedos and lobe shapes within 3% of the truth.
RECOVERY = 0.03


def quiet_fit(samples, model, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return brdffit.fit(samples, model, **options)


@pytest.fixture(scope="module")
def dielectric():
    """1% noise with its sigma (so Laplace's errors are calibrated, not rescaled) on a 6 × 18 × 18 grid."""
    wi, wo = data_synth.hemisphere_grid(6, 18, 18)
    return data_synth.synthesize(
        "cook-torrance", DIELECTRIC, wi, wo, noise=0.01, seed=3, with_sigma=True, fresnel="dielectric"
    )


@pytest.fixture(scope="module")
def near_normal():
    """Schlick Cook-Torrance seen within 35° of the normal: F ≈ f0 there, so only ks·f0 is measured."""
    wi, wo = data_synth.hemisphere_grid(6, 18, 36)
    return data_synth.synthesize("cook-torrance", SCHLICK, wi, wo, noise=0.01, seed=3, with_sigma=True).within(35)


def flat(params: dict) -> dict[str, float]:
    out = {}
    for name, value in params.items():
        for index, one in enumerate(value if isinstance(value, list) else [value]):
            out[f"{name}[{index}]" if isinstance(value, list) else name] = one
    return out


# ---------------------------------------------------------------------------------------------- acceptance
@pytest.mark.slow
def test_fixed_eta_recovers_the_rest_and_narrows_the_errors_of_ks(dielectric):
    free = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", uncertainty="laplace")
    held = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", uncertainty="laplace", fixed={"eta": 1.5})
    assert held.converged and held.params["eta"] == 1.5 and held.fixed == {"eta": 1.5}
    # the written parameters are those solved (a fixed value is written exactly, and solved at θ = ln(eta - 1))
    assert np.sum(held.residuals(dielectric) ** 2) == pytest.approx(held.cost, rel=1e-9)
    truth = flat(DIELECTRIC)
    for name, value in flat(held.params).items():
        assert abs(value - truth[name]) <= RECOVERY * truth[name], name
    assert held.uncertainty["stderr"]["eta"] == 0.0
    for free_error, held_error in zip(free.uncertainty["stderr"]["ks"], held.uncertainty["stderr"]["ks"], strict=True):
        assert held_error < 0.9 * free_error  # eta and ks trade off (correlation ≈ -0.9): fixing one narrows the other
    assert held.uncertainty["diagnostics"]["dof"] == free.uncertainty["diagnostics"]["dof"] + 1


def test_a_degenerate_pair_stops_being_degenerate_when_one_is_fixed(near_normal):
    free = quiet_fit(near_normal, "cook-torrance", uncertainty="laplace")
    # Only ks·f0 is measured: the pair is said degenerate, or one of it undetermined (an error beyond 10× its
    # plausible range, issue 29) and held while the other's error is taken.
    pair_said = "degenerate" in " ".join(free.uncertainty["warnings"])
    assert pair_said or any(name.split("[")[0] in ("f0", "ks") for name in free.uncertainty.undetermined)
    for fixed in ({"f0": 0.04}, {"ks": 0.5}):
        held = quiet_fit(near_normal, "cook-torrance", uncertainty="laplace", fixed=fixed)
        assert not any("degenerate" in line for line in held.uncertainty["warnings"]), fixed
        (name,) = fixed
        other = "ks" if name == "f0" else "f0"
        truth = flat(SCHLICK)
        for key, value in flat({other: held.params[other]}).items():
            assert abs(value - truth[key]) <= 0.10 * truth[key], key  # f0's recovery tolerance is 10%


def test_changing_a_fixed_value_or_a_bound_compiles_nothing(dielectric):
    # the first held fit compiles the held programs (a bound also compiles the solve that tries it on its bound)
    quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"eta": 1.5}, bounds={"m": [0.01, 1.0]})
    compiled = []
    listener = lambda event, duration, **_: compiled.append(event) if "backend_compile" in event else None
    jax.monitoring.register_event_duration_secs_listener(listener)
    try:
        quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"eta": 1.6})
        quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"m": 0.2}, bounds={"eta": [1.2, 2.0]})
    finally:
        jax.monitoring.unregister_event_duration_listener(listener)
    assert compiled == []


# ---------------------------------------------------------------------------------------------- the map
HOLD = Hold(
    free=np.array([1.0, 1.0, 0.0, 1.0]),
    bounded=np.array([0.0, 1.0, 0.0, 1.0]),
    value=np.array([0.0, 0.0, 2.5, 0.0]),
    low=np.array([0.0, -1.0, 0.0, 3.0]),
    high=np.array([0.0, 2.0, 0.0, 3.5]),
)


def test_slopes_are_the_maps_derivative():
    z = jnp.array([0.3, -0.7, 9.0, 1.9])
    assert np.allclose(np.diag(jax.jacfwd(theta_of)(z, HOLD)), slopes(z, HOLD), rtol=1e-14, atol=0)


def test_a_start_is_moved_onto_what_the_hold_allows():
    theta = np.array([0.4, 5.0, -1.0, 3.2])
    start = np.asarray(respected(jnp.asarray(theta), HOLD))
    assert start[0] == 0.4 and start[2] == 2.5 and start[3] == pytest.approx(3.2, rel=1e-12)
    assert -1.0 < start[1] < 2.0 and start[1] == pytest.approx(2.0 - 3e-3, rel=1e-9)  # 1e-3 of the range inside
    assert np.allclose(theta_of(z_of(jnp.asarray(start), HOLD), HOLD), start, rtol=1e-12)
    assert list(np.asarray(on_bound(jnp.array([0.0, 2.0, 2.5, 3.0]), HOLD))) == [0, 1, 0, -1]


def test_the_start_search_holds_albedos_in_its_least_squares(rng):
    basis = rng.random((3, 40))
    y = rng.random((40, 2))
    gram = np.einsum("bn,dn->bd", basis, basis)[None].repeat(2, 0)
    rhs = np.einsum("bn,nc->cb", basis, y)
    held = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), np.array([[0.3, 0.0, 0.0], [0.0, 0.0, 0.05]])
    x = np.asarray(nonnegative_least_squares(jnp.asarray(gram), jnp.asarray(rhs), tuple(map(jnp.asarray, held))))
    for c in range(2):
        fixed = held[0][c] > 0
        rest = y[:, c] - basis[fixed].T @ held[1][c][fixed]
        expected, _ = nnls(basis[~fixed].T, rest)
        assert np.allclose(x[c][fixed], held[1][c][fixed], rtol=0, atol=0)
        assert np.allclose(x[c][~fixed], expected, rtol=1e-9, atol=1e-12)


# ---------------------------------------------------------------------------------------------- bounds
def test_a_bound_that_excludes_the_truth_ends_on_it_with_a_warning(dielectric):
    result = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", bounds={"m": [0.05, 0.15]})
    # On the bound itself (solved again with m held there: the logistic map only reaches it in the limit), at
    # the cost of the fit that fixes m there: both are the constrained optimum.
    assert result.params["m"] == pytest.approx(0.15, rel=1e-12)
    assert any("m ended on its upper bound 0.15" in line for line in result.warnings)
    assert result.bounds == {"m": [0.05, 0.15]}
    on_it = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"m": 0.15})
    assert result.cost == pytest.approx(on_it.cost, rel=1e-9)
    again = quiet_fit(
        dielectric, "cook-torrance", fresnel="dielectric", bounds={"m": [0.05, 0.15]}, start=result.params
    )
    assert again.cost == pytest.approx(result.cost, rel=1e-9)


def test_a_bound_around_the_truth_changes_nothing(dielectric):
    free = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric")
    bounded = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", bounds={"m": [0.1, 0.4], "ks": [0, 0.9]})
    assert bounded.cost == pytest.approx(free.cost, rel=1e-8)  # the same optimum, found in other coordinates
    assert not bounded.warnings


def test_a_fixed_albedo_of_zero_is_written_as_zero(dielectric):
    result = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"kd": 0})
    assert result.params["kd"] == [0.0, 0.0, 0.0] and result.fixed == {"kd": [0.0, 0.0, 0.0]}


# ---------------------------------------------------------------------------------------------- Lafortune, batches
def test_a_lafortune_direction_is_held_by_cxy(rng):
    wi, wo = data_synth.hemisphere_grid(6, 18, 18)
    truth = {"rho_d": [0.2], "lobes": [{"rho_s": [0.6], "cxy": -0.6, "cz": float(np.sqrt(1 - 0.72)), "n": 20.0}]}
    samples = data_synth.synthesize("lafortune", truth, wi, wo, noise=0.01, seed=1)
    result = quiet_fit(samples, "lafortune", lobes=2, fixed={"lobes[1].cxy": 0.5}, bounds={"lobes[1].n": [1, 5]})
    second = result.params["lobes"][1]
    assert second["cxy"] == 0.5 and second["cz"] == pytest.approx(np.sqrt(1 - 0.5), rel=1e-15)
    assert 1 <= second["n"] <= 5
    assert result.params["lobes"][0]["cxy"] == pytest.approx(-0.6, rel=0.02)


def test_fit_batch_holds_every_dataset(dielectric):
    results = brdffit.fit_batch([dielectric, dielectric], "cook-torrance", fresnel="dielectric", fixed={"eta": 1.5})
    single = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"eta": 1.5})
    for result in results:
        assert result.params["eta"] == 1.5 and result.fixed == {"eta": 1.5}
        assert result.cost == pytest.approx(single.cost, rel=1e-10)


# ---------------------------------------------------------------------------------------------- the result
def test_the_result_file_and_table_keep_what_was_held(dielectric, tmp_path):
    result = quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", fixed={"eta": 1.5}, bounds={"m": [0.1, 0.3]})
    path = tmp_path / "fit.json"
    result.save(path)
    content = json.loads(path.read_text())
    assert content["fit"]["fixed"] == {"eta": 1.5} and content["fit"]["bounds"] == {"m": [0.1, 0.3]}
    again = brdffit.load_result(path)
    assert again.fixed == result.fixed and again.bounds == result.bounds
    table = again.table()
    assert "eta" in table and "= 1.5" in table and "bounds: m in [0.1, 0.3]" in table
    # Laplace of the loaded result knows what was held
    estimated = brdffit.laplace_uncertainty(again, dielectric)
    assert estimated.uncertainty["stderr"]["eta"] == 0.0 and estimated.uncertainty["diagnostics"]["fixed"] == ["eta"]


def test_mcmc_samples_only_the_free_parameters(dielectric):
    settings = brdffit.MCMC(walkers=12, steps=60, burn=20, seed=1)
    result = quiet_fit(
        dielectric,
        "cook-torrance",
        fresnel="dielectric",
        fixed={"eta": 1.5, "kd": [0.1, 0.2, 0.3]},
        uncertainty="mcmc",
        mcmc=settings,
    )
    diagnostics = result.uncertainty["diagnostics"]
    assert diagnostics["sampled"] == ["ks[r]", "ks[g]", "ks[b]", "m"]  # sigma given: no ln s
    assert result.uncertainty["stderr"]["eta"] == 0.0 and result.uncertainty["stderr"]["kd"] == [0.0, 0.0, 0.0]
    assert np.all(result.draws[:, 7] == 1.5)
    with pytest.raises(BrdfInputError, match="walkers"):
        quiet_fit(dielectric, "cook-torrance", fresnel="dielectric", uncertainty="mcmc", mcmc=settings)  # 8 > 6


def test_compare_counts_only_free_parameters(dielectric):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        comparison = brdffit.compare(dielectric, ["cook-torrance:fresnel=dielectric", "ward"], fixed={"eta": 1.5})
    scores = {score.spec: score for score in comparison}
    assert scores["cook-torrance:fresnel=dielectric"].k == 7 and scores["ward"].k == 7
    assert scores["cook-torrance:fresnel=dielectric"].result.fixed == {"eta": 1.5} and scores["ward"].result.fixed == {}
    assert "held: eta = 1.5" in comparison.table()
    assert brdffit.Comparison.from_dict(json.loads(comparison.to_json())).models[0].result.fixed == {"eta": 1.5}
    with pytest.raises(BrdfInputError, match="no compared model has a parameter 'eta'"):
        brdffit.compare(dielectric, ["ward"], fixed={"eta": 1.5})


# ---------------------------------------------------------------------------------------------- errors
CT = get_model("cook-torrance", fresnel="dielectric")


@pytest.mark.parametrize(
    ("fixed", "bounds", "message"),
    [
        ({"eta": 0.5}, None, r"fixed: eta = 0.5 is outside its domain > 1"),
        ({"foo": 1}, None, r"has no parameter 'foo'; its parameters are kd, ks, m, eta"),
        ({"kd": [0.1, 0.2]}, None, r"kd has 2 values but the samples have 3 channel"),
        ({"kd": -0.1}, None, r"outside its domain ≥ 0"),
        ({"m": "a"}, None, r"m takes numbers"),
        ({"m": True}, None, r"m takes numbers"),
        (None, {"m": [0.3, 0.1]}, r"low < high"),
        (None, {"m": [0, 1]}, r"reaches outside its domain > 0"),
        (None, {"m": [0.1, float("inf")]}, r"finite"),
        (None, {"m": 0.3}, r"two numbers"),
        ({"m": 0.2}, {"m": [0.1, 0.3]}, r"m is also fixed"),
        ({"kd": 0, "ks": 0, "m": 0.1, "eta": 1.5}, None, r"nothing is left to fit"),
        ([("eta", 1.5)], None, r"must be a dictionary"),
    ],
)
def test_bad_holds_are_one_line_errors(fixed, bounds, message):
    with pytest.raises(BrdfInputError, match=message) as caught:
        constraints_for(CT, 3, fixed, bounds)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("fixed", "bounds", "message"),
    [
        ({"lobes[0].cz": 0.5}, None, r"cz alone leaves the lobe forward or retro-reflective"),
        ({"lobes[0].cxy": 0.9}, None, r"cxy = 0.9 is outside \[-0.7071, 0.7071\]"),
        ({"lobes[2].n": 3}, None, r"no parameter 'lobes\[2\].n'"),
        ({"n": 3}, None, r"no parameter 'n'"),
        ({"lobes[0].cxy": 0.5}, {"lobes[0].cz": [0.1, 0.2]}, r"one direction"),
        ({"lobes[0].cxy": 0.5, "lobes[0].cz": 0.1}, None, r"2·cxy² \+ cz² = 1"),
    ],
)
def test_bad_lafortune_holds_are_one_line_errors(fixed, bounds, message):
    with pytest.raises(BrdfInputError, match=message):
        constraints_for(get_model("lafortune", lobes=2), 1, fixed, bounds)


def test_a_model_with_its_own_fit_takes_no_holds():
    """The data-driven kind (built here without its basis file, which building it by name reads)."""
    from brdffit.datadriven.model import PcaModel

    with pytest.raises(BrdfInputError, match="takes no fixed or bounded parameters"):
        constraints_for(PcaModel("pca", "data-driven"), 3, {"coefficients": 0})


def test_a_fixed_direction_is_recorded_as_held():
    """cxy and cz given together are put onto 2·cxy² + cz² = 1, and the record says what the fit held."""
    constraints = constraints_for(get_model("lafortune"), 1, {"lobes[0].cxy": 0.5, "lobes[0].cz": 0.7071})
    cxy, cz = constraints.fixed["lobes[0].cxy"], constraints.fixed["lobes[0].cz"]
    assert 2 * cxy**2 + cz**2 == pytest.approx(1.0, rel=1e-15) and cxy == pytest.approx(0.5, rel=1e-5)
    assert constraints_for(get_model("lafortune"), 1, {"lobes[0].cxy": -1 / np.sqrt(2)}) is not None  # cz = 0


def test_a_range_narrower_than_the_fit_can_tell_apart_is_refused():
    with pytest.raises(BrdfInputError, match="too narrow"):
        constraints_for(CT, 3, None, {"m": [1e-300, 1e-299]})  # both ends are the fit's smallest m, 1e-12


def test_names_are_checked_before_the_samples_are_known():
    check_names(CT, {"kd": [0.1, 0.2, 0.3], "eta": 1.5}, {"m": [0.1, 0.2]})
    with pytest.raises(BrdfInputError, match=r"eta = 0\.5"):
        check_names(CT, {"eta": 0.5})


def test_nothing_held_is_no_hold():
    assert constraints_for(CT, 3, {}, None) is None


def test_a_parameter_that_ends_on_its_bound_is_written_within_it():
    """The solver's scaled logit reaches a bound to within rounding (the pickled oak's Cook-Torrance, m bounded to
    [0.01, 0.1], ended at 0.10000000000000002): the result holds what the user allowed, the bound itself."""
    from paths import EXAMPLE

    samples = brdffit.load_samples(EXAMPLE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = brdffit.fit(samples, "cook-torrance", bounds={"m": [0.01, 0.1]})
    assert 0.01 <= result.params["m"] <= 0.1
    assert any("m ended on its upper bound 0.1" in line for line in result.warnings)
