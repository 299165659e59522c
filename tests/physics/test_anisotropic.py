"""Anisotropic GGX and Beckmann (Heitz 2014) as a Cook-Torrance option: normalisation, the masking identity, golden
values written out from the azimuth form of the formulas (not the tangent-frame components the code uses), the
isotropic lobe at alpha_u = alpha_v, the symmetries of the tangent, energy, the option's spelling and the canonical
twin. Reciprocity, gradients against finite differences and the parameter forms: the catalogue's two anisotropic
cases, in test_models.py."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import directions_from_degrees, random_directions
from scipy.special import erf
from test_models import _rotate_azimuth, directional_albedo

from brdffit import BrdfInputError, evaluate, get_model
from brdffit.physics.domains import AXIS_AZIMUTH
from brdffit.physics.geometry import in_turned_frame
from brdffit.physics.microfacet import DISTRIBUTIONS, anisotropic_slope2
from brdffit.physics.models.specs import model_of_spec, spec_of

SHADOWINGS = ("v-groove", "smith", "smith-correlated")


def _options(distribution, shadowing="smith", fresnel="none"):
    return {"fresnel": fresnel, "distribution": distribution, "shadowing": shadowing, "anisotropic": True}


def _midpoints(count: int, stop: float) -> np.ndarray:
    return (np.arange(count) + 0.5) * stop / count


def _normal_grid(n_u: int, n_phi: int):
    """Microfacet normals at the midpoints of an n_u × n_phi grid in (cos θh, φh), and each cell's d cos θh dφh."""
    u, phi = _midpoints(n_u, 1.0), _midpoints(n_phi, 2 * math.pi)
    uu, pp = np.meshgrid(u, phi, indexing="ij")
    sin = np.sqrt(1 - uu**2)
    return np.stack([sin * np.cos(pp), sin * np.sin(pp), uu], axis=-1), (1.0 / n_u) * (2 * math.pi / n_phi)


@pytest.mark.parametrize("name", list(DISTRIBUTIONS))
@pytest.mark.parametrize(("alpha_u", "alpha_v"), [(0.05, 0.3), (0.4, 0.1), (0.5, 1.0)])
def test_anisotropic_distributions_are_normalised(name, alpha_u, alpha_v):
    """∫ D(h) cos θh dω_h = 1 (Heitz 2014, eq. 4), by midpoints in (cos θh, φh): the grid resolves the sharpest lobe
    (α = 0.05: ~0.05 in tan θh, 3000 rows in cos θh) to 1e-3."""
    h, cell = _normal_grid(3000, 1440)
    density = DISTRIBUTIONS[name].anisotropic_density(
        jnp.asarray(h[..., 0]), jnp.asarray(h[..., 1]), jnp.asarray(h[..., 2]), alpha_u, alpha_v
    )
    assert float(jnp.sum(density * h[..., 2])) * cell == pytest.approx(1.0, rel=1e-3)


@pytest.mark.parametrize("name", list(DISTRIBUTIONS))
@pytest.mark.parametrize(("theta_o", "phi_o"), [(0.0, 0.0), (40.0, 20.0), (75.0, 100.0)])
def test_anisotropic_smith_masking_matches_its_distribution(name, theta_o, phi_o):
    """The identity that defines Smith's Λ (Heitz 2014, eq. 19), ∫ G1(wo) max(0, wo·h) D(h) dω_h = cos θo, holds only
    for the Λ of that D: with the direction's own roughness α(φ) it holds for the anisotropic D too (αu = 0.1,
    αv = 0.4, in the tangent frame). Midpoint quadrature: 1e-3, as for the isotropic ones."""
    alpha_u, alpha_v = 0.1, 0.4
    distribution = DISTRIBUTIONS[name]
    h, cell = _normal_grid(3000, 1440)
    wo = directions_from_degrees(theta_o, phi_o)[0]
    density = np.asarray(
        distribution.anisotropic_density(
            jnp.asarray(h[..., 0]), jnp.asarray(h[..., 1]), jnp.asarray(h[..., 2]), alpha_u, alpha_v
        )
    )
    lam = float(distribution.slope_lambda(anisotropic_slope2(jnp.asarray(wo), alpha_u, alpha_v)))
    integral = np.sum(np.maximum(h @ wo, 0.0) * density) * cell / (1.0 + lam)
    assert integral == pytest.approx(wo[2], rel=1e-3)


@pytest.mark.parametrize("distribution", list(DISTRIBUTIONS))
@pytest.mark.parametrize("shadowing", SHADOWINGS)
def test_anisotropic_golden_value(distribution, shadowing):
    """The lobe at one pair, written out by hand from the azimuth form: θi = 30°, φi = 10°, θo = 50°, φo = 200°;
    tangent at 25°; αu = 0.15, αv = 0.4; ks = 0.8, F = 1, kd = 0.1. D from h's zenith θh and azimuth φh' relative to
    the tangent, D = exp(−tan²θh (cos²φh'/αu² + sin²φh'/αv²)) / (π αu αv cos⁴θh) (GGX: 1/(π αu αv cos⁴θh (1 +
    …)²)); Λ with a = 1/(α(φ') tan θ), α(φ')² = cos²φ' αu² + sin²φ' αv², from each direction's zenith and azimuth."""
    alpha_u, alpha_v, phi_t = 0.15, 0.4, 25.0
    wi, wo = directions_from_degrees(30.0, 10.0), directions_from_degrees(50.0, 200.0)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    theta_h, phi_h = math.acos(h[0, 2]), math.atan2(h[0, 1], h[0, 0]) - math.radians(phi_t)
    spread = math.tan(theta_h) ** 2 * (math.cos(phi_h) ** 2 / alpha_u**2 + math.sin(phi_h) ** 2 / alpha_v**2)
    base = math.pi * alpha_u * alpha_v * math.cos(theta_h) ** 4
    density = math.exp(-spread) / base if distribution == "beckmann" else 1 / (base * (1 + spread) ** 2)

    def lam(theta_deg, phi_deg):
        phi = math.radians(phi_deg - phi_t)
        alpha = math.sqrt(math.cos(phi) ** 2 * alpha_u**2 + math.sin(phi) ** 2 * alpha_v**2)
        a = 1 / (alpha * math.tan(math.radians(theta_deg)))
        if distribution == "beckmann":
            return (erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))
        return (-1 + math.sqrt(1 + 1 / (a * a))) / 2

    ci, co, ch = wi[0, 2], wo[0, 2], h[0, 2]
    cos_beta = float(wi[0] @ h[0])
    g = {
        "v-groove": min(1.0, 2 * ch * ci / cos_beta, 2 * ch * co / cos_beta),
        "smith": 1 / ((1 + lam(30.0, 10.0)) * (1 + lam(50.0, 200.0))),
        "smith-correlated": 1 / (1 + lam(30.0, 10.0) + lam(50.0, 200.0)),
    }[shadowing]
    expected = 0.1 / math.pi + 0.8 * density * g / (4 * ci * co)
    params = {"kd": [0.1], "ks": [0.8], "alpha_u": alpha_u, "alpha_v": alpha_v, "phi_t": phi_t}
    got = evaluate("cook-torrance", params, wi, wo, **_options(distribution, shadowing))[0, 0]
    assert got == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("distribution", list(DISTRIBUTIONS))
@pytest.mark.parametrize("shadowing", SHADOWINGS)
@pytest.mark.parametrize("phi_t", [0.0, 37.0, -80.0, 90.0])
def test_a_round_lobe_is_the_isotropic_lobe_whatever_its_tangent(distribution, shadowing, phi_t, rng):
    """αu = αv = m is the isotropic lobe of roughness m at any tangent azimuth. The two compute tan²θ differently
    (``(1 − cos²)/cos²`` against the tangent-frame ``(x² + y²)/z²``): a few ulp, amplified by exp(−tan²θh/m²)
    (up to ~10² here) and the grazing ``1/z²``: rtol 1e-12."""
    wi, wo = random_directions(rng, 2000), random_directions(rng, 2000)
    options = {"fresnel": "conductor", "distribution": distribution, "shadowing": shadowing}
    fresnel = {"eta": 0.2, "k": 3.9}
    isotropic = evaluate("cook-torrance", {"kd": [0.1], "ks": [0.7], "m": 0.2, **fresnel}, wi, wo, **options)
    params = {"kd": [0.1], "ks": [0.7], "alpha_u": 0.2, "alpha_v": 0.2, "phi_t": phi_t, **fresnel}
    anisotropic = evaluate("cook-torrance", params, wi, wo, anisotropic=True, **options)
    np.testing.assert_allclose(anisotropic, isotropic, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("distribution", list(DISTRIBUTIONS))
@pytest.mark.parametrize("shadowing", SHADOWINGS)
def test_turning_both_directions_and_the_tangent_together_changes_nothing(distribution, shadowing, rng):
    """The lobe depends on the directions relative to the tangent only: turning wi, wo and phi_t by one angle (any
    per pair) leaves every value; turning the directions alone does not (the lobe is anisotropic); and the lobe is
    π-periodic in phi_t. Rounding of the rotations: rtol 1e-11, as for the isotropic models' common rotation."""
    wi, wo = random_directions(rng, 500), random_directions(rng, 500)
    params = {"kd": [0.05], "ks": [0.8], "alpha_u": 0.08, "alpha_v": 0.35}
    options = _options(distribution, shadowing)

    def values(phi_t, a, b):
        return evaluate("cook-torrance", {**params, "phi_t": phi_t}, a, b, **options)

    base = values(20.0, wi, wo)
    for turn in (33.0, -71.0, 140.0):
        turned = [_rotate_azimuth(w, np.radians(turn)) for w in (wi, wo)]
        np.testing.assert_allclose(values(float(AXIS_AZIMUTH.wrapped(20.0 + turn)), *turned), base, rtol=1e-11)
    directions_alone = values(20.0, _rotate_azimuth(wi, 0.7), _rotate_azimuth(wo, 0.7))
    assert np.max(np.abs(directions_alone - base) / base) > 0.1
    lobe = get_model("cook-torrance", **options).lobe  # π-periodic: the tangent and its opposite are one axis
    shape = {"alpha_u": 0.08, "alpha_v": 0.35}
    np.testing.assert_allclose(
        lobe(shape | {"phi_t": 200.0}, jnp.asarray(wi), jnp.asarray(wo)),
        lobe(shape | {"phi_t": 20.0}, jnp.asarray(wi), jnp.asarray(wo)),
        rtol=1e-11,
    )


def test_exchanging_the_roughnesses_with_the_tangent_turned_90_degrees_is_the_same_lobe(rng):
    """(αu, αv, φt) and (αv, αu, φt + 90°) are one lobe (the canonical twin a fit reports); rounding: rtol 1e-12."""
    wi, wo = random_directions(rng, 1000), random_directions(rng, 1000)
    options = _options("ggx", "smith-correlated")
    first = {"kd": [0.1], "ks": [0.6], "alpha_u": 0.3, "alpha_v": 0.07, "phi_t": 50.0}
    twin = {"kd": [0.1], "ks": [0.6], "alpha_u": 0.07, "alpha_v": 0.3, "phi_t": -40.0}
    np.testing.assert_allclose(
        evaluate("cook-torrance", first, wi, wo, **options),
        evaluate("cook-torrance", twin, wi, wo, **options),
        rtol=1e-12,
    )
    lobe = get_model("cook-torrance", **options).lobe
    canonical = lobe.canonical({name: np.array([value]) for name, value in first.items() if name not in ("kd", "ks")})
    assert {name: float(value[0]) for name, value in canonical.items()} == {
        "alpha_u": 0.07,
        "alpha_v": 0.3,
        "phi_t": -40.0,
    }
    at_seam = lobe.canonical({"alpha_u": np.array([0.3]), "alpha_v": np.array([0.1]), "phi_t": np.array([0.0])})
    assert at_seam["phi_t"] == pytest.approx([90.0])  # (−90, 90]: 90 is in, −90 is not


@pytest.mark.parametrize("distribution", list(DISTRIBUTIONS))
@pytest.mark.parametrize("shadowing", ["smith", "smith-correlated"])
def test_anisotropic_directional_albedo_at_most_one(distribution, shadowing):
    """Energy: with F = 1 and ks = 1 Smith's masking-shadowing only removes energy (Heitz 2014), so the lobe's
    directional albedo is at most 1 at every incidence, whichever azimuth the light comes from relative to the
    tangent (φt = 0° and 60°: along, across and between the axes). Quadrature of test_models (Gauss-Legendre ×
    periodic trapezoid), exact to ~1e-6: tolerance 1e-3."""
    options = _options(distribution, shadowing)
    for alpha_u, alpha_v in ((0.05, 0.3), (0.3, 1.0)):
        for phi_t in (0.0, 60.0):
            params = {"kd": [0.0], "ks": [1.0], "alpha_u": alpha_u, "alpha_v": alpha_v, "phi_t": phi_t}
            for theta in (0.0, 45.0, 75.0, 85.0):
                albedo = directional_albedo("cook-torrance", params, theta, options)[0]
                assert 0.2 < albedo <= 1.0 + 1e-3, (params, theta, albedo)


def test_in_turned_frame_is_the_tangent_frame():
    """Along the tangent at 30°: (1, 0, 0) in its frame; along its bitangent: (0, 1, 0)."""
    along, across = directions_from_degrees(90.0, 30.0), directions_from_degrees(90.0, 120.0)
    np.testing.assert_allclose(in_turned_frame(along, math.radians(30.0)), [[1.0, 0.0, 0.0]], atol=1e-15)
    np.testing.assert_allclose(in_turned_frame(across, math.radians(30.0)), [[0.0, 1.0, 0.0]], atol=1e-15)


def test_the_option_is_spelled_true_or_false_and_isotropic_stays_the_default():
    model = model_of_spec("cook-torrance:distribution=ggx,shadowing=smith,anisotropic=true")
    assert not model.isotropic and model.lobe.names == ("alpha_u", "alpha_v", "phi_t", "f0")
    assert spec_of(model.name, model.model_options) == "cook-torrance:distribution=ggx,shadowing=smith,anisotropic=true"
    assert model_of_spec("cook-torrance:anisotropic=TRUE") == get_model("cook-torrance", anisotropic=True)
    default = get_model("cook-torrance")
    assert (
        default.isotropic
        and default.lobe.names == ("m", "f0")
        and default == get_model("cook-torrance", anisotropic="false")
    )
    with pytest.raises(BrdfInputError) as error:
        get_model("cook-torrance", anisotropic="yes")
    assert str(error.value) == "anisotropic='yes' is not allowed; give true or false"
    params = {"kd": [0.1], "ks": [0.5], "alpha_u": 0.1, "alpha_v": 0.2, "phi_t": -90.0, "f0": 0.04}
    with pytest.raises(BrdfInputError, match=r"phi_t = -90.0 is outside its domain \(-90, 90\] degrees"):
        get_model("cook-torrance", anisotropic=True).dictionary.to_params(params)
