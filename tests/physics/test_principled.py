"""Mitsuba 3's ``principled`` in JAX (``brdffit/physics/renderers/principled.py``) against Mitsuba 3 itself, its
reciprocity, the channels it takes, finite values and derivatives at grazing angles and the parameters' bounds, and
its derivatives against central finite differences.

Tolerance against Mitsuba. Both sides see the same directions, rounded to float32 (as ``mi.Vector3f`` takes them),
so what differs is Mitsuba's float32 arithmetic (ε = 2⁻²⁴ ≈ 6e-8 per operation) against float64: some fifty
operations from the directions to the value, each within ε, bound the relative error by ~50 ε ≈ 3e-6; the tests
allow 1e-5 (measured: at most 1.5e-6 over these cases). One term loses more: the clearcoat's GTR1 denominator
``1 + (α² − 1) ch²`` cancels to ``α²`` (1.2e-4 at ``clearcoat_gloss = 0.9``) at the half vector's normal, where
Mitsuba's ``ch²`` (within ~4 ε, after the normalisation of ``wi + wo`` and the square) and the product and sum
(2 ε more) err by up to ~6 ε absolutely: the coat's relative error is ``6 ε / (1 + (α² − 1) ch²)``, up to 3e-3 at
the peak. Each value is held to ``1e-5 |f| + 8 ε · coat / (1 + (α² − 1) ch²)`` (measured: 1.4e-3 relative at a
coat's peak). The GGX terms have no such cancellation (``h_x²/α² + h_y²/α² + ch²`` sums positive terms; near the
mirror ``wi + wo`` subtracts nearly equal components exactly), so roughness 0.05 holds 1e-5 too.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import directions_from_degrees, random_directions

from brdffit import BrdfInputError
from brdffit.physics.renderers.principled import CLEARCOAT_ALPHA_RANGE, DEFAULTS, PARAMETERS, principled_brdf

#: float32's unit roundoff, Mitsuba scalar_rgb's arithmetic.
EPS32 = 2.0**-24
#: The relative tolerance against Mitsuba (module docstring).
RTOL = 1e-5

#: Parameter sets (brdffit's spelling) compared with Mitsuba.
CASES = {
    "defaults": {},
    "metal": {"base_color": [0.95, 0.64, 0.54], "metallic": 1.0, "roughness": 0.3},
    "clearcoat": {"base_color": [0.2, 0.3, 0.6], "roughness": 0.5, "clearcoat": 1.0, "clearcoat_gloss": 0.9},
    "sheen": {"base_color": [0.7, 0.2, 0.1], "roughness": 0.6, "sheen": 1.0, "sheen_tint": 0.6},
    "anisotropic": {"base_color": [0.5, 0.5, 0.2], "roughness": 0.4, "anisotropic": 0.8, "metallic": 0.5},
    "spec_tint": {"base_color": [0.1, 0.6, 0.3], "roughness": 0.2, "specular": 0.8, "spec_tint": 0.7},
    "low-roughness": {"base_color": [0.3, 0.3, 0.3], "roughness": 0.05, "metallic": 0.2},
    # every lobe at once, off the defaults
    "mixed": {
        "base_color": [0.8, 0.5, 0.05],
        "roughness": 0.35,
        "metallic": 0.3,
        "specular": 0.3,
        "spec_tint": 0.4,
        "anisotropic": 0.5,
        "sheen": 0.7,
        "sheen_tint": 1.0,
        "clearcoat": 0.5,
        "clearcoat_gloss": 0.3,
    },
    # specular = 0: η = 1, Mitsuba drops the whole specular lobe, the metal's too, so a pure metal is black
    "specular-0-metal": {"base_color": [0.9, 0.6, 0.3], "metallic": 1.0, "roughness": 0.3, "specular": 0.0},
}


def _plugin(params: dict) -> dict:
    """The Mitsuba plugin dictionary of ``params``: only the parameters given, Mitsuba's defaults for the rest."""
    plugin = {"type": "principled"}
    for name, value in params.items():
        plugin[name] = {"type": "rgb", "value": list(value)} if name == "base_color" else float(value)
    return plugin


def _jax_params(params: dict, dtype=jnp.float64) -> dict:
    """Every parameter (:data:`DEFAULTS` where ``params`` names none) as a JAX array of ``dtype``: one structure,
    so that one compiled program serves every case."""
    return {name: jnp.asarray(value, dtype) for name, value in (DEFAULTS | params).items()}


_compiled_brdf = jax.jit(principled_brdf)


def _brdf(params: dict, wi, wo) -> np.ndarray:
    """The function's values (float64) at ``params``, compiled once per shape."""
    return np.asarray(_compiled_brdf(_jax_params(params), jnp.asarray(wi), jnp.asarray(wo)))


def _pairs(seed: int, n_random: int = 300, n_mirror: int = 100):
    """``n_random`` pairs uniform in solid angle up to 89° and ``n_mirror`` pairs within ~0.05–2° of the mirror
    direction (up to 89°), rounded to float32 as Mitsuba takes them."""
    rng = np.random.default_rng(seed)
    min_cos = np.cos(np.radians(89.0))
    wi = random_directions(rng, n_random + n_mirror, min_cos)
    wo = random_directions(rng, n_random + n_mirror, min_cos)
    mirror = wi[n_random:] * np.array([-1.0, -1.0, 1.0])
    mirror += rng.normal(scale=np.radians(1.0), size=mirror.shape) * rng.choice([0.05, 1.0, 2.0], (n_mirror, 1))
    mirror[:, 2] = np.maximum(mirror[:, 2], min_cos)
    wo[n_random:] = mirror / np.linalg.norm(mirror, axis=1, keepdims=True)
    return wi.astype(np.float32).astype(float), wo.astype(np.float32).astype(float)


def _tolerance(params: dict, wi, wo, expected):
    """``1e-5 |f| + 8 ε · coat / (1 + (α² − 1) ch²)`` (N, C): float32's rounding, and that of Mitsuba's GTR1
    denominator carried by the clearcoat lobe (the function's value less its value without the coat)."""
    tolerance = RTOL * np.abs(expected)
    if not params.get("clearcoat", 0.0):
        return tolerance
    coat = _brdf(params, wi, wo) - _brdf(params | {"clearcoat": 0.0}, wi, wo)
    low, high = CLEARCOAT_ALPHA_RANGE
    alpha2 = (low + params.get("clearcoat_gloss", 0.0) * (high - low)) ** 2
    h = wi + wo
    cos2_h = h[:, 2] ** 2 / np.sum(h * h, axis=1)
    return tolerance + 8 * EPS32 * coat / (1.0 + (alpha2 - 1.0) * cos2_h)[:, None]


def _assert_equals_mitsuba(mitsuba_brdf, params: dict, seed: int):
    wi, wo = _pairs(seed)
    expected = mitsuba_brdf(_plugin(params), wi, wo)
    got = _brdf(params, wi, wo)
    excess = np.abs(got - expected) - _tolerance(params, wi, wo, expected)
    worst = np.unravel_index(np.argmax(excess), got.shape)
    assert np.all(excess <= 0.0), f"{params}, pair {worst}: {got[worst]} vs Mitsuba {expected[worst]}"
    return expected


@pytest.fixture(scope="module")
def mitsuba_brdf():
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install 'brdffit[render]')")
    from brdffit.export.mitsuba_eval import mitsuba_brdf

    return mitsuba_brdf


@pytest.mark.parametrize("case", list(CASES))
def test_equals_mitsuba(mitsuba_brdf, case):
    """Mitsuba's own values at 400 pairs (300 random up to 89°, 100 near the mirror), each within
    ``1e-5 |f| + 8 ε · coat / (1 + (α² − 1) ch²)`` (module docstring); the defaults case gives Mitsuba no
    parameter at all, which checks :data:`DEFAULTS`."""
    expected = _assert_equals_mitsuba(mitsuba_brdf, CASES[case], seed=list(CASES).index(case))
    if case == "specular-0-metal":
        assert np.all(expected == 0.0)


def test_mitsuba_and_this_are_reciprocal(mitsuba_brdf):
    """Mitsuba takes the Fresnel terms' and the specular lobe's cosines from the viewer, but for unit directions
    above the horizon ``wi·h = wo·h`` and every lobe is symmetric: this function with light and viewer exchanged
    agrees to float64 rounding, Mitsuba within twice the tolerance above (its float32 directions are a rounding off
    unit length, which moves ``cd`` by ~4e-6 at grazing mirror pairs)."""
    params = CASES["mixed"]
    wi, wo = _pairs(seed=99)
    forward = mitsuba_brdf(_plugin(params), wi, wo)
    backward = mitsuba_brdf(_plugin(params), wo, wi)
    assert np.all(np.abs(forward - backward) <= 2 * _tolerance(params, wi, wo, forward))
    wi, wo = wi / np.linalg.norm(wi, axis=1, keepdims=True), wo / np.linalg.norm(wo, axis=1, keepdims=True)
    np.testing.assert_allclose(_brdf(params, wo, wi), _brdf(params, wi, wo), rtol=1e-12)


def test_below_the_horizon_is_zero():
    """0 wherever either direction is below the horizon (Mitsuba's too: the opaque plugin has no lobe there)."""
    wi = directions_from_degrees([30.0, 100.0, 91.0, 120.0], [0.0, 0.0, 0.0, 50.0])
    wo = directions_from_degrees([100.0, 30.0, 45.0, 130.0], [180.0, 180.0, 180.0, 0.0])
    values = _brdf(CASES["mixed"], wi, wo)
    assert values.shape == (4, 3)
    assert np.all(values == 0.0)


def test_monochrome_is_a_grey_rgb_channel():
    """C = 1 (Mitsuba's mono variants: the luminance is the value, tints are 1) equals a grey RGB's channel, whose
    luminance is the grey itself (the weights sum to 1)."""
    wi, wo = _pairs(seed=3)
    params = CASES["mixed"]
    rgb = _brdf(params | {"base_color": [0.4] * 3}, wi, wo)
    mono = _brdf(params | {"base_color": [0.4]}, wi, wo)
    assert mono.shape == (400, 1)
    np.testing.assert_allclose(mono[:, 0], rgb[:, 1], rtol=1e-14)


def test_other_channel_counts_and_unknown_parameters_are_refused():
    wi, wo = _pairs(seed=4, n_random=2, n_mirror=0)
    with pytest.raises(BrdfInputError, match=r"base_color has shape \(4,\); give 3 channels"):
        principled_brdf({"base_color": jnp.ones(4)}, wi, wo)
    with pytest.raises(BrdfInputError, match="'roughnes' is not a principled parameter; choose one of: base_color"):
        principled_brdf({"roughnes": 0.3}, wi, wo)


def test_parameters_list_every_default():
    assert [name for name, *_ in PARAMETERS] == list(DEFAULTS)
    assert all(lower == 0.0 and upper == 1.0 for _, _, lower, upper in PARAMETERS)
    assert [name for name, per_channel, *_ in PARAMETERS if per_channel] == ["base_color"]


#: Grazing, normal and exact-mirror pairs: light and viewer at 89.9° on either side, at normal incidence, one at the
#: normal and one grazing, along the tangent and the bitangent (the anisotropic slopes' 0s).
EDGE_WI = directions_from_degrees([89.9, 89.9, 0.0, 0.0, 60.0, 89.9, 45.0], [0.0, 0.0, 0.0, 0.0, 90.0, 90.0, 30.0])
EDGE_WO = directions_from_degrees(
    [89.9, 89.9, 0.0, 89.9, 60.0, 10.0, 45.0], [180.0, 0.0, 0.0, 0.0, 270.0, 270.0, 210.0]
)
#: An interior point with every lobe on, and the bounds the fits reach.
INTERIOR = CASES["mixed"]
EXTREMES = {
    "roughness-0": {"roughness": 0.0},
    "roughness-1": {"roughness": 1.0},
    "metallic-0": {"metallic": 0.0},
    "metallic-1": {"metallic": 1.0},
    "anisotropic-1": {"anisotropic": 1.0},
    "specular-0": {"specular": 0.0},
    "specular-1": {"specular": 1.0},
    "gloss-1": {"clearcoat_gloss": 1.0},
    "black": {"base_color": [0.0, 0.0, 0.0]},
}


@functools.cache
def _objective(dtype, edges: bool):
    """A weighted sum of the function's values (every channel and pair counts) and its gradient, compiled: at the
    edge pairs (``edges``), or at 24 seeded pairs up to 80°, each more than 10° from the mirror (a sharp lobe's peak,
    1e10 at roughness 0 and 89.9°, would drown the other terms' finite differences in rounding)."""
    if edges:
        wi, wo = EDGE_WI, EDGE_WO
    else:
        rng = np.random.default_rng(5)
        wi, wo = (random_directions(rng, 64, np.cos(np.radians(80.0))) for _ in range(2))
        away = np.sum(wi * (wo * np.array([-1.0, -1.0, 1.0])), axis=1) < np.cos(np.radians(10.0))
        wi, wo = wi[away][:24], wo[away][:24]
    wi, wo = jnp.asarray(wi, dtype), jnp.asarray(wo, dtype)
    weights = jnp.asarray(np.linspace(0.5, 1.5, 3 * len(wi)).reshape(-1, 3), dtype)

    def objective(params):
        return jnp.sum(weights * principled_brdf(params, wi, wo))

    return jax.jit(objective), jax.jit(jax.grad(objective))


@pytest.mark.parametrize("dtype", [jnp.float64, jnp.float32])
@pytest.mark.parametrize("extreme", list(EXTREMES))
def test_finite_values_and_gradients_at_the_edges(extreme, dtype):
    """Finite values and derivatives in every parameter at grazing (89.9°), normal and mirror pairs, at each bound,
    in float64 and float32; float32 in, float32 out."""
    params = _jax_params(INTERIOR | EXTREMES[extreme], dtype)
    values = _compiled_brdf(params, jnp.asarray(EDGE_WI, dtype), jnp.asarray(EDGE_WO, dtype))
    assert values.dtype == dtype
    assert bool(jnp.all(jnp.isfinite(values)))
    _, gradient_of = _objective(dtype, edges=True)
    gradient = gradient_of(params)
    assert all(bool(jnp.all(jnp.isfinite(value))) for value in gradient.values()), gradient


@pytest.mark.parametrize("point", ["interior", "roughness-0", "roughness-1", "metallic-1", "anisotropic-1"])
def test_gradients_match_central_differences(point):
    """``jax.grad`` against central differences of step 1e-6 in every parameter (each channel of base_color), in
    float64: the differences' truncation (~h² f''' ≈ 1e-12 relative) and rounding (~1e-16 f/h ≈ 1e-10 relative)
    errors lie far below the 1e-6 allowed. The formulas hold across the bounds (no mask cuts a lobe there), so the
    differences may straddle them; at roughness 0 the floor α = 0.001 holds on both sides (roughness² = 1e-12)."""
    objective, gradient_of = _objective(jnp.float64, edges=False)
    params = _jax_params(INTERIOR | ({} if point == "interior" else EXTREMES[point]))
    gradient = gradient_of(params)
    step = 1e-6
    for name, value in params.items():
        for index in np.ndindex(value.shape):
            shifted = [params | {name: value.at[index].add(sign * step)} for sign in (1.0, -1.0)]
            difference = (objective(shifted[0]) - objective(shifted[1])) / (2 * step)
            assert float(gradient[name][index]) == pytest.approx(float(difference), rel=1e-6, abs=1e-9), name


def test_equals_mitsuba_at_random_parameters(mitsuba_brdf):
    """Twenty seeded parameter sets drawn uniformly from the box of :data:`PARAMETERS` (every lobe on), at 400
    pairs each, within the tolerance of :func:`test_equals_mitsuba`."""
    rng = np.random.default_rng(20261121)
    for draw in range(20):
        params = {name: (rng.random(3) if per_channel else rng.random()) for name, per_channel, _, _ in PARAMETERS}
        _assert_equals_mitsuba(mitsuba_brdf, params, seed=1000 + draw)
