"""Fresnel terms against an independent computation with complex numbers (Born & Wolf §1.5)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from brdffit.physics.fresnel import fresnel_conductor, fresnel_dielectric, fresnel_schlick

COSINES = np.array([1.0, 0.9, 0.7, 0.5, 0.3, 0.1, 0.01, 1e-3])


def fresnel_from_amplitudes(cos_theta, index):
    """Unpolarised reflectance from the s and p amplitudes, with Snell's law in complex arithmetic."""
    index = np.asarray(index, dtype=complex)
    sin2 = 1.0 - cos_theta**2
    cos_t = np.sqrt(1.0 - sin2 / index**2)
    rs = (cos_theta - index * cos_t) / (cos_theta + index * cos_t)
    rp = (index * cos_theta - cos_t) / (index * cos_theta + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


@pytest.mark.parametrize("eta", [1.0001, 1.33, 1.5, 2.4, 10.0])
def test_dielectric_matches_the_amplitudes(eta):
    np.testing.assert_allclose(fresnel_dielectric(COSINES, eta), fresnel_from_amplitudes(COSINES, eta), rtol=1e-12)


@pytest.mark.parametrize(("eta", "k"), [(0.2, 3.9), (1.1, 6.9), (2.9, 3.0), (0.05, 0.0), (1.5, 0.0), (5.0, 10.0)])
def test_conductor_matches_the_amplitudes(eta, k):
    """rtol 1e-9: for eta < 1 and k = 0 (total reflection below the critical angle) the real-arithmetic
    form takes a ≈ sqrt(tiny); both forms agree to ~1e-10 there and to ~1e-15 elsewhere."""
    np.testing.assert_allclose(
        fresnel_conductor(COSINES, eta, k), fresnel_from_amplitudes(COSINES, eta + 1j * k), rtol=1e-9
    )


def test_golden_values():
    # Normal incidence on glass: ((1.5 - 1)/(1.5 + 1))² = 0.04 exactly.
    assert float(fresnel_dielectric(1.0, 1.5)) == pytest.approx(0.04, rel=1e-14)
    # Normal incidence on a conductor: ((n-1)² + k²)/((n+1)² + k²); gold at 550 nm, n = 0.2, k = 3.9.
    assert float(fresnel_conductor(1.0, 0.2, 3.9)) == pytest.approx((0.8**2 + 3.9**2) / (1.2**2 + 3.9**2), rel=1e-14)
    # Schlick: f0 at normal incidence, 1 at grazing.
    assert float(fresnel_schlick(1.0, 0.3)) == 0.3
    assert float(fresnel_schlick(0.0, 0.3)) == 1.0
    # A conductor with k = 0 is a dielectric.
    np.testing.assert_allclose(fresnel_conductor(COSINES, 1.5, 0.0), fresnel_dielectric(COSINES, 1.5), rtol=1e-13)


@pytest.mark.parametrize(
    ("function", "args"),
    [
        (fresnel_schlick, (0.04,)),
        (fresnel_dielectric, (1.5,)),
        (fresnel_conductor, (0.2, 3.9)),
        (fresnel_conductor, (0.5, 0.0)),
    ],
)
def test_gradients_are_finite_and_match_finite_differences(function, args):
    """Central differences with h = 1e-7 on cos β ∈ [0.01, 1 - 1e-6]: truncation ~1e-14, rounding ~1e-9."""
    cos_beta = jnp.linspace(0.01, 1.0 - 1e-6, 50)
    gradient = jax.vmap(
        jax.grad(lambda c, *a: function(c, *a), argnums=tuple(range(len(args) + 1))), in_axes=(0,) + (None,) * len(args)
    )(cos_beta, *(jnp.asarray(a) for a in args))
    for g in gradient:
        assert np.all(np.isfinite(g))
    h = 1e-7
    numeric = (np.asarray(function(cos_beta + h, *args)) - np.asarray(function(cos_beta - h, *args))) / (2 * h)
    np.testing.assert_allclose(gradient[0], numeric, rtol=1e-6, atol=1e-8)
