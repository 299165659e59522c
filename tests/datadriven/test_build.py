"""The basis learned from a library: exact on a library of known rank, the streamed build against a direct SVD,
the basis file and its errors."""

import numpy as np
import pytest

from brdffit.data.merl import SCALES, read_merl, stored_planes
from brdffit.datadriven.basis import bin_cosine_weights, horizon_filled, load_basis, save_basis
from brdffit.datadriven.build import build_basis
from brdffit.datadriven.mapping import mapped
from brdffit.errors import BrdfInputError


def test_a_rank_two_library_has_two_components(linear_library):
    """Mixtures of two grey tables in the ``none`` mapping: the centred library has rank ≤ 2, so two components
    explain it all (1e-10: rounding of the Gram matrix), and a third, which would be rounding, is refused."""
    paths, _, _ = linear_library
    basis = build_basis(paths, components=2, mapping="none")
    assert basis.explained.sum() == pytest.approx(1.0, abs=1e-10)
    with pytest.raises(BrdfInputError, match="span only 2 direction"):
        build_basis(paths, components=3, mapping="none")


@pytest.mark.slow
def test_streamed_build_matches_a_direct_svd(library):
    """The two-pass Gram build gives the variances and the subspace of numpy's SVD of the whole mapped library
    (both exact: 1e-9 relative, the Gram matrix squares the condition of the smallest kept component)."""
    paths = library[0][:4]
    basis = build_basis(paths, components=4)
    filled = horizon_filled()
    rho = np.concatenate([np.asarray(stored_planes(p)) * SCALES[:, None] for p in paths])[:, filled]
    reference = np.median(rho, axis=0)
    x = mapped("log-relative", rho, reference, bin_cosine_weights()[filled])
    centred = x - x.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    variance = singular**2 / np.sum(singular**2)
    np.testing.assert_allclose(basis.explained, variance[:4], rtol=1e-9)
    np.testing.assert_allclose(basis.reference[filled], reference, rtol=1e-12)
    # The components span the library: projecting the centred library on them leaves what the rest explains.
    components = basis.components[:, filled].astype(np.float64)
    q, _ = np.linalg.qr(components.T)
    leftover = centred - (centred @ q) @ q.T
    assert np.sum(leftover**2) / np.sum(centred**2) == pytest.approx(1 - variance[:4].sum(), abs=1e-6)


def test_library_coefficients_have_unit_variance(library):
    """Components are scaled so that the library's coefficients along each have variance 1 (float32 storage:
    1e-6)."""
    paths = library[0][:4]
    basis = build_basis(paths, components=3)
    filled = basis.filled
    rho = np.concatenate([np.asarray(stored_planes(p)) * SCALES[:, None] for p in paths])[:, filled]
    x = mapped("log-relative", rho, basis.reference[filled], bin_cosine_weights()[filled]) - basis.mean[filled]
    components = basis.components[:, filled].astype(np.float64)
    coefficients = np.linalg.lstsq(components.T, x.T, rcond=None)[0]
    np.testing.assert_allclose(np.var(coefficients, axis=1, ddof=1), 1.0, rtol=1e-5)


def test_missing_bins_take_the_median(library, tmp_path):
    """A table that lacks bins (stored value < 0) still builds; a bin every table lacks is empty."""
    table = np.asarray(stored_planes(library[0][0])).copy()
    table[:, 1000:1010] = -1.0
    header = np.array([90, 90, 180], dtype="<i4").tobytes()
    holed = tmp_path / "holed.binary"
    holed.write_bytes(header + table.astype("<f8").tobytes())
    others = library[0][1:3]
    basis = build_basis([holed, *others], components=2)
    assert np.all(np.isfinite(basis.components))
    lacking = tmp_path / "lacking.binary"
    table[:, 2000:2005] = -1.0
    lacking.write_bytes(header + table.astype("<f8").tobytes())
    every = build_basis([lacking, lacking], components=1)
    above = horizon_filled()
    assert not every.filled[2000:2005][above[2000:2005]].any()


def test_the_file_round_trips(basis_file, tmp_path):
    basis = load_basis(basis_file)
    copy = tmp_path / "copy.npz"
    save_basis(basis, copy)
    again = load_basis(copy)
    np.testing.assert_array_equal(again.components, basis.components)
    np.testing.assert_array_equal(again.mean, basis.mean)
    assert again.mapping == basis.mapping and again.materials == basis.materials
    assert len(again.digest) == 64


@pytest.mark.parametrize(
    "content, message",
    [
        (b"not a zip", "not a basis file"),
        (None, "not a basis file"),  # an npz of something else
    ],
)
def test_files_that_are_not_bases(tmp_path, content, message):
    path = tmp_path / "other.npz"
    if content is None:
        np.savez(path, values=np.zeros(3))
    else:
        path.write_bytes(content)
    with pytest.raises(BrdfInputError, match=message):
        load_basis(path)


def test_missing_basis_file(tmp_path):
    with pytest.raises(BrdfInputError, match="no such file"):
        load_basis(tmp_path / "absent.npz")


@pytest.mark.parametrize(
    "arguments, message",
    [
        ({"components": 0}, "whole number"),
        ({"components": 100}, "at most"),
        ({"mapping": "sqrt"}, "not a mapping"),
    ],
)
def test_build_errors(library, arguments, message):
    with pytest.raises(BrdfInputError, match=message):
        build_basis(library[0][:2], **arguments)


def test_one_path_is_not_a_library(library):
    with pytest.raises(BrdfInputError, match="a list of MERL files"):
        build_basis(str(library[0][0]))


def test_a_file_that_is_not_merl(tmp_path, library):
    bad = tmp_path / "bad.binary"
    bad.write_bytes(b"\x00" * 100)
    with pytest.raises(BrdfInputError, match=r"bad\.binary"):
        build_basis([library[0][0], bad])


def test_library_reads_as_merl(library):
    """The fixture's tables are MERL files the reader takes (the library is made with brdffit's writer)."""
    assert read_merl(library[0][0], subsample=10).n_samples == 10


def test_a_malformed_basis_file_is_one_line(tmp_path, basis_file):
    with np.load(basis_file) as stored:
        arrays = {name: stored[name] for name in stored.files}
    for name, value, message in [
        ("version", np.array("one"), "basis version"),
        ("explained", np.zeros(2), "explained has shape"),
        ("reference", -arrays["reference"] - 1, "negative"),
    ]:
        path = tmp_path / f"{name}.npz"
        np.savez(path, **{**arrays, name: value})
        with pytest.raises(BrdfInputError, match=message):
            load_basis(path)
