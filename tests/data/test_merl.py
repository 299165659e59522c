"""MERL ``.binary`` reader and writer (Matusik et al. 2003; Rusinkiewicz 1998 half/difference angles).

The geometry is checked against an implementation, written here and independent of the module's, of
MERL's ``std_coords_to_half_diff_coords`` (``BRDFRead.cpp``): rotate ``wi`` by ``-φh`` about the normal
and by ``-θh`` about the binormal to get the difference vector.
"""

import math
import struct
import time
from pathlib import Path

import numpy as np
import pytest
from catalogue import CASES
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import brdffit
from brdffit.data.merl import bin_directions, read_merl, write_merl_table
from brdffit.errors import BrdfInputError
from brdffit.export.merl import write_merl

SHAPE = (90, 90, 180)
N_BINS = 90 * 90 * 180
FILE_BYTES = 12 + 3 * N_BINS * 8
SCALES = np.array([1.0, 1.15, 1.66]) / 1500.0
WARD = CASES[1][2]  # pickled oak (Ngan et al. 2005)


# ---------------------------------------------------------------------- independent helpers
def merl_bytes(stored: np.ndarray, dims=SHAPE) -> bytes:
    """A MERL file built by hand: ``stored`` (3, N) numbers as written, R then G then B."""
    return struct.pack("<3i", *dims) + np.asarray(stored, dtype="<f8").tobytes()


def grid_angles():
    """(θh, θd, φd) radians and the (i, j, k) indices of every bin, flat in file order (``BRDFRead.cpp``)."""
    i, j, k = (a.reshape(-1) for a in np.meshgrid(*(np.arange(n) for n in SHAPE), indexing="ij"))
    return (i / 90) ** 2 * (math.pi / 2), j / 90 * (math.pi / 2), k / 180 * math.pi, (i, j, k)


def rotate(v, axis, angle):
    """Rodrigues' rotation of the vectors ``v`` (N, 3) by ``angle`` (N,) about the unit ``axis`` (as MERL)."""
    axis = np.asarray(axis, dtype=float)
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return v * cos + axis * (v @ axis)[:, None] * (1 - cos) + np.cross(axis, v) * sin


def std_to_half_diff(wi, wo):
    """``(θh, φh, θd, φd)`` of direction pairs, as MERL's ``std_coords_to_half_diff_coords``."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    theta_h = np.arctan2(np.hypot(h[:, 0], h[:, 1]), h[:, 2])
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    diff = rotate(rotate(wi, [0, 0, 1], -phi_h), [0, 1, 0], -theta_h)
    theta_d = np.arctan2(np.hypot(diff[:, 0], diff[:, 1]), diff[:, 2])
    phi_d = np.arctan2(diff[:, 1], diff[:, 0])
    return theta_h, phi_h, theta_d, phi_d


def expected_valid_bins() -> np.ndarray:
    """Bins whose light and viewer are both above the horizon, from the closed form of their z components.

    ``z = cos θh cos θd ∓ sin θh sin θd cos φd``; bins with ``θh + θd = 90°`` at ``φd = 0``
    (``i² + 90 j = 8100``, ``k = 0``) lie exactly on the horizon and are not valid.
    """
    theta_h, theta_d, phi_d, (i, j, k) = grid_angles()
    lowest_z = np.cos(theta_h) * np.cos(theta_d) - np.sin(theta_h) * np.sin(theta_d) * np.abs(np.cos(phi_d))
    on_horizon = (k == 0) & (i**2 + 90 * j == 8100)
    return (lowest_z > 0) & ~on_horizon


def one_line_error(call, *fragments):
    with pytest.raises(BrdfInputError) as caught:
        call()
    message = str(caught.value)
    assert type(caught.value) is BrdfInputError
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message
    return message


# ---------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("merl")


@pytest.fixture(scope="module")
def ward_file(folder) -> Path:
    path = folder / "ward.binary"
    write_merl("ward", WARD, path)
    return path


@pytest.fixture(scope="module")
def ward_full(ward_file):
    start = time.perf_counter()
    samples = read_merl(ward_file)
    seconds = time.perf_counter() - start
    print(f"\nread_merl: full {FILE_BYTES:,}-byte file, {samples.n_samples:,} samples in {seconds:.3f} s")
    return samples


@pytest.fixture(scope="module")
def index_file(folder) -> Path:
    """A file built by hand whose stored r, g, b are the bin's indices i (θh), j (θd), k (φd)."""
    _, _, _, ijk = grid_angles()
    path = folder / "index.binary"
    path.write_bytes(merl_bytes(np.stack(ijk).astype(float)))
    return path


# ---------------------------------------------------------------------- acceptance: round trip
def test_round_trip_of_a_ward_material_fits_back_its_parameters(ward_file):
    samples = read_merl(ward_file, subsample=20000, seed=0)
    assert samples.n_samples == 20000
    assert samples.channels == ("r", "g", "b")
    result = brdffit.fit(samples, "ward")
    for name, truth in WARD.items():
        np.testing.assert_allclose(result.params[name], truth, rtol=0.03, err_msg=name)


def test_full_read_holds_every_valid_bin_with_the_model_values(ward_file, ward_full):
    assert ward_full.n_samples == int(expected_valid_bins().sum()) == 1_111_430
    assert ward_full.source == str(ward_file)
    assert np.all(ward_full.wi[:, 2] > 0) and np.all(ward_full.wo[:, 2] > 0)
    # float64 stored, scaled by 1/scale then ×scale: the values come back to rounding.
    pick = np.random.default_rng(1).choice(ward_full.n_samples, 5000, replace=False)
    expected = brdffit.evaluate("ward", WARD, ward_full.wi[pick], ward_full.wo[pick])
    np.testing.assert_allclose(ward_full.values[pick], expected, rtol=1e-13)


def test_writer_lays_out_header_and_planes_as_the_format(folder):
    rng = np.random.default_rng(3)
    values = rng.random((N_BINS, 3))
    values[rng.random(N_BINS) < 0.01] = -1.0  # missing bins
    path = folder / "values.binary"
    write_merl_table(values.reshape(*SHAPE, 3), path)
    assert path.read_bytes() == merl_bytes((values / SCALES).T)
    assert not [p for p in folder.iterdir() if p.name.startswith(".values.")]  # no temporary left behind


# ---------------------------------------------------------------------- coordinates
def test_each_sample_converts_back_to_its_bin(index_file):
    samples = read_merl(index_file)
    i, j, k = (np.rint(samples.values / SCALES).astype(int)).T  # the stored indices of each sample's bin
    assert samples.n_samples == int(expected_valid_bins().sum())
    theta_h, phi_h, theta_d, phi_d = std_to_half_diff(samples.wi, samples.wo)
    np.testing.assert_allclose(phi_h, 0.0, atol=1e-9)  # 0 up to Samples' renormalisation
    np.testing.assert_allclose(theta_h, (i / 90) ** 2 * (math.pi / 2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(theta_d, j / 90 * (math.pi / 2), rtol=0, atol=1e-9)
    # φd is defined where θd > 0, and only modulo π (reciprocity; MERL folds it into [0, π)).
    defined = j > 0
    offset = np.mod(phi_d[defined] - k[defined] / 180 * math.pi, math.pi)
    assert np.max(np.minimum(offset, math.pi - offset)) < 1e-9
    # Nearest bin of each converted pair is the bin itself (rounding MERL's index mappings).
    assert np.array_equal(np.rint(90 * np.sqrt(theta_h / (math.pi / 2))).astype(int), i)
    assert np.array_equal(np.rint(theta_d / (math.pi / 2) * 90).astype(int), j)
    folded = np.rint(np.mod(phi_d[defined], math.pi) / math.pi * 180).astype(int) % 180
    assert np.array_equal(folded, k[defined])


@pytest.mark.parametrize(
    ("ijk", "wi", "wo"),
    [
        ((0, 0, 0), (0, 0, 1), (0, 0, 1)),  # θh = θd = 0: both along the normal
        ((0, 30, 0), (0.5, 0, math.sqrt(3) / 2), (-0.5, 0, math.sqrt(3) / 2)),  # θd = 30°, φd = 0
        ((0, 30, 90), (0, 0.5, math.sqrt(3) / 2), (0, -0.5, math.sqrt(3) / 2)),  # θd = 30°, φd = 90°
        ((30, 0, 0), (math.sin(math.radians(10)), 0, math.cos(math.radians(10))), None),  # θh = 10°: mirror pair
        (
            (30, 30, 0),  # θh = 10°, θd = 30°, φd = 0: wi at 40°, wo at -20° in the x-z plane
            (math.sin(math.radians(40)), 0, math.cos(math.radians(40))),
            (-math.sin(math.radians(20)), 0, math.cos(math.radians(20))),
        ),
    ],
)
def test_directions_worked_by_hand(ijk, wi, wo):
    wi_all, wo_all = bin_directions()
    flat = np.ravel_multi_index(ijk, SHAPE)
    np.testing.assert_allclose(wi_all[flat], wi, atol=1e-15)
    np.testing.assert_allclose(wo_all[flat], wi if wo is None else wo, atol=1e-15)


def test_bins_exactly_on_the_horizon_are_dropped(index_file):
    samples = read_merl(index_file)
    flat = np.ravel_multi_index(tuple(np.rint(samples.values / SCALES).astype(int).T), SHAPE)
    read = np.zeros(N_BINS, dtype=bool)
    read[flat] = True
    assert read[np.ravel_multi_index((29, 80, 0), SHAPE)] and not read[np.ravel_multi_index((31, 80, 0), SHAPE)]
    for on_horizon in [(30, 80, 0), (60, 50, 0)]:  # θh + θd = 90° at φd = 0
        assert not read[np.ravel_multi_index(on_horizon, SHAPE)]


def test_missing_bins_are_skipped(folder):
    stored = np.ones((3, N_BINS))
    stored[1, 0] = -1.0  # green missing at (0, 0, 0)
    stored[2, 1] = -0.5  # blue missing at (0, 0, 1)
    path = folder / "missing.binary"
    path.write_bytes(merl_bytes(stored))
    samples = read_merl(path)
    assert samples.n_samples == int(expected_valid_bins().sum()) - 2
    np.testing.assert_allclose(samples.values[0], SCALES)  # first valid bin is (0, 0, 2)


# ---------------------------------------------------------------------- selection
def test_max_theta_keeps_exactly_the_samples_within_it(ward_file, ward_full):
    kept = read_merl(ward_file, max_theta=60)
    expected = ward_full.within(60)
    assert 0 < kept.n_samples == expected.n_samples < ward_full.n_samples
    np.testing.assert_array_equal(kept.wi, expected.wi)
    np.testing.assert_array_equal(kept.values, expected.values)
    assert kept.theta_i.max() <= 60 and kept.theta_o.max() <= 60
    assert read_merl(ward_file, max_theta=90).n_samples == ward_full.n_samples


def test_random_subsample_is_a_seeded_subset(index_file):
    first = read_merl(index_file, subsample=1000, seed=4)
    again = read_merl(index_file, subsample=1000, seed=4)
    other = read_merl(index_file, subsample=1000, seed=5)
    np.testing.assert_array_equal(first.wi, again.wi)
    assert not np.array_equal(first.wi, other.wi)
    flat = np.ravel_multi_index(tuple(np.rint(first.values / SCALES).astype(int).T), SHAPE)
    assert np.unique(flat).size == 1000  # without replacement
    assert np.all(expected_valid_bins()[flat])
    np.testing.assert_allclose(first.wi, bin_directions()[0][flat], rtol=0, atol=1e-15)


def test_stratified_subsample_takes_an_equal_share_of_each_theta_h_bin(index_file):
    def theta_h_bins(samples):
        return np.rint(samples.values[:, 0] / SCALES[0]).astype(int)

    first = read_merl(index_file, subsample=9000, subsample_method="stratified", seed=1)
    again = read_merl(index_file, subsample=9000, subsample_method="stratified", seed=1)
    other = read_merl(index_file, subsample=9000, subsample_method="stratified", seed=2)
    assert first.n_samples == 9000
    np.testing.assert_array_equal(first.wi, again.wi)
    np.testing.assert_array_equal(first.values, again.values)
    assert not np.array_equal(first.values, other.values)
    counts = np.bincount(theta_h_bins(first), minlength=90)
    assert counts.max() - counts.min() <= 1  # every θh bin has > 100 valid samples
    assert len({tuple(row) for row in first.values}) == 9000  # no bin twice

    # Where a θh bin has too few valid samples, it gives all it has and the others make up the count.
    valid_per_bin = np.bincount(grid_angles()[3][0][expected_valid_bins()], minlength=90)
    total = 90 * 2000
    few = read_merl(index_file, subsample=total, subsample_method="stratified", seed=1)
    counts = np.bincount(theta_h_bins(few), minlength=90)
    short = valid_per_bin < total // 90
    assert np.any(short)
    np.testing.assert_array_equal(counts[short], valid_per_bin[short])
    assert counts.sum() == total and counts[~short].max() - counts[~short].min() <= 1


# ---------------------------------------------------------------------- errors
def test_file_errors(folder, ward_file):
    truncated = folder / "truncated.binary"
    truncated.write_bytes(ward_file.read_bytes()[:1000])
    one_line_error(lambda: read_merl(truncated), str(truncated), "holds 1,000 bytes", "needs 34,992,012")
    longer = folder / "longer.binary"
    longer.write_bytes(ward_file.read_bytes() + b"\0")
    one_line_error(lambda: read_merl(longer), "holds 34,992,013 bytes", "needs 34,992,012")
    dims = folder / "dims.binary"
    dims.write_bytes(struct.pack("<3i", 90, 90, 360) + bytes(64))
    one_line_error(lambda: read_merl(dims), str(dims), "dimensions (90, 90, 360), expected (90, 90, 180)")
    short = folder / "short.binary"
    short.write_bytes(b"\x5a\0\0\0")
    one_line_error(lambda: read_merl(short), str(short), "holds 4 bytes", "header")
    missing = folder / "nowhere.binary"
    one_line_error(lambda: read_merl(missing), str(missing), "no such file")
    one_line_error(lambda: read_merl(folder), str(folder), "folder")


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_stored_values_are_rejected(folder, bad):
    stored = np.ones((3, N_BINS))
    stored[2, np.ravel_multi_index((1, 2, 3), SHAPE)] = bad
    path = folder / "nonfinite.binary"
    path.write_bytes(merl_bytes(stored))
    one_line_error(lambda: read_merl(path), str(path), "channel b", "(θh 1, θd 2, φd 3)", "finite")


def test_no_valid_sample_is_an_error(folder, index_file):
    path = folder / "empty.binary"
    path.write_bytes(merl_bytes(-np.ones((3, N_BINS))))
    one_line_error(lambda: read_merl(path), str(path), "no valid sample")
    stored = np.ones((3, N_BINS))
    stored[:, : 90 * 180] = -1  # only θh bin 0 is missing; every other bin has θh ≥ 0.011°
    path.write_bytes(merl_bytes(stored))
    one_line_error(lambda: read_merl(path, max_theta=0.001), str(path), "no valid sample", "max_theta=0.001")


@pytest.mark.parametrize(
    ("options", "fragment"),
    [
        ({"subsample": 0}, "subsample=0 is not allowed; give a whole number ≥ 1"),
        ({"subsample": -5}, "subsample=-5"),
        ({"subsample": 2.5}, "subsample=2.5"),
        ({"subsample": "100"}, "subsample='100'"),
        ({"subsample": True}, "subsample=True"),
        ({"subsample": 100, "subsample_method": "grid"}, "subsample_method='grid' is not allowed"),
        ({"max_theta": 0}, "max_theta=0 is not allowed; give degrees in (0, 90]"),
        ({"max_theta": -10}, "max_theta=-10"),
        ({"max_theta": 90.5}, "max_theta=90.5"),
        ({"max_theta": math.nan}, "max_theta=nan"),
        ({"max_theta": "60"}, "max_theta='60'"),
        ({"seed": -1}, "seed=-1"),
    ],
)
def test_bad_options_are_rejected(ward_file, options, fragment):
    one_line_error(lambda: read_merl(ward_file, **options), fragment)


def test_subsample_larger_than_available_names_both_counts(ward_file):
    one_line_error(
        lambda: read_merl(ward_file, max_theta=10, subsample=10**6),
        str(ward_file),
        "subsample=1,000,000 is more than the ",
        " valid samples",
    )
    assert read_merl(ward_file, subsample=2000.0, subsample_method="stratified").n_samples == 2000
    every = read_merl(ward_file, max_theta=5)
    for method in ("random", "stratified"):  # asking for all of them gives all of them
        kept = read_merl(ward_file, max_theta=5, subsample=every.n_samples, subsample_method=method)
        np.testing.assert_array_equal(kept.wi, every.wi)


def test_writer_errors(folder):
    path = folder / "written.binary"
    values = np.zeros((N_BINS, 3))
    values[7, 1] = math.nan
    one_line_error(lambda: write_merl_table(values, path), str(path), "NaN or infinity")
    one_line_error(lambda: write_merl_table(np.zeros((10, 3)), path), str(path), "shape")
    one_line_error(lambda: write_merl_table(np.zeros((N_BINS, 3)), folder / "no" / "such.binary"), "cannot be written")
    assert not path.exists()


# ---------------------------------------------------------------------- fuzzing
HEADERS = st.one_of(
    st.just(struct.pack("<3i", *SHAPE)),
    st.tuples(*[st.integers(-(2**31), 2**31 - 1)] * 3).map(lambda dims: struct.pack("<3i", *dims)),
    st.tuples(*[st.sampled_from([0, 1, 90, 180, 360, 2**31 - 1])] * 3).map(lambda dims: struct.pack("<3i", *dims)),
    st.just(struct.pack(">3i", *SHAPE)),  # big-endian
)


@settings(max_examples=200, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    content=st.one_of(
        st.binary(max_size=64),
        st.tuples(HEADERS, st.binary(max_size=256)).map(lambda parts: parts[0] + parts[1]),
        st.tuples(HEADERS, st.integers(0, 12)).map(lambda parts: parts[0][: parts[1]]),
    ),
    options=st.fixed_dictionaries(
        {},
        optional={
            "max_theta": st.one_of(st.floats(allow_nan=True), st.integers(-100, 100)),
            "subsample": st.one_of(st.integers(-3, 10**7), st.floats()),
            "subsample_method": st.sampled_from(["random", "stratified", "other"]),
        },
    ),
)
def test_fuzzed_small_files_raise_only_brdf_input_error(folder, content, options):
    path = folder / "fuzz.binary"
    path.write_bytes(content)
    with pytest.raises(BrdfInputError) as caught:
        read_merl(path, **options)
    assert "\n" not in str(caught.value)
