"""Conductors with a complex index per channel (``Lobe.channel_names``): the per-channel basis of the normal equations,
the start search's measured metals, the default hold of ``ks``, the parameter dictionary and its errors.

Mitsuba's own metals, fitted and exported back, are in ``tests/export/test_mitsuba_metals.py``.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import random_directions
from test_holding import quiet_fit

import brdffit
from brdffit import BrdfInputError, data_synth, get_model
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.objective.problem import build_problem, normal_equations, residuals
from brdffit.fitting.single.constraints import constraints_for
from brdffit.physics.metals import BANDS_NM, METALS, metal_grid, metal_index

OPTIONS = {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"}
#: Copper-like (Mitsuba's Cu rounded): an index that differs in every channel.
COPPER = {"kd": [0.02, 0.01, 0.01], "ks": [1.0, 1.0, 1.0], "m": 0.2, "eta": [0.2, 0.92, 1.1], "k": [3.9, 2.45, 2.14]}


@pytest.fixture(scope="module")
def copper():
    """1% noise on a 6 × 18 × 18 hemisphere grid."""
    wi, wo = data_synth.hemisphere_grid(6, 18, 18)
    return data_synth.synthesize("cook-torrance", COPPER, wi, wo, noise=0.01, seed=4, **OPTIONS)


@pytest.mark.slow
@pytest.mark.parametrize("loss", ["log", "l2"])
def test_normal_equations_equal_the_dense_ones(copper, loss):
    """JᵀJ, Jᵀr and rᵀr accumulated over the per-channel basis equal those of the dense Jacobian (jax.jacfwd of the
    residuals) to rounding: the same sums in another order (1e-12 relative)."""
    model, loss = get_model("cook-torrance", **OPTIONS), get_loss(loss)
    problem = build_problem(copper)
    theta = jnp.asarray(model.unconstrained.from_params(model.dictionary.to_params(COPPER))) + 0.05
    sums = normal_equations(model, loss, theta, problem)
    r = lambda t: residuals(model, loss, t, problem).ravel()
    jacobian, values = jax.jacfwd(r)(theta), r(theta)
    gram, gradient = jacobian.T @ jacobian, jacobian.T @ values
    np.testing.assert_allclose(sums.gram, gram, rtol=1e-12, atol=1e-12 * float(jnp.max(jnp.abs(gram))))
    np.testing.assert_allclose(sums.gradient, gradient, rtol=1e-12, atol=1e-12 * float(jnp.max(jnp.abs(gradient))))
    assert float(sums.cost) == pytest.approx(float(values @ values), rel=1e-12)


def test_equal_channels_are_the_one_channel_conductor(rng):
    """A per-channel index equal in every channel is the scalar conductor: each channel's BRDF equals the one-channel
    model's (the one-channel layout is the old scalar one), to rounding."""
    model = get_model("cook-torrance", **OPTIONS)
    wi, wo = random_directions(rng, 200), random_directions(rng, 200)
    three = {"kd": [0.1, 0.1, 0.1], "ks": [0.8, 0.8, 0.8], "m": 0.3, "eta": [0.4, 0.4, 0.4], "k": [2.5, 2.5, 2.5]}
    one = {"kd": [0.1], "ks": [0.8], "m": 0.3, "eta": 0.4, "k": 2.5}
    values = brdffit.evaluate(model, three, wi, wo)
    np.testing.assert_allclose(values, np.repeat(brdffit.evaluate(model, one, wi, wo), 3, axis=1), rtol=1e-14)


@pytest.mark.slow
def test_a_fit_of_equal_channels_is_the_one_channel_fit():
    """Three identical channels fit as one: the same roughness and index in every channel (both fits converge to
    the same optimum; 1e-6 relative is the solver's stopping tolerance), three times the cost."""
    wi, wo = data_synth.hemisphere_grid(6, 12, 12)
    truth = {"kd": [0.02], "ks": [1.0], "m": 0.2, "eta": 0.9, "k": 2.4}
    one = data_synth.synthesize("cook-torrance", truth, wi, wo, noise=0.01, seed=2, **OPTIONS)
    three = brdffit.Samples.from_arrays(one.wi, one.wo, np.repeat(one.values, 3, axis=1), channels=("r", "g", "b"))
    fitted_one = quiet_fit(one, "cook-torrance", **OPTIONS)
    fitted_three = quiet_fit(three, "cook-torrance", **OPTIONS)
    assert fitted_three.params["m"] == pytest.approx(fitted_one.params["m"], rel=1e-6)
    for name in ("eta", "k"):
        np.testing.assert_allclose(fitted_three.params[name], fitted_one.params[name] * 3, rtol=1e-5)
    assert fitted_three.cost == pytest.approx(3 * fitted_one.cost, rel=1e-6)


def test_the_fit_recovers_an_index_per_channel(copper):
    """1% noise: the roughness within 1%, each channel's k within 5% and eta within 10% (where k ≫ eta, as in
    copper's red, the reflectance ((eta-1)² + k²)/((eta+1)² + k²) hardly depends on eta: measured 8% off there, 3%
    elsewhere), ks held at 1 by default and recorded as held."""
    result = quiet_fit(copper, "cook-torrance", **OPTIONS)
    assert result.params["m"] == pytest.approx(COPPER["m"], rel=0.01)
    np.testing.assert_allclose(result.params["eta"], COPPER["eta"], rtol=0.10)
    np.testing.assert_allclose(result.params["k"], COPPER["k"], rtol=0.05)
    assert result.params["ks"] == [1.0, 1.0, 1.0] and result.fixed == {"ks": [1.0, 1.0, 1.0]}


def test_ks_is_freed_fixed_or_bounded_by_the_user(copper):
    model = get_model("cook-torrance", **OPTIONS)
    assert constraints_for(model, 3).fixed == {"ks": [1.0, 1.0, 1.0]}
    assert constraints_for(model, 3, {"ks": None}) is None  # freed: nothing held
    assert constraints_for(model, 3, {"ks": 0.9}).fixed == {"ks": [0.9, 0.9, 0.9]}
    assert constraints_for(model, 3, bounds={"ks": (0.5, 1.0)}).fixed == {}
    assert constraints_for(model, 3, {"ks": None, "kd": 0}).fixed == {"kd": [0.0, 0.0, 0.0]}
    assert constraints_for(get_model("cook-torrance"), 3, {"ks": None}) is None  # free anyway: nothing
    assert constraints_for(model, 3, {"ks": [1.0, 1.0, 1.0]}, defaults=False).fixed == {"ks": [1.0, 1.0, 1.0]}
    freed = quiet_fit(copper, "cook-torrance", fixed={"ks": None}, **OPTIONS)
    assert freed.fixed == {} and freed.params["ks"] != [1.0, 1.0, 1.0]


def test_eta_is_fixed_as_one_number_or_a_list(copper):
    listed = quiet_fit(copper, "cook-torrance", fixed={"eta": COPPER["eta"]}, **OPTIONS)
    assert listed.params["eta"] == COPPER["eta"] and listed.fixed["eta"] == COPPER["eta"]
    assert listed.params["m"] == pytest.approx(COPPER["m"], rel=0.01)
    one = quiet_fit(copper, "cook-torrance", fixed={"eta": 0.5}, bounds={"k": (2.0, 5.0)}, **OPTIONS)
    assert one.params["eta"] == [0.5, 0.5, 0.5]
    assert all(2.0 <= k <= 5.0 for k in one.params["k"])


@pytest.mark.parametrize(
    ("fixed", "message"),
    [
        ({"eta": [0.2, 0.9]}, "eta has 2 values but the samples have 3 channel(s)"),
        ({"k": -1.0}, "k = -1.0 is outside its domain ≥ 0"),
        ({"ks": "one"}, "ks takes numbers"),
        ({"kz": None}, "has no parameter 'kz'"),
    ],
)
def test_bad_holds_of_a_conductor_are_one_line_errors(fixed, message):
    with pytest.raises(BrdfInputError, match=message.replace("(", r"\(").replace(")", r"\)")) as error:
        constraints_for(get_model("cook-torrance", **OPTIONS), 3, fixed)
    assert "\n" not in str(error.value)


def test_the_dictionary_writes_lists_and_reads_one_number_for_every_channel():
    model = get_model("cook-torrance", **OPTIONS)
    params = model.dictionary.to_params(COPPER)
    assert params.shape["eta"].shape == (1, 3) and params.shape["m"].shape == (1,)
    assert model.dictionary.from_params(params) == {name: COPPER[name] for name in model.dictionary.names}
    old = model.dictionary.to_params(COPPER | {"eta": 0.5, "k": 3})  # a result file written before the lists
    np.testing.assert_array_equal(old.shape["eta"], [[0.5, 0.5, 0.5]])
    labels = model.physical.labels(("r", "g", "b"))
    assert labels[-7:] == ["m", "eta[r]", "eta[g]", "eta[b]", "k[r]", "k[g]", "k[b]"]
    vector = model.unconstrained.from_params(params)
    np.testing.assert_allclose(model.dictionary.from_params(model.unconstrained.to_params(vector, 3))["k"], COPPER["k"])


@pytest.mark.parametrize(
    ("values", "message"),
    [
        (
            {"eta": [0.2, 0.9]},
            r"cook-torrance: eta takes one number per channel \(3\) or one for all, got \[0.2, 0.9\]",
        ),
        ({"k": [1.0, "x", 2.0]}, "cook-torrance: k takes one number per channel"),
        ({"eta": [0.2, -0.9, 1.0]}, "cook-torrance: eta = .* is outside its domain > 0"),
    ],
)
def test_a_wrong_index_in_the_dictionary_is_a_one_line_error(values, message):
    with pytest.raises(BrdfInputError, match=message) as error:
        get_model("cook-torrance", **OPTIONS).dictionary.to_params(COPPER | values)
    assert "\n" not in str(error.value)


def test_a_k_on_its_lower_end_is_warned_about():
    """A k of 1e-12 (the fit's floor, where a start of k = 0 stays) is said, as every end of a domain is."""
    from brdffit.fitting.single.caveats import _implausible

    model = get_model("cook-torrance", **OPTIONS)
    params = model.dictionary.to_params(COPPER | {"k": [1e-12, 2.45, 2.14]})
    found = _implausible(model, params, ("r", "g", "b"))
    assert found == [
        "k[r] = 1e-12 lies on an end of its domain ≥ 0: the fit ended against the bound, where the model may not"
        " describe the data"
    ]
    assert _implausible(model, model.dictionary.to_params(COPPER | {"kd": [0, 0, 0]}), ("r", "g", "b")) == []


def test_measured_metals_in_the_datas_channels():
    """RGB channels in any order take Mitsuba's RGB values; wavelengths the tables interpolated (gold at 550 nm:
    Au.eta.spd and Au.k.spd give 0.3455 and 2.7306 at 551.04 nm; the 10 nm resampling and 1 nm move them by less
    than 0.03: k rises 0.015 per nm there); other names none."""
    gold = METALS["Au"]
    eta, k = metal_index(gold, ("b", "g", "r"))
    np.testing.assert_array_equal(eta, gold.eta_rgb[::-1])
    np.testing.assert_array_equal(k, gold.k_rgb[::-1])
    eta, k = metal_index(gold, ("450", "550nm", "650 nm"))
    assert eta[1] == pytest.approx(0.3455, abs=0.03) and k[1] == pytest.approx(2.7306, abs=0.03)
    assert eta[0] > 1.0 > eta[1] and k[0] < k[1] < k[2]  # gold absorbs blue, reflects red
    assert metal_grid(("x", "y", "z")) == () and metal_grid(("value",)) == ()
    assert len(metal_grid(("r", "g", "b"))) == len(METALS) >= 10


def _linear_srgb(values) -> np.ndarray:
    """Spectral samples at BANDS_NM to linear sRGB as Mitsuba converts its tables on loading: interpolated to every
    1 nm, weighted by the CIE 1931 2° colour-matching functions, divided by ∫ ȳ, times the XYZ → sRGB matrix."""
    colour = pytest.importorskip("colour", reason="colour-science gives the colour-matching functions")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    xyz_to_srgb = [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]]
    on_every_nm = np.interp(np.arange(360.0, 831.0), BANDS_NM, values)
    return np.asarray(xyz_to_srgb) @ ((on_every_nm[:, None] * cmfs.values).sum(axis=0) / cmfs.values[:, 1].sum())


def test_titanium_and_iron_are_johnson_and_christys_in_mitsubas_rgb():
    """Ti and Fe (Johnson & Christy 1974, which Mitsuba lacks): their RGB is the conversion that gives Mitsuba's own
    RGB of its eight metals within 0.002 (measured: 0.0012 at most, Cr's blue eta; Cu's red eta 0.5% off); their
    bands the table's
    (Fe at 549 nm: n 2.95, k 2.93; Ti at 582 nm: 2.60, 3.58; linear between the table's points and again between the
    bands: within 0.01)."""
    for symbol, metal in METALS.items():
        rgb = np.concatenate([_linear_srgb(metal.eta), _linear_srgb(metal.k)])
        expected = np.concatenate([metal.eta_rgb, metal.k_rgb])
        tolerance = 1e-6 if symbol in ("Ti", "Fe") else 2e-3  # ours rounded to 6 digits; Mitsuba's its own way
        np.testing.assert_allclose(rgb, expected, rtol=tolerance, atol=tolerance, err_msg=symbol)
    iron, titanium = metal_index(METALS["Fe"], ("549",)), metal_index(METALS["Ti"], ("582",))
    np.testing.assert_allclose(np.ravel(iron), [2.95, 2.93], atol=0.01)
    np.testing.assert_allclose(np.ravel(titanium), [2.60, 3.58], atol=0.01)


def test_the_start_search_tries_the_measured_metals():
    """Gold's own index is among the grid starts on RGB data; the best start on exact gold data is gold itself."""
    from brdffit.fitting.starts.grid import grid_channels, starting_points

    model = get_model("cook-torrance", **OPTIONS)
    gold = METALS["Au"]
    truth = {"kd": [0.0, 0.0, 0.0], "ks": [1.0] * 3, "m": 0.15, "eta": list(gold.eta_rgb), "k": list(gold.k_rgb)}
    wi, wo = data_synth.hemisphere_grid(6, 12, 12)
    samples = data_synth.synthesize("cook-torrance", truth, wi, wo, **OPTIONS)
    hold = constraints_for(model, 3).hold()
    assert grid_channels(model, samples.channels) == ("r", "g", "b")
    assert grid_channels(get_model("ward"), samples.channels) is None
    (best,) = starting_points(model, get_loss("log"), build_problem(samples), 1, hold, samples.channels)
    start = model.dictionary.from_params(model.unconstrained.to_params(np.asarray(best), 3))
    np.testing.assert_allclose(start["eta"], gold.eta_rgb, rtol=1e-9)
    assert start["m"] == pytest.approx(0.15, rel=1e-9) and start["ks"] == pytest.approx([1.0] * 3, rel=1e-12)
