"""The greedy choice of direction pairs and the directions file."""

import numpy as np
import pytest

from brdffit.data.merl import bin_directions
from brdffit.datadriven.basis import load_basis
from brdffit.datadriven.directions import (
    MIN_SEPARATION,
    bin_angles_degrees,
    condition_number,
    read_directions,
    select_bins,
    write_directions,
)
from brdffit.errors import BrdfInputError


def test_selection_is_seeded_distinct_and_within_limits(basis_file):
    basis = load_basis(basis_file)
    bins = select_bins(basis, 12, max_theta=60, candidates=2000, seed=3)
    assert np.array_equal(bins, select_bins(basis, 12, max_theta=60, candidates=2000, seed=3))
    assert len(set(bins.tolist())) == 12 and basis.filled[bins].all()
    wi, wo = bin_directions()
    assert np.all(np.degrees(np.arccos(wi[bins, 2])) <= 60 + 1e-9)
    assert np.all(np.degrees(np.arccos(wo[bins, 2])) <= 60 + 1e-9)
    assert np.all(np.degrees(np.arccos(np.sum(wi[bins] * wo[bins], axis=1))) >= MIN_SEPARATION - 1e-9)


def test_greedy_pairs_condition_better_than_random_ones(basis_file):
    """The greedy pairs' condition number beats the median of 20 seeded random choices of as many filled bins (the
    greedy choice is a heuristic, so only "better than typical" is asserted)."""
    basis = load_basis(basis_file)
    greedy = condition_number(basis, select_bins(basis, 20, candidates=5000))
    rng = np.random.default_rng(0)
    filled = np.flatnonzero(basis.filled)
    random = [condition_number(basis, rng.choice(filled, 20, replace=False)) for _ in range(20)]
    assert greedy < np.median(random)


def test_directions_file_round_trips(tmp_path, basis_file):
    bins = select_bins(load_basis(basis_file), 8, candidates=2000)
    path = tmp_path / "directions.csv"
    write_directions(bin_angles_degrees(bins), path)
    wi, wo = read_directions(path)
    expected_wi, expected_wo = bin_directions()
    np.testing.assert_allclose(wi, expected_wi[bins], atol=1e-9)  # 10 significant digits of degrees
    np.testing.assert_allclose(wo, expected_wo[bins], atol=1e-9)


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "empty"),
        ("theta_i,phi_i,theta_o\n1,2,3\n", "lacks phi_o"),
        ("theta_i,phi_i,theta_o,phi_o\n1,2,x,4\n", "row 2"),
        ("theta_i,phi_i,theta_o,phi_o\n95,0,10,0\n", r"row 2: zenith angles must lie in \[0, 90\]"),
        ("theta_i,phi_i,theta_o,phi_o\n", "no pairs"),
        ("theta_i,phi_i,theta_o,phi_o\n1,2,3,4,5\n", "row 2: 5 fields"),
    ],
)
def test_bad_directions_files(tmp_path, text, message):
    path = tmp_path / "directions.csv"
    path.write_text(text)
    with pytest.raises(BrdfInputError, match=message):
        read_directions(path)


def test_more_pairs_than_bins(basis_file):
    with pytest.raises(BrdfInputError, match="only"):
        select_bins(load_basis(basis_file), 10, max_theta=0.5)


def test_fewer_candidates_than_pairs(basis_file):
    """Asking for more pairs than candidates is refused (it once repeated a pair to fill the count)."""
    with pytest.raises(BrdfInputError, match="candidates=3"):
        select_bins(load_basis(basis_file), 8, candidates=3)


@pytest.mark.parametrize("angles", [np.zeros((3, 3)), np.array([[100.0, 0, 10, 0]]), np.array([[np.nan, 0, 10, 0]])])
def test_writing_bad_angles(tmp_path, angles):
    with pytest.raises(BrdfInputError, match="angles must"):
        write_directions(angles, tmp_path / "d.csv")
    assert not (tmp_path / "d.csv").exists()
