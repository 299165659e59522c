"""KHR_materials_sheen's lobe and its directional albedo ``E`` (``physics/renderers/sheen.py``): the Charlie
distribution normalised, Λ continuous where its two branches meet, the stored table the quadrature's, its
interpolation close to the quadrature between the nodes, and values and derivatives finite at the edges."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from brdffit.physics.renderers.sheen import (
    albedo_quadrature,
    charlie_distribution,
    sheen_albedo,
    sheen_alpha,
    sheen_lambda,
)
from brdffit.physics.renderers.sheen_table import NODES, SHEEN_ALBEDO


@pytest.mark.parametrize("sheen_roughness", [0.1, 0.3, 0.5, 1.0])
def test_the_charlie_distribution_is_normalised(sheen_roughness):
    # ∫ D cos θh dω_h = 2π ∫ D cos θh sin θh dθh = 1 (Estevez & Kulla 2017): by the midpoint rule on 200,000 rows, whose
    # error (~1e-9 for the narrowest lobe here, α_g = 0.01) the tolerance 1e-6 covers.
    n = 200_000
    theta = (np.arange(n) + 0.5) * (math.pi / 2) / n
    alpha = sheen_alpha(sheen_roughness)
    integrand = charlie_distribution(np.cos(theta), alpha) * np.cos(theta) * np.sin(theta)
    assert 2 * math.pi * integrand.sum() * (math.pi / 2) / n == pytest.approx(1.0, rel=1e-6)


def test_lambda_is_continuous_where_its_branches_meet():
    # exp(l(μ)) below 0.5, exp(2 l(0.5) − l(1 − μ)) from 0.5: the same at 0.5, and within rounding either side of it
    for alpha in (1e-4, 0.09, 0.25, 1.0):
        below, at, above = (float(sheen_lambda(np.float64(x), alpha)) for x in (0.5 - 1e-12, 0.5, 0.5 + 1e-12))
        assert below == pytest.approx(at, rel=1e-9) and above == pytest.approx(at, rel=1e-9)


def test_the_stored_table_is_the_quadrature():
    # Nodes across the table (grazing, middle, normal; smooth to rough) computed afresh, with the table's n = 400 (its
    # 12 decimals) and with n = 800 (the quadrature's own error: within 1e-4 of the stored value).
    for i, j in [(2, 3), (4, 1), (8, 8), (16, 4), (16, 20), (24, 12), (32, 0), (32, 32), (10, 28)]:
        cosine, roughness = (j / (NODES - 1)) ** 2, (i / (NODES - 1)) ** 2
        assert albedo_quadrature(cosine, roughness) == pytest.approx(SHEEN_ALBEDO[i][j], abs=1e-12)
        assert albedo_quadrature(cosine, roughness, n=800) == pytest.approx(SHEEN_ALBEDO[i][j], abs=1e-4)


def test_the_interpolated_albedo_is_the_quadratures_between_the_nodes():
    # 60 random (μ, r) from 0.02 to 1: measured within 1e-3 (at r near 1, the last interval's extrapolated end node),
    # median 1e-5; the tolerances twice and ten times that.
    rng = np.random.default_rng(4)
    points = rng.uniform(0.02, 1.0, size=(60, 2))
    errors = [abs(float(sheen_albedo(np.array([mu]), r)[0]) - albedo_quadrature(mu, r)) for mu, r in points]
    assert max(errors) < 2e-3 and np.median(errors) < 1e-4, (max(errors), np.median(errors))
    # at the nodes, the interpolation is the table
    for i, j in [(8, 8), (20, 5), (31, 30)]:
        value = sheen_albedo(np.array([(j / (NODES - 1)) ** 2]), (i / (NODES - 1)) ** 2)[0]
        assert value == pytest.approx(min(SHEEN_ALBEDO[i][j], 1.0), abs=1e-12)


def test_the_albedo_exceeds_one_at_grazing_views_of_smooth_sheens_and_is_clipped_there():
    # Charlie's visibility is Estevez & Kulla's fit, not exact: seen from 0.01 (89.4°) a sheen of roughness 0.05
    # reflects 1.61 times what it receives (the quadrature), which the layering's E clips to 1.
    assert albedo_quadrature(0.01, 0.05) == pytest.approx(1.6085, abs=1e-3)
    assert float(sheen_albedo(np.array([0.01]), 0.05)[0]) == 1.0
    # the roughest sheen stays below 1 but on the horizon (measured: 1.016 at μ = 10⁻⁶, 0.763 at most from μ = 0.001)
    assert SHEEN_ALBEDO[-1][0] > 1.0 and max(SHEEN_ALBEDO[-1][1:]) < 0.77


def test_values_and_derivatives_are_finite_at_the_edges():
    cosines = jnp.array([1e-9, 1e-3, 0.25, 0.5, 1.0])
    for roughness in (0.0, 1e-6, 1e-3, 0.5, 1.0):
        with jax.enable_x64(True):
            values = sheen_albedo(cosines, jnp.float64(roughness))
            by_cosine = jax.grad(lambda c, r=roughness: jnp.sum(sheen_albedo(c, jnp.float64(r))))(cosines)
            by_roughness = jax.grad(lambda r: jnp.sum(sheen_albedo(cosines, r)))(jnp.float64(roughness))
        assert np.all(np.isfinite(values)) and np.all((values >= 0) & (values <= 1))
        assert np.all(np.isfinite(by_cosine)) and np.isfinite(by_roughness)


def test_the_interpolation_is_smooth_across_a_node():
    # Catmull-Rom is C¹: the derivative in μ just left and right of a node agrees (a linear interpolation's would jump
    # by the difference of the neighbouring slopes, here 10% of them)
    node = (12 / (NODES - 1)) ** 2
    with jax.enable_x64(True):
        slope = jax.grad(lambda c: sheen_albedo(jnp.reshape(c, (1,)), jnp.float64(0.5))[0])
        left, right = float(slope(jnp.float64(node * (1 - 1e-9)))), float(slope(jnp.float64(node * (1 + 1e-9))))
    assert left == pytest.approx(right, rel=1e-6)
