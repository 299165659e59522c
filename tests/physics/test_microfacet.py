"""Microfacet distributions and Smith masking-shadowing: normalisation, the masking identity, golden values derived
by hand (scipy's erf, not JAX's), and the Cook-Torrance lobe built from them."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import directions_from_degrees
from scipy.special import erf

from brdffit import evaluate
from brdffit.physics.microfacet import DISTRIBUTIONS, SHADOWING, beckmann_lambda, ggx_lambda


def _midpoints(count: int, stop: float) -> np.ndarray:
    return (np.arange(count) + 0.5) * stop / count


@pytest.mark.parametrize("name", list(DISTRIBUTIONS))
@pytest.mark.parametrize("m", [0.05, 0.3, 1.0])
def test_distributions_are_normalised(name, m):
    """∫ D(h) cos θh dω_h = 1 over the hemisphere of microfacet normals: in cos θh (D cos θh sin θh dθh = D u du),
    midpoints on a grid fine enough for the sharpest lobe (m = 0.05: the peak is ~0.05 wide in tan θh)."""
    u = _midpoints(400_000, 1.0)  # u = cos θh
    density = np.asarray(DISTRIBUTIONS[name].density(jnp.asarray(u), m))
    assert 2 * math.pi * np.sum(density * u) / u.size == pytest.approx(1.0, rel=1e-4)


@pytest.mark.parametrize("name", list(DISTRIBUTIONS))
@pytest.mark.parametrize("m", [0.1, 0.5])
@pytest.mark.parametrize("theta_o", [0.0, 40.0, 75.0])
def test_smith_masking_matches_its_distribution(name, m, theta_o):
    """The identity that defines Smith's Λ (Heitz 2014, eq. 19): the projected area of the visible microfacets is
    that of the geometric surface, ∫ G1(wo) max(0, wo·h) D(h) dω_h = cos θo. It holds only for the Λ that belongs
    to D, so it checks each Λ against its distribution. Midpoint quadrature in (cos θh, φh): 1e-3."""
    distribution = DISTRIBUTIONS[name]
    u, phi = _midpoints(3000, 1.0), _midpoints(720, 2 * math.pi)
    uu, pp = np.meshgrid(u, phi, indexing="ij")
    sin = np.sqrt(1 - uu**2)
    h = np.stack([sin * np.cos(pp), sin * np.sin(pp), uu], axis=-1)
    wo = directions_from_degrees(theta_o, 0.0)[0]
    projected = np.maximum(h @ wo, 0.0)
    density = np.asarray(distribution.density(jnp.asarray(uu), m))
    g1 = 1.0 / (1.0 + float(distribution.smith_lambda(jnp.asarray(wo[2]), m)))
    integral = g1 * np.sum(projected * density) * (1.0 / u.size) * (2 * math.pi / phi.size)
    assert integral == pytest.approx(wo[2], rel=1e-3)


def test_smith_lambda_golden_values():
    """Λ from its formula with a = 1/(m tan θ), evaluated by hand (scipy's erf): Beckmann
    (erf(a) − 1)/2 + exp(−a²)/(2a√π), GGX (−1 + sqrt(1 + 1/a²))/2; at θ = 60°, m = 0.4 (a = 1/(0.4·√3))."""
    a = 1 / (0.4 * math.sqrt(3))
    beckmann = (erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))
    ggx = (-1 + math.sqrt(1 + 1 / (a * a))) / 2
    cos60 = jnp.asarray(0.5)
    assert float(beckmann_lambda(cos60, 0.4)) == pytest.approx(beckmann, rel=1e-12)
    assert float(ggx_lambda(cos60, 0.4)) == pytest.approx(ggx, rel=1e-12)
    # At the normal Λ = 0 (G1 = 1); at grazing it grows without bound.
    assert float(beckmann_lambda(jnp.asarray(1.0), 0.4)) == pytest.approx(0.0, abs=1e-200)
    assert float(ggx_lambda(jnp.asarray(1.0), 0.4)) == 0.0
    assert float(beckmann_lambda(jnp.asarray(math.cos(math.radians(89.9))), 0.4)) > 50


@pytest.mark.parametrize("distribution", list(DISTRIBUTIONS))
@pytest.mark.parametrize("shadowing", list(SHADOWING))
def test_cook_torrance_golden_value(distribution, shadowing):
    """The lobe at one pair, written out by hand: θi = 30°, φi = 0, θo = 50°, φo = 200°; ks = 0.8, m = 0.25,
    F = 1 (fresnel none), kd = 0.1."""
    wi, wo = directions_from_degrees(30.0, 0.0), directions_from_degrees(50.0, 200.0)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    ci, co, ch = wi[0, 2], wo[0, 2], h[0, 2]
    cos_beta = float(wi[0] @ h[0])
    m = 0.25
    tan2_h = (1 - ch**2) / ch**2
    if distribution == "beckmann":
        density = math.exp(-tan2_h / m**2) / (math.pi * m**2 * ch**4)

        def lam(c):
            a = 1 / (m * math.sqrt(1 - c * c) / c)
            return (erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))
    else:
        density = m**2 / (math.pi * ch**4 * (m**2 + tan2_h) ** 2)

        def lam(c):
            return (-1 + math.sqrt(1 + m * m * (1 - c * c) / (c * c))) / 2

    g = {
        "v-groove": min(1.0, 2 * ch * ci / cos_beta, 2 * ch * co / cos_beta),
        "smith": 1 / ((1 + lam(ci)) * (1 + lam(co))),
        "smith-correlated": 1 / (1 + lam(ci) + lam(co)),
    }[shadowing]
    expected = 0.1 / math.pi + 0.8 * density * g / (4 * ci * co)
    params = {"kd": [0.1], "ks": [0.8], "m": m}
    options = {"fresnel": "none", "distribution": distribution, "shadowing": shadowing}
    assert evaluate("cook-torrance", params, wi, wo, **options)[0, 0] == pytest.approx(expected, rel=1e-12)


def test_the_defaults_are_cook_and_torrances_model():
    """No option given: Beckmann and V-groove, the model every earlier result file was fitted with."""
    wi, wo = directions_from_degrees([10.0, 40.0, 70.0], 0.0), directions_from_degrees([20.0, 50.0, 85.0], 180.0)
    params = {"kd": [0.2], "ks": [0.5], "m": 0.2, "f0": 0.04}
    np.testing.assert_array_equal(
        evaluate("cook-torrance", params, wi, wo),
        evaluate("cook-torrance", params, wi, wo, distribution="beckmann", shadowing="v-groove"),
    )
