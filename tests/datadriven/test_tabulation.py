"""Where pairs fall in MERL's table and how the table is interpolated there; the maps of the basis."""

import math

import numpy as np
import pytest

from brdffit.data.merl import SHAPE, bin_directions
from brdffit.datadriven.mapping import EPSILON, MAPPINGS, mapped, unmapped
from brdffit.datadriven.tabulation import interpolation, table_coordinates
from brdffit.physics.geometry import from_half_difference
from brdffit.physics.merl_table import bin_angles
from tests.conftest import random_directions


def test_bins_have_whole_coordinates():
    """At a bin's own directions the coordinates are its indices (rounding: 1e-9 of a bin, far below the 1/90 a
    wrong bin would be)."""
    rng = np.random.default_rng(0)
    wi, wo = bin_directions()
    theta_d_bin = np.unravel_index(np.arange(wi.shape[0]), SHAPE)[1]
    # θd = 0 has no φd (wi = wo): those bins are left out.
    above = np.flatnonzero((wi[:, 2] > 1e-6) & (wo[:, 2] > 1e-6) & (theta_d_bin > 0))
    chosen = rng.choice(above, 2000, replace=False)
    expected = np.stack(np.unravel_index(chosen, SHAPE), axis=1)
    got = table_coordinates(wi[chosen], wo[chosen])
    got[:, 2] = np.where(got[:, 2] > SHAPE[2] - 1e-6, got[:, 2] - SHAPE[2], got[:, 2])  # φd = π is bin 0
    np.testing.assert_allclose(got, expected, atol=1e-9)


def test_a_bin_is_interpolated_by_itself():
    wi, wo = bin_directions()
    chosen = np.array([5 * 16200 + 20 * 180 + 33, 40 * 16200 + 10 * 180 + 0])
    index, weight = interpolation(wi[chosen], wo[chosen], np.ones(wi.shape[0], bool))
    for row, bin_ in enumerate(chosen):
        assert weight[row][index[row] == bin_].sum() == pytest.approx(1.0, abs=1e-9)


def test_weights_sum_to_one_and_skip_empty_bins():
    rng = np.random.default_rng(1)
    wi, wo = random_directions(rng, 500), random_directions(rng, 500)
    filled = rng.random(math.prod(SHAPE)) > 0.3
    index, weight = interpolation(wi, wo, filled)
    total = weight.sum(axis=1)
    np.testing.assert_allclose(total[total > 0], 1.0, atol=1e-12)
    assert np.all(weight[~filled[index]] == 0)


def test_phi_d_wraps_around():
    """Just below φd = π the neighbours are the last bin and bin 0 (φd = π is φd = 0 by reciprocity)."""
    theta_h, theta_d = np.array([0.3]), np.array([0.4])
    wi, wo = from_half_difference(theta_h, np.zeros(1), theta_d, np.array([math.pi * (1 - 0.25 / SHAPE[2])]))
    index, weight = interpolation(wi, wo, np.ones(math.prod(SHAPE), bool))
    phi_bins = np.unravel_index(index[0], SHAPE)[2]
    assert set(phi_bins[weight[0] > 0]) == {SHAPE[2] - 1, 0}


def test_reciprocal_pairs_share_their_bins():
    rng = np.random.default_rng(2)
    wi, wo = random_directions(rng, 300), random_directions(rng, 300)
    filled = np.ones(math.prod(SHAPE), bool)
    forward, backward = interpolation(wi, wo, filled), interpolation(wo, wi, filled)
    for row in range(wi.shape[0]):
        assert _weights(forward, row) == _weights(backward, row)


def _weights(interpolated, row: int) -> dict[int, float]:
    """The bins and weights (rounded to 1e-9, far above the angles' rounding) of one pair."""
    index, weight = interpolated
    return {int(i): round(float(w), 9) for i, w in zip(index[row], weight[row], strict=True) if w > 1e-12}


@pytest.mark.parametrize("mapping", MAPPINGS)
def test_maps_invert(mapping):
    """ρ(m(ρ)) = ρ to rounding: relative 1e-12 where ρ·w ≫ ε (the log's rounding, ε/(ρw) times larger below)."""
    rng = np.random.default_rng(3)
    rho = 10 ** rng.uniform(-2, 3, 1000)
    reference = 10 ** rng.uniform(-2, 2, 1000)
    weight = rng.uniform(0.05, 1.0, 1000)
    again = unmapped(mapping, mapped(mapping, rho, reference, weight), reference, weight)
    np.testing.assert_allclose(again, rho, rtol=1e-9)


def test_log_relative_is_zero_at_the_reference_and_never_below_zero():
    reference = np.array([0.1, 5.0, 200.0])
    assert np.all(mapped("log-relative", reference, reference, 0.5) == 0)
    assert np.all(unmapped("log-relative", np.array([-50.0]), reference, 0.5) == 0)  # clipped at ρ = 0
    # At a grazing pair (w → 0) every BRDF maps near 0: the floor ε dominates ρ·w.
    assert abs(mapped("log-relative", 10.0, 0.1, 1e-9)) < 10 * 1e-9 / EPSILON


def test_bin_angles_are_the_tables():
    """The coordinates use the table's own angle grid (data/merl.py)."""
    theta_h, _, phi_d = bin_angles()
    assert theta_h[1, 0, 0] == pytest.approx((1 / 90) ** 2 * math.pi / 2)
    assert phi_d[0, 0, 1] == pytest.approx(math.pi / 180)
