"""Directions, half vectors and the safe power used by the cosine lobes."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import random_directions

from brdffit.physics.geometry import (
    direction_to_spherical,
    from_half_difference,
    half_vector,
    mirror_direction,
    safe_power,
    spherical_to_direction,
    to_half_difference,
)


def test_spherical_round_trip(rng):
    theta = rng.uniform(0, np.pi / 2, 100)
    phi = rng.uniform(-np.pi, np.pi, 100)
    direction = spherical_to_direction(theta, phi)
    np.testing.assert_allclose(np.linalg.norm(direction, axis=-1), 1.0, rtol=1e-15)
    back_theta, back_phi = direction_to_spherical(direction)
    np.testing.assert_allclose(back_theta, theta, atol=1e-14)
    np.testing.assert_allclose(back_phi, phi, atol=1e-14)
    # The convention: phi = 0 is the tangent x, phi = 90° is y.
    np.testing.assert_allclose(spherical_to_direction(np.pi / 2, np.pi / 2), [0.0, 1.0, 0.0], atol=1e-16)


def test_azimuth_is_in_minus_pi_to_pi_with_pi_included():
    """A direction on the negative x axis has φ = π, whatever the sign of its zero y (-0.0 comes out of rotations
    and sign flips, and arctan2 would give -π for it), on the host and in JAX."""
    directions = np.array([[-0.6, 0.0, 0.8], [-0.6, -0.0, 0.8]])
    for phi in (direction_to_spherical(directions)[1], jax.jit(direction_to_spherical)(jnp.asarray(directions))[1]):
        assert np.all(np.asarray(phi) == np.pi)


def test_angle_conversions_stay_on_the_host_for_numpy_and_trace_for_jax(rng):
    """numpy in, numpy out (readers run on the host); JAX arrays and tracers get jax.numpy. Same values
    to 1 ulp (libm and XLA's sin/cos/atan2 may round differently)."""
    theta, phi = rng.uniform(0, np.pi / 2, 50), rng.uniform(-np.pi, np.pi, 50)
    on_host = spherical_to_direction(theta, phi)
    assert type(on_host) is np.ndarray and type(direction_to_spherical(on_host)[0]) is np.ndarray
    traced = jax.jit(spherical_to_direction)(jnp.asarray(theta), jnp.asarray(phi))
    assert isinstance(traced, jax.Array)
    np.testing.assert_allclose(on_host, traced, rtol=0, atol=4e-16)
    for host, device in zip(direction_to_spherical(on_host), jax.jit(direction_to_spherical)(traced), strict=True):
        np.testing.assert_allclose(host, device, rtol=0, atol=1e-15)


def test_half_vector_bisects(rng):
    wi, wo = random_directions(rng, 100), random_directions(rng, 100)
    h = np.asarray(half_vector(wi, wo))
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(np.sum(wi * h, axis=1), np.sum(wo * h, axis=1), rtol=1e-14)
    # The mirror direction's half vector is the normal.
    np.testing.assert_allclose(
        np.asarray(half_vector(wi, np.asarray(mirror_direction(wi)))), np.tile([0, 0, 1.0], (100, 1)), atol=1e-15
    )


@pytest.mark.parametrize("exponent", [1e-2, 0.5, 1.0, 7.0, 1e4])
def test_safe_power(exponent):
    base = jnp.array([-0.5, 0.0, 1e-320, 1e-300, 0.3, 1.0])
    values = safe_power(base, exponent)
    expected = np.where(np.array(base) > np.finfo(float).tiny, np.maximum(np.array(base), 0.0) ** exponent, 0.0)
    # exp(n ln b) carries a relative error of |n ln b|·ε: 690·1.1e-16 ≈ 8e-14 at b = 1e-300, n = 1.
    np.testing.assert_allclose(values, expected, rtol=2e-13)
    for grad in jax.vmap(jax.grad(safe_power, argnums=(0, 1)), in_axes=(0, None))(base, jnp.asarray(exponent)):
        assert np.all(np.isfinite(grad))


def test_half_difference_angles_round_trip_and_known_pairs(rng):
    """Rusinkiewicz's angles and back, on the host and in JAX; a mirror pair has θd = θi and θh = 0, a pair at
    the same direction θd = 0; swapping wi and wo turns φd by π."""
    theta_h, phi_h = rng.uniform(0, 1.2, 200), rng.uniform(-3, 3, 200)
    theta_d, phi_d = rng.uniform(0.01, 1.2, 200), rng.uniform(-3, 3, 200)
    wi, wo = from_half_difference(theta_h, phi_h, theta_d, phi_d)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1.0, rtol=1e-15)
    for back, given in zip(to_half_difference(wi, wo), (theta_h, phi_h, theta_d, phi_d), strict=True):
        np.testing.assert_allclose(np.angle(np.exp(1j * (back - given))), 0.0, atol=1e-12)  # azimuths modulo 2π
    traced = jax.jit(to_half_difference)(jnp.asarray(wi), jnp.asarray(wo))
    for host, device in zip(to_half_difference(wi, wo), traced, strict=True):
        np.testing.assert_allclose(host, device, rtol=0, atol=1e-12)
    light = spherical_to_direction(np.array([0.7]), np.array([0.3]))
    mirror = light * np.array([-1.0, -1.0, 1.0])
    angles = to_half_difference(light, mirror)
    np.testing.assert_allclose([angles[0][0], angles[2][0]], [0.0, 0.7], atol=1e-12)
    np.testing.assert_allclose(to_half_difference(light, light)[2], 0.0, atol=1e-7)
    swapped = to_half_difference(wo, wi)[3]
    np.testing.assert_allclose(np.angle(np.exp(1j * (swapped - phi_d - np.pi))), 0.0, atol=1e-12)


def test_public_angles_and_directions_round_trip_as_the_samples_file_holds_them(tmp_path):
    """``brdffit.directions_from_angles`` gives the directions ``load_samples`` reads from the same angles in a CSV
    file (to 1e-15: float64 rounding of sin and cos), and ``angles_from_directions`` gives them back (to 1e-12 degrees:
    arctan2 of rounded components); a zenith below the horizon is one line naming it."""
    import brdffit

    angles = np.array([[10.0, 0.0, 30.0, 180.0], [45.0, 20.0, 60.0, -90.0], [0.0, 0.0, 89.5, 45.0]])
    path = tmp_path / "angles.csv"
    path.write_text(
        "theta_i,phi_i,theta_o,phi_o,value\n" + "".join(",".join(map(str, row)) + ",0.1\n" for row in angles)
    )
    samples = brdffit.load_samples(path)
    wi, wo = brdffit.directions_from_angles(*angles.T)
    np.testing.assert_allclose(wi, samples.wi, atol=1e-15)
    np.testing.assert_allclose(wo, samples.wo, atol=1e-15)
    back = np.stack(brdffit.angles_from_directions(wi, wo), axis=1)
    np.testing.assert_allclose(back[1:], angles[1:], atol=1e-12)
    np.testing.assert_allclose(back[0, [0, 2, 3]], angles[0, [0, 2, 3]], atol=1e-12)  # φ of the normal is 0 anyway
    radians = brdffit.directions_from_angles(*np.radians(angles.T), degrees=False)
    np.testing.assert_allclose(radians[1], wo, atol=1e-15)
    with pytest.raises(
        brdffit.BrdfInputError, match=r"^theta_o = 95 \(at 0\) must be finite and within \[0, 90\] degrees"
    ):
        brdffit.directions_from_angles(10.0, 0.0, 95.0, 0.0)
