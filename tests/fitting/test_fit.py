"""The fit: recovery of every model from the default start, losses, sigma, weights, starts, results."""

import contextlib
import json
import sys
import warnings

import numpy as np
import pytest
from catalogue import CASES, parametrize_cases
from reference_materials import flat_parameters

from brdffit import (
    BrdfInputError,
    FitResult,
    FitWarning,
    Samples,
    data_synth,
    evaluate,
    fit,
    get_model,
    load_result,
    load_samples,
)

#: A geometry that sees every lobe: 6000 random pairs plus 6000 around the mirror direction.
_RANDOM = data_synth.uniform_random(6000, seed=1)
_SPECULAR = data_synth.near_specular(8, 6000, spread=25.0, seed=2)
WI = np.vstack([_RANDOM[0], _SPECULAR[0]])
WO = np.vstack([_RANDOM[1], _SPECULAR[1]])


def noiseless(model, options, params):
    return data_synth.synthesize(model, params, WI, WO, **options)


def sorted_lobes(params):
    """Lafortune lobes have no natural order; compare them sorted by cxy."""
    if "lobes" in params:
        params = params | {"lobes": sorted(params["lobes"], key=lambda lobe: lobe["cxy"])}
    return params


def assert_recovered(result, truth, rtol):
    fitted, expected = flat_parameters(sorted_lobes(result.params)), flat_parameters(sorted_lobes(truth))
    assert list(fitted) == list(expected)
    for name, value in expected.items():
        # Published direction components are rounded; the model rescales (cxy, cz) onto 2cxy² + cz² = 1.
        tolerance = max(rtol, 2e-3) if name.endswith(("cxy", "cz")) else rtol
        assert fitted[name] == pytest.approx(value, rel=tolerance, abs=1e-12), (name, fitted[name], value)


def departed_holds(model, options, params) -> dict:
    """The model's default holds (``LobeModel.held``) that the truth departs from, freed: the fit is asked for every
    parameter the data were made with."""
    held = dict(getattr(get_model(model, **options), "held", ()))
    return {name: None for name, value in held.items() if not np.allclose(params[name], value)}


@parametrize_cases()
def test_recovers_noiseless_data_from_the_default_start(model, options, params):
    """Noise-free data: the optimum is the truth, so the fit must land on it (to 1e-5, far inside
    the tolerances the solver stops at) from the data-driven start."""
    fixed = departed_holds(model, options, params)
    if model == "gltf" and params["clearcoat"] == 0:  # no coat: its roughness is any; held, as one who knows holds it
        fixed |= {"clearcoat": 0.0, "clearcoat_roughness": 0.0}
    result = fit(noiseless(model, options, params), model, fixed=fixed, **options)
    assert result.converged, result.message
    # A truth on an end of [0, 1] (glTF's metallic 0) is reached only in the limit of the solver's logistic map:
    # the solve stops within ~1e-8 of it (its slope there is ~1e-8), a cost of ~1e-12 on these values of ~1.
    on_an_end = any(value in (0.0, 1.0) for name, value in params.items() if name == "metallic")
    assert result.cost < (1e-11 if on_an_end else 1e-16)
    assert_recovered(result, params, rtol=1e-5)


@pytest.mark.parametrize("loss", ["log", "l2", "cosine", "cbrt", "relative"])
def test_every_loss_finds_the_optimum(loss):
    model, options, params = CASES[4]  # cook-torrance, Schlick
    result = fit(noiseless(model, options, params), model, loss, **options)
    assert result.converged and result.loss == loss
    assert_recovered(result, params, rtol=1e-5)


def test_sigma_and_weight_keep_the_noiseless_optimum(rng):
    model, options, params = CASES[1]
    clean = noiseless(model, options, params)
    weighted = Samples.from_arrays(
        clean.wi, clean.wo, clean.values, clean.channels, sigma=0.01 * clean.values, weight=rng.random(clean.n_samples)
    )
    assert_recovered(fit(weighted, model), params, rtol=1e-5)


def test_sigma_gives_a_chi_squared_cost():
    """With the true sigma, the cost at the optimum is χ² with N·C - k degrees of freedom:
    mean N·C - k, standard deviation sqrt(2(N·C - k)); a 5σ band."""
    model, _, params = CASES[1]
    noisy = data_synth.synthesize(model, params, WI, WO, noise=0.01, seed=5, with_sigma=True)
    result = fit(noisy, model, "l2")
    dof = noisy.values.size - 7
    assert abs(result.cost - dof) < 5 * np.sqrt(2 * dof)


def test_lambert_l2_is_the_mean():
    """For Lambert and the l2 loss the optimum is rho_d = π·mean(y) per channel, exactly."""
    samples = data_synth.synthesize("lambert", {"rho_d": [0.2, 0.4]}, WI, WO, noise=0.05, seed=9)
    result = fit(samples, "lambert", "l2")
    np.testing.assert_allclose(result.params["rho_d"], np.pi * samples.values.mean(axis=0), rtol=1e-10)


def test_max_theta_drops_samples():
    model, options, params = CASES[1]
    samples = noiseless(model, options, params)
    result = fit(samples, model, max_theta=60.0)
    kept = np.sum((samples.theta_i <= 60) & (samples.theta_o <= 60))
    assert result.n_samples == kept < samples.n_samples


def test_start_is_used_and_checked():
    model, options, params = CASES[1]
    samples = noiseless(model, options, params)
    result = fit(samples, model, start=params, n_starts=1)
    assert result.n_steps <= 3 and result.converged
    with pytest.raises(BrdfInputError, match="start parameters have 1 channel"):
        fit(samples, model, start={"rho_d": [0.1], "rho_s": [0.1], "alpha": 0.1})


def test_a_bad_start_is_said_before_any_work_starts(monkeypatch):
    """A start that does not fit the model is checked before the fit sets to work (its reciprocity check, its
    programs' compilation): nothing is left running behind the error."""
    from brdffit.fitting.single import stacked

    model, options, params = CASES[1]
    monkeypatch.setattr(stacked, "ReciprocityAhead", lambda samples: pytest.fail("the check started"))
    with pytest.raises(BrdfInputError, match="start parameters have 1 channel"):
        fit(noiseless(model, options, params), model, start={"rho_d": [0.1], "rho_s": [0.1], "alpha": 0.1})


@pytest.mark.parametrize("given", [True, False])
def test_the_screens_compile_once_the_solve_is_lowered_from_a_given_start_else_before_the_search(given, monkeypatch):
    """The caveats' screen program compiles in the background (``stacked.compile_in_background``): a single fit from a
    given start starts it once its solve is lowered, so that its tracing runs beside the solve's compilation and not
    beside the solve's own tracing (``StackedFit._compile_screens``); a fit from grid starts, before its search. The
    result is the same. A step budget of its own gives the fit a solve not compiled before in this process."""
    import threading

    import jax

    from brdffit._programs import cache
    from brdffit.fitting.single import stacked

    monkeypatch.setattr(cache, "_enabled", None)
    events, ours = [], {threading.get_ident()}  # this fit's threads: the main one and those it starts
    lower, start = jax.stages.Traced.lower, stacked.compile_in_background

    def lowered(self, *args, **kwargs):
        program = lower(self, *args, **kwargs)
        events.append(("lowered", self.fun_name, threading.get_ident()))
        return program

    def started(program, *arguments):
        events.append(("started", program.__name__, threading.get_ident()))
        thread = start(program, *arguments)
        ours.add(thread.ident)
        return thread

    monkeypatch.setattr(jax.stages.Traced, "lower", lowered)
    monkeypatch.setattr(stacked, "compile_in_background", started)
    model, options, params = CASES[1]
    samples = noiseless(model, options, params)
    result = fit(samples, model, start=params if given else None, n_starts=1, max_steps=91 + given)
    said = [(event, name) for event, name, thread in events if thread in ours]  # not a thread an earlier test left
    screens, solve = said.index(("started", "_bucket_screens")), said.index(("lowered", "solve"))
    assert (screens > solve) == given
    assert result.converged and result.warnings == []


def test_not_converged_is_reported():
    model, options, params = CASES[4]
    result = fit(noiseless(model, options, params), model, max_steps=2, **options)
    assert result.converged is False and "maximum number of solver steps" in result.message


def test_fits_are_deterministic():
    model, options, params = CASES[10]
    samples = data_synth.synthesize(model, params, WI, WO, noise=0.01, seed=4, **options)
    assert fit(samples, model, **options) == fit(samples, model, **options)


def test_result_round_trip_and_predict(tmp_path):
    model, options, params = CASES[11]  # two Lafortune lobes
    result = fit(noiseless(model, options, params), model, **options)
    result.save(tmp_path / "r.json")
    again = load_result(tmp_path / "r.json")
    assert again == result
    np.testing.assert_array_equal(
        result.predict(WI[:10], WO[:10]), evaluate(model, result.params, WI[:10], WO[:10], **options)
    )
    content = json.loads((tmp_path / "r.json").read_text())
    assert content["model_options"] == {"lobes": 2} and list(content["params"]) == ["rho_d", "lobes"]
    assert list(content["params"]["lobes"][0]) == ["rho_s", "cxy", "cz", "n"]
    assert "lobe 2 cxy" in result.table()


@pytest.mark.parametrize(("model", "loss"), [("ward", "log"), ("lambert", "cbrt"), ("cook-torrance", "relative")])
def test_all_zero_data_fits_zero_albedos_and_converges(model, loss):
    """A black sample: the optimum is on the boundary with cost 0; every loss must get there and stop (and say that
    the lobe fits nothing)."""
    wi, wo = data_synth.uniform_random(50, seed=0)
    lobe = pytest.warns(FitWarning, match="the specular lobe .* contributes less than 0.1% of the model")
    with lobe if model != "lambert" else contextlib.nullcontext():
        result = fit(Samples.from_arrays(wi, wo, np.zeros(50)), model, loss)
    assert result.converged and result.n_steps < 50 and result.rmse < 1e-6


def test_too_few_values_for_the_parameters():
    wi, wo = data_synth.uniform_random(2, seed=0)
    with pytest.raises(
        BrdfInputError, match=r"2 sample\(s\) × 1 channel\(s\) cannot determine the 3 parameters of ward"
    ):
        fit(Samples.from_arrays(wi, wo, [0.1, 0.2]), "ward")


def test_bad_calls():
    samples = noiseless(*CASES[0])
    with pytest.raises(BrdfInputError, match="fit takes Samples"):
        fit(12, "ward")
    with pytest.raises(BrdfInputError, match=r"^nowhere/samples.csv: no such file$"):
        fit("nowhere/samples.csv", "ward")  # a path is read with load_samples
    with pytest.raises(BrdfInputError, match="'wrd' is not a model"):
        fit(samples, "wrd")
    with pytest.raises(BrdfInputError, match=r"^max_steps=0 is not allowed"):
        fit(samples, "ward", max_steps=0)
    with pytest.raises(BrdfInputError, match="not a brdffit result file"):
        FitResult.from_dict({"model": "ward"})


def test_float32_is_refined_to_the_float64_optimum():
    """float32 solves, then float64 refines: the optimum is float64's (to its tolerances, ~1e-8 relative)."""
    model, options, params = CASES[4]
    samples = data_synth.synthesize(model, params, WI, WO, noise=0.01, seed=6, **options)
    double = fit(samples, model, **options)
    single = fit(samples, model, dtype="float32", **options)
    assert single.converged and single.dtype == "float32" and double.dtype == "float64"
    fitted, expected = flat_parameters(single.params), flat_parameters(double.params)
    for name, value in expected.items():
        assert fitted[name] == pytest.approx(value, rel=1e-8), name
    assert "float32, refined in float64" in single.table()


def test_large_data_searches_starts_on_a_subsample(monkeypatch):
    """Above SEARCH_SAMPLES the starts are searched on a seeded subsample and the winner refined on all:
    the optimum is the same as searching on everything."""
    starts_module = sys.modules["brdffit.fitting.starts.grid"]
    model, options, params = CASES[1]
    samples = data_synth.synthesize(model, params, WI, WO, noise=0.01, seed=8, **options)
    everything = fit(samples, model)
    monkeypatch.setattr(starts_module, "SEARCH_SAMPLES", 2000)
    subsampled = fit(samples, model, seed=1)
    assert subsampled.converged and subsampled.cost == pytest.approx(everything.cost, rel=1e-10)
    fitted, expected = flat_parameters(subsampled.params), flat_parameters(everything.params)
    for name, value in expected.items():
        assert fitted[name] == pytest.approx(value, rel=1e-6), name


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_rmse_is_that_of_the_returned_parameters(dtype):
    """``rmse`` comes from the solver's last accepted pass, not a separate evaluation: it must equal
    sqrt(mean((f - y)²)) at the reported parameters over the real samples only (5000 samples pad to 5120 rows).
    rtol 1e-9: the same sums in another order and the parameters printed to 17 digits."""
    wi, wo = data_synth.uniform_random(5000, seed=4)
    model, _, params = CASES[1]
    samples = data_synth.synthesize(model, params, wi, wo, noise=0.05, seed=5)
    result = fit(samples, model, dtype=dtype)
    error = evaluate(model, result.params, wi, wo) - samples.values
    assert result.rmse == pytest.approx(float(np.sqrt(np.mean(error**2))), rel=1e-9)


def test_starts_that_reach_one_optimum_tie_and_the_first_wins():
    """Costs equal to within rounding (SAME_COST, relative 1e-12) are one optimum: the earlier, better-ranked start
    wins, so the reported step count does not depend on how a sum was rounded; a real improvement still wins."""
    from types import SimpleNamespace

    from brdffit.fitting.solver.compiled import best

    runs = [SimpleNamespace(cost=c, name=i) for i, c in enumerate([3.2728725253445340e-03, 3.2728725253445335e-03])]
    assert best(runs).name == 0
    runs = [SimpleNamespace(cost=c, name=i) for i, c in enumerate([3.27287252534e-03, 3.27287252530e-03, 1.0])]
    assert best(runs).name == 1


def test_a_path_is_fitted_as_load_samples_reads_it():
    from paths import EXAMPLE

    assert fit(EXAMPLE, "lambert").to_dict() == fit(load_samples(EXAMPLE), "lambert").to_dict()
    assert repr(load_samples(EXAMPLE)) == f"Samples(10368 × 3 channel(s) [r, g, b] from {EXAMPLE})"


def test_residuals_of_a_result_sum_to_its_cost_with_sigma_and_weight():
    """Σ r² of ``FitResult.residuals`` is the reported cost (both float64 sums of the same 3·10³ squares, in
    different orders: equal to ~1e-13 relative, 1e-10 allowed); samples of other channels are refused."""
    truth = CASES[1]
    samples = noiseless(*truth)
    rng = np.random.default_rng(5)
    samples = Samples.from_arrays(
        samples.wi[:1000],
        samples.wo[:1000],
        samples.values[:1000] * (1 + 0.02 * rng.standard_normal((1000, 3))),
        channels=samples.channels,
        sigma=0.02 * samples.values[:1000] + 1e-4,
        weight=rng.uniform(0.5, 2.0, 1000),
    )
    result = fit(samples, "ward", "cbrt")
    residuals = result.residuals(samples)
    assert residuals.shape == (1000, 3)
    assert np.sum(residuals**2) == pytest.approx(result.cost, rel=1e-10)
    grey = Samples.from_arrays(samples.wi, samples.wo, samples.values[:, :1])
    with pytest.raises(BrdfInputError, match="channels value are not the result's"):
        result.residuals(grey)


@pytest.mark.slow
def test_an_anisotropic_fit_reports_the_twin_with_the_smoother_tangent_unless_a_hold_names_the_other():
    """(αu, αv, φt) and (αv, αu, φt ± 90°) are one lobe: a fit reports alpha_u ≤ alpha_v (the tangent along the
    smoother direction, in (−90, 90]), whichever twin made the data; a user who fixes alpha_u keeps their naming.
    Noiseless data: the truth to 1e-5, as every catalogued model."""
    options = {"fresnel": "none", "distribution": "ggx", "shadowing": "smith", "anisotropic": True}
    made = {"kd": [0.1, 0.1, 0.1], "ks": [0.6, 0.5, 0.4], "alpha_u": 0.3, "alpha_v": 0.08, "phi_t": -60.0}
    samples = noiseless("cook-torrance", options, made)
    result = fit(samples, "cook-torrance", **options)
    assert_recovered(result, made | {"alpha_u": 0.08, "alpha_v": 0.3, "phi_t": 30.0}, rtol=1e-5)
    held = fit(samples, "cook-torrance", fixed={"alpha_u": 0.3}, **options)
    assert_recovered(held, made, rtol=1e-5)


@pytest.mark.parametrize("fresnel", ["schlick", "dielectric", "conductor", "none"])
@pytest.mark.parametrize("anisotropic", [False, True])
def test_no_grid_start_of_cook_torrance_reflects_nothing(fresnel, anisotropic):
    """A start whose Fresnel term is 0 at every angle (a conductor's eta = 1, k = 0) is a dead lobe no derivative
    moves; it won the grid's race on the pickled oak (below). Every start reflects at normal incidence."""
    from brdffit import get_model
    from brdffit.physics.fresnel import FRESNEL

    lobe = get_model("cook-torrance", fresnel=fresnel, anisotropic=anisotropic).lobe
    reflectance = FRESNEL[fresnel].reflectance
    assert lobe.grid and all(float(reflectance(np.float64(1.0), shape)) > 0.0 for shape in lobe.grid)
    for shape in lobe.grid:  # the closed form the grid uses is the reflectance at normal incidence (rounding)
        at_normal = float(np.asarray(FRESNEL[fresnel].at_normal(shape)))
        assert at_normal == pytest.approx(float(reflectance(np.float64(1.0), shape)), rel=1e-12, abs=1e-15)


def test_a_conductor_fit_of_a_non_metal_does_not_start_from_a_dead_lobe():
    """The pickled oak (no metal) with a conductor's ks held at 1: the default fit ended at eta = 1, k = 0 with its
    lobe dead (cost 8.717, Lambert's); starts at k = 1e-3 reach 8.547. Within 0.5% of it (the fit ends at 8.563:
    a channel started below eta = 1 does not cross F's zero there), and no lobe is dead."""
    from paths import EXAMPLE

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # k on its end is said; the result's warnings are checked
        result = fit(load_samples(EXAMPLE), "cook-torrance", fresnel="conductor")
    assert result.cost <= 1.005 * 8.5466
    assert not any("contributes less than" in line for line in result.warnings)
