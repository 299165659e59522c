"""Mitsuba 3's ``roughplastic`` in JAX: against Mitsuba 3 itself (skipped where it is not installed), its tables against
Mitsuba's quadrature, reciprocity, and finite gradients that match finite differences.

Tolerances, with their reasons:

* specular term, 1e-5 relative: Mitsuba's ``scalar_rgb`` computes in float32 (ε = 6e-8); its ``D·G·F`` through
  ``normalize``, ``exp`` and the Smith terms lands within ~70 ε = 4.7e-6 of the float64 value (measured over these
  pairs), so 1e-5 holds twice that. Values below 1e-10 of the largest are compared absolutely: there Mitsuba's float32
  exponent (``tan²θh/α²`` of thousands) loses the relative digits, and its ``D·h_z ≤ 1e-20`` cut may fall either way;
* diffuse term, :data:`DIFFUSE_TABLE_ERROR` (2e-3): the table's interpolation in ``α``, measured at every midpoint of
  its grid (the module docstring); at a node, where there is none, 2e-5 (float32 sums of 1024 and 16384 terms, which
  land within 6e-6).

The directions are rounded to float32 before either side sees them, so that Mitsuba's inputs are the same numbers.
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import random_directions

from brdffit.errors import BrdfInputError
from brdffit.physics.geometry import mirror_direction
from brdffit.physics.models.cook_torrance import CookTorranceLobe
from brdffit.physics.renderers.roughplastic import (
    ALPHA_NODES,
    ALPHA_RANGE,
    DIFFUSE_TABLE_ERROR,
    rough_dielectric_table,
    rough_dielectric_terms,
    roughplastic_brdf,
)

try:
    import mitsuba
except ImportError:
    mitsuba = None

needs_mitsuba = pytest.mark.skipif(mitsuba is None, reason="Mitsuba 3 is not installed (pip install 'brdffit[render]')")

#: Float32 evaluation against float64 (module docstring).
SPECULAR_RTOL = 1e-5
#: Mitsuba's tables against this module's at a node: float32 sums (module docstring).
NODE_RTOL = 2e-5
#: Values below this fraction of the largest are compared absolutely (module docstring).
TAIL = 1e-10
GRAZING_COS = math.cos(math.radians(89.0))
KD = np.array([0.3, 0.5, 0.1])
KS = np.array([1.0, 0.8, 0.6])
ALPHAS = (0.01, 0.05, 0.2, 0.6, 1.0)


def float32_exact(directions):
    return np.asarray(directions, dtype=np.float32).astype(float)


@pytest.fixture(scope="module")
def pairs():
    """360 pairs: 300 uniform in solid angle down to 89° from the normal (both), 60 within ~1° of the mirror."""
    rng = np.random.default_rng(20261126)
    wi = random_directions(rng, 360, GRAZING_COS)
    wo = random_directions(rng, 360, GRAZING_COS)
    near = mirror_direction(wi[:60]) + rng.normal(scale=0.02, size=(60, 3))
    near[:, 2] = np.abs(near[:, 2]) + 0.02
    wo[:60] = near / np.linalg.norm(near, axis=1, keepdims=True)
    return float32_exact(wi), float32_exact(wo)


def plugin(distribution, alpha, int_ior, kd, ks):
    return {
        "type": "roughplastic",
        "distribution": distribution,
        "alpha": alpha,
        "int_ior": int_ior,
        "diffuse_reflectance": {"type": "rgb", "value": list(map(float, kd))},
        "specular_reflectance": {"type": "rgb", "value": list(map(float, ks))},
    }


#: Compiled once per distribution, index and shape: op by op, JAX compiles each primitive for each shape apart.
brdf = jax.jit(roughplastic_brdf, static_argnames=("distribution", "int_ior"))


def ours(distribution, alpha, int_ior, kd, ks, wi, wo):
    params = {"alpha": alpha, "diffuse_reflectance": jnp.asarray(kd), "specular_reflectance": jnp.asarray(ks)}
    return np.asarray(brdf(params, jnp.asarray(wi), jnp.asarray(wo), distribution=distribution, int_ior=int_ior))


def theirs(distribution, alpha, int_ior, kd, ks, wi, wo):
    from brdffit.export.mitsuba_eval import mitsuba_brdf

    return mitsuba_brdf(plugin(distribution, alpha, int_ior, kd, ks), wi, wo)


def assert_close(got, expected, rtol):
    """``|got − expected| ≤ rtol·|expected| + TAIL·max|expected|``."""
    allowed = rtol * np.abs(expected) + TAIL * np.abs(expected).max()
    worst = np.argmax(np.abs(got - expected) - allowed)
    assert np.all(np.abs(got - expected) <= allowed), (got.flat[worst], expected.flat[worst])


#: Each case builds its table (~2.5 s): the default index with both distributions, and 1.6 with GGX (whose internal
#: reflectance ripples most) in the quick run, with Beckmann in the heavy one.
CASES = [
    pytest.param("beckmann", 1.49, id="beckmann-1.49"),
    pytest.param("ggx", 1.49, id="ggx-1.49"),
    pytest.param("ggx", 1.6, id="ggx-1.6"),
    pytest.param("beckmann", 1.6, id="beckmann-1.6", marks=pytest.mark.heavy),
]


@needs_mitsuba
@pytest.mark.parametrize(("distribution", "int_ior"), CASES)
def test_matches_mitsuba(pairs, distribution, int_ior):
    """Each term alone and both together, at five roughnesses, over the 360 pairs."""
    wi, wo = pairs
    zero = np.zeros(3)
    for alpha in ALPHAS:
        specular = ours(distribution, alpha, int_ior, zero, KS, wi, wo)
        assert_close(specular, theirs(distribution, alpha, int_ior, zero, KS, wi, wo), SPECULAR_RTOL)
        diffuse = ours(distribution, alpha, int_ior, KD, zero, wi, wo)
        assert_close(diffuse, theirs(distribution, alpha, int_ior, KD, zero, wi, wo), DIFFUSE_TABLE_ERROR)
        both = ours(distribution, alpha, int_ior, KD, KS, wi, wo)
        allowed = SPECULAR_RTOL * specular + DIFFUSE_TABLE_ERROR * diffuse + TAIL * specular.max()
        assert np.all(np.abs(both - theirs(distribution, alpha, int_ior, KD, KS, wi, wo)) <= allowed)


@needs_mitsuba
@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test_tables_match_mitsuba_at_their_nodes(distribution):
    """At a tabulated roughness there is no interpolation: the diffuse term at the pairs (μ_j, 1) and (μ_j, μ_j) of
    Mitsuba's own cosines, which its linear interpolation returns as they are, is Mitsuba's to float32 sums."""
    log_alphas = np.linspace(math.log(ALPHA_RANGE[0]), math.log(ALPHA_RANGE[1]), ALPHA_NODES)
    cosines = np.arange(1, 64) / 63.0
    light = np.stack([np.sqrt(1.0 - cosines**2), np.zeros_like(cosines), cosines], axis=-1)
    wi = float32_exact(np.concatenate([light, light]))
    wo = np.concatenate([np.tile([0.0, 0.0, 1.0], (63, 1)), mirror_direction(wi[63:])])
    for alpha in np.exp(log_alphas[[0, 9, 20, 31, 40, 47]]).astype(np.float32).astype(float):
        got = ours(distribution, alpha, 1.49, KD, np.zeros(3), wi, wo)
        assert_close(got, theirs(distribution, alpha, 1.49, KD, np.zeros(3), wi, wo), NODE_RTOL)


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test_interpolation_error_between_nodes(distribution):
    """The spline at midpoints of the grid against Mitsuba's quadrature run there: the diffuse term's factor
    ``T(ci) T(co)/(1 − Ri)`` within DIFFUSE_TABLE_ERROR (a few midpoints; every one: the heavy test below)."""
    check_midpoints(distribution, 1.49 / 1.000277, [3, 15, 24, 33, 45])


@pytest.mark.heavy
@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
@pytest.mark.parametrize("eta", [1.3, 1.49 / 1.000277, 1.6 / 1.000277], ids=["1.3", "1.49", "1.6"])
def test_interpolation_error_at_every_midpoint(distribution, eta):
    check_midpoints(distribution, eta, range(ALPHA_NODES - 1))


def check_midpoints(distribution, eta, intervals):
    log_alphas = np.linspace(math.log(ALPHA_RANGE[0]), math.log(ALPHA_RANGE[1]), ALPHA_NODES)
    table = rough_dielectric_table(distribution, eta)
    for k in intervals:
        alpha = math.exp(0.5 * (log_alphas[k] + log_alphas[k + 1]))
        exact = rough_dielectric_terms(distribution, alpha, eta)
        transmittance, internal = (np.asarray(x) for x in table.at(alpha, np.float64))
        got = np.outer(transmittance, transmittance) / (1.0 - internal)
        expected = np.outer(exact[:64], exact[:64]) / (1.0 - exact[64])
        np.testing.assert_allclose(got, expected, rtol=DIFFUSE_TABLE_ERROR, err_msg=f"alpha {alpha}")


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test_reciprocal(pairs, distribution):
    """Both terms are symmetric in the light and the viewer: f(wi, wo) = f(wo, wi) to float64 rounding, for unit
    vectors (the float32-rounded ones are 6e-8 off unit length, which moves ``wi·h`` from ``wo·h``, and so ``F`` at
    grazing ``cos β``, by up to 4e-6)."""
    wi, wo = (w / np.linalg.norm(w, axis=1, keepdims=True) for w in pairs)
    forward = ours(distribution, 0.2, 1.49, KD, KS, wi, wo)
    np.testing.assert_allclose(ours(distribution, 0.2, 1.49, KD, KS, wo, wi), forward, rtol=1e-12)


@needs_mitsuba
def test_mitsuba_is_reciprocal_too(pairs):
    """Mitsuba places ``t_i`` (the viewer's) and ``t_o`` (the light's) symmetrically: its values swap to float32."""
    wi, wo = pairs
    forward = theirs("ggx", 0.2, 1.49, KD, KS, wi, wo)
    assert_close(theirs("ggx", 0.2, 1.49, KD, KS, wo, wi), forward, SPECULAR_RTOL)


def test_ggx_specular_is_the_cook_torrance_lobe(pairs):
    """GGX with separable Smith and the exact dielectric Fresnel: brdffit's own Cook-Torrance lobe, to rounding."""
    wi, wo = pairs
    specular = ours("ggx", 0.3, 1.49, np.zeros(1), np.ones(1), wi, wo)[:, 0]
    lobe = CookTorranceLobe("dielectric", "ggx", "smith")({"m": 0.3, "eta": 1.49 / 1.000277}, wi, wo)
    np.testing.assert_allclose(specular, np.asarray(lobe), rtol=1e-12)


def test_below_the_horizon_is_zero():
    wi = np.array([[0.0, 0.6, 0.8], [0.6, 0.0, -0.8], [0.6, 0.0, 0.0]])
    wo = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    assert np.all(ours("beckmann", 0.1, 1.49, KD, KS, wi, wo) == 0.0)


def test_refuses_a_coating_lighter_than_the_outside():
    with pytest.raises(BrdfInputError, match=r"int_ior=1\.0 must exceed ext_ior"):
        ours("ggx", 0.1, 1.0, KD, KS, np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))


def grazing_pairs():
    """Pairs at 89.9° and at the normal, in and off the mirror plane, and one near the mirror."""
    theta = np.radians([89.9, 89.9, 0.0, 89.9, 60.0])
    phi = np.radians([0.0, 180.0, 0.0, 90.0, 0.0])
    theta_o = np.radians([89.9, 89.9, 89.9, 0.0, 60.05])
    wi = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    wo = np.stack([-np.sin(theta_o), np.zeros(5), np.cos(theta_o)], axis=-1)
    return jnp.asarray(wi), jnp.asarray(wo)


@functools.partial(jax.jit, static_argnums=3)
def total(params, wi, wo, distribution):
    return jnp.sum(roughplastic_brdf(params, wi, wo, distribution=distribution))


#: Compiled once per distribution and shape, as :data:`brdf`.
total_gradient = jax.jit(jax.grad(total), static_argnums=3)


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
@pytest.mark.parametrize("alpha", [5e-5, 1e-4, 1e-3, 0.3, 2.0, 3.0])
def test_gradients_are_finite_at_grazing_angles_and_extreme_roughness(distribution, alpha):
    wi, wo = grazing_pairs()
    params = {"alpha": alpha, "diffuse_reflectance": jnp.asarray(KD), "specular_reflectance": jnp.asarray(KS)}
    values = brdf(params, wi, wo, distribution=distribution)
    gradient = total_gradient(params, wi, wo, distribution)
    assert np.all(np.isfinite(values))
    assert all(np.all(np.isfinite(g)) for g in jax.tree_util.tree_leaves(gradient))


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
@pytest.mark.parametrize("alpha", [2e-3, 0.07, 0.45, 1.7])
def test_gradient_matches_finite_differences(pairs, distribution, alpha):
    """Central differences in float64 with steps 1e-6 relative: truncation ~1e-12 relative, rounding ~1e-10."""
    wi, wo = (jnp.asarray(w[60:120]) for w in pairs)  # off the mirror: values of order 1, not 1e3
    params = {"alpha": alpha, "diffuse_reflectance": jnp.asarray(KD), "specular_reflectance": jnp.asarray(KS)}
    gradient = total_gradient(params, wi, wo, distribution)
    step = 1e-6 * alpha
    difference = (
        total(params | {"alpha": alpha + step}, wi, wo, distribution)
        - total(params | {"alpha": alpha - step}, wi, wo, distribution)
    ) / (2 * step)
    np.testing.assert_allclose(float(gradient["alpha"]), float(difference), rtol=1e-6)
    # linear in the reflectances (Euler): kd·∂/∂kd + ks·∂/∂ks is the value itself
    linear = np.dot(gradient["diffuse_reflectance"], KD) + np.dot(gradient["specular_reflectance"], KS)
    np.testing.assert_allclose(linear, float(total(params, wi, wo, distribution)), rtol=1e-12)


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test_the_slope_in_alpha_is_continuous_across_nodes(distribution):
    """The spline is C²: on either side of a node the derivative in α agrees (Mitsuba's own linear interpolation in
    cos θ is what the derivative in the directions sees, not this)."""
    wi, wo = (jnp.asarray(w) for w in grazing_pairs())
    log_alphas = np.linspace(math.log(ALPHA_RANGE[0]), math.log(ALPHA_RANGE[1]), ALPHA_NODES)
    params = {"alpha": 0.0, "diffuse_reflectance": jnp.asarray(KD), "specular_reflectance": jnp.zeros(3)}
    for node in np.exp(log_alphas[[5, 23, 40]]):
        below, above = (
            float(total_gradient(params | {"alpha": float(node * factor)}, wi, wo, distribution)["alpha"])
            for factor in (1 - 1e-9, 1 + 1e-9)
        )
        assert below == pytest.approx(above, rel=1e-6)


def test_float32_follows_float64(pairs):
    """With float64 off, the result is float32 and within float32 rounding of the float64 one (1e-5 relative,
    the specular tolerance, plus the tail)."""
    wi, wo = pairs
    expected = ours("beckmann", 0.2, 1.49, KD, KS, wi, wo)
    with jax.enable_x64(False):
        params = {"alpha": 0.2, "diffuse_reflectance": jnp.asarray(KD, jnp.float32), "specular_reflectance": KS}
        got = brdf(params, jnp.asarray(wi, jnp.float32), jnp.asarray(wo, jnp.float32))
        assert got.dtype == jnp.float32
    assert_close(np.asarray(got, dtype=float), expected, SPECULAR_RTOL)


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test_the_shipped_rows_are_the_quadratures(distribution):
    """The default index's rows ship (``roughplastic_rows.npz``: 2 s a distribution saved in every process that uses
    the model); they must be what the quadrature computes today, at every node (a few nodes here, all of them where
    the grid's size changed), to the summation order of numpy's reductions on another machine: 1e-12 relative. Any
    other index is computed."""
    from brdffit.physics.renderers.roughplastic import (
        ALPHA_NODES,
        COSINE_NODES,
        DEFAULT_INT_IOR,
        EXT_IOR,
        shipped_rows,
        tabulated_log_alphas,
    )

    shipped = shipped_rows(distribution, DEFAULT_INT_IOR / EXT_IOR)
    assert shipped.shape == (ALPHA_NODES, COSINE_NODES + 1)
    for node in (0, 17, ALPHA_NODES - 1):
        alpha = float(np.exp(tabulated_log_alphas()[node]))
        computed = rough_dielectric_terms(distribution, alpha, DEFAULT_INT_IOR / EXT_IOR)
        np.testing.assert_allclose(shipped[node], computed, rtol=1e-12, atol=0.0)
    assert shipped_rows(distribution, 1.6) is None
