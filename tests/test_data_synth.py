"""Synthetic geometries, noise and sample sets."""

import numpy as np
import pytest

from brdffit import BrdfInputError, data_synth
from brdffit.physics.geometry import mirror_direction


def test_hemisphere_grid_layout():
    wi, wo = data_synth.hemisphere_grid(8, 36, 36)
    assert wi.shape == wo.shape == (8 * 36 * 36, 3)
    theta_i = np.degrees(np.arccos(wi[:, 2]))
    theta_o = np.degrees(np.arccos(wo[:, 2]))
    np.testing.assert_allclose(np.unique(theta_i.round(9)), (np.arange(8) + 0.5) * 90 / 8)
    np.testing.assert_allclose(np.unique(theta_o.round(9)), (np.arange(36) + 0.5) * 2.5)
    phi_o = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360
    np.testing.assert_allclose(np.unique(phi_o.round(6)) % 360, np.arange(36) * 10.0, atol=1e-6)
    np.testing.assert_allclose(wi[:, 1], 0.0)


def test_in_plane():
    wi, wo = data_synth.in_plane(4, 10)
    assert wi.shape == (40, 3)
    np.testing.assert_allclose(wo[:, 1], 0.0, atol=2e-16)  # sin(π) is 1.2e-16 in float64
    assert np.all(wo[:, 2] > 0) and np.sum(wo[:, 0] < 0) == 20  # half on the mirror side


def test_uniform_random_is_seeded_and_uniform_in_solid_angle():
    wi, wo = data_synth.uniform_random(20000, seed=3)
    again = data_synth.uniform_random(20000, seed=3)
    other = data_synth.uniform_random(20000, seed=4)
    np.testing.assert_array_equal(wi, again[0])
    assert not np.array_equal(wi, other[0])
    assert np.all((wi[:, 2] > 0) & (wo[:, 2] > 0))
    # Uniform in solid angle: cos θ is uniform on (0, 1]; mean 1/2 with standard error sqrt(1/12/N).
    assert abs(wo[:, 2].mean() - 0.5) < 5 * np.sqrt(1 / 12 / 20000)


def test_near_specular_stays_near_the_mirror_and_above_the_horizon():
    wi, wo = data_synth.near_specular(6, 3000, spread=8.0, seed=1)
    assert wi.shape == wo.shape == (3000, 3)
    angle = np.degrees(np.arccos(np.clip(np.sum(np.asarray(mirror_direction(wi)) * wo, axis=1), -1, 1)))
    assert angle.max() <= 8.0 + 1e-9
    assert np.all(wo[:, 2] > np.cos(np.radians(89.9)))
    np.testing.assert_array_equal(wo, data_synth.near_specular(6, 3000, spread=8.0, seed=1)[1])


def test_noise_statistics_and_seed():
    values = np.full((200000, 1), 0.3)
    noisy, sigma = data_synth.add_noise(values, 0.01, "multiplicative", seed=1)
    ratio = noisy / values - 1
    # Mean 0 and standard deviation 0.01, checked to 5 standard errors.
    assert abs(ratio.mean()) < 5 * 0.01 / np.sqrt(ratio.size)
    assert abs(ratio.std() - 0.01) < 5 * 0.01 / np.sqrt(2 * ratio.size)
    np.testing.assert_allclose(sigma, 0.003)
    np.testing.assert_array_equal(noisy, data_synth.add_noise(values, 0.01, "multiplicative", seed=1)[0])
    additive, sigma = data_synth.add_noise(np.zeros((1000, 1)), 0.1, "additive", seed=2)
    assert np.all(additive >= 0) and np.all(sigma == 0.1)  # clipped at 0: reflectance is never negative


def test_synthesize_names_channels_and_keeps_sigma():
    wi, wo = data_synth.uniform_random(100, seed=0)
    rgb = data_synth.synthesize(
        "ward", {"rho_d": [0.1, 0.2, 0.3], "rho_s": [0.1] * 3, "alpha": 0.2}, wi, wo, noise=0.01, with_sigma=True
    )
    assert rgb.channels == ("r", "g", "b") and rgb.sigma.shape == (100, 3)
    mono = data_synth.synthesize("lambert", {"rho_d": 0.5}, wi, wo)
    assert mono.channels == ("value",) and mono.sigma is None
    np.testing.assert_allclose(mono.values, 0.5 / np.pi)
    with pytest.raises(BrdfInputError, match="a sigma column needs noise > 0"):
        data_synth.synthesize("lambert", {"rho_d": 0.5}, wi, wo, with_sigma=True)
