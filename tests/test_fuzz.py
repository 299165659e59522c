"""A seeded fuzz suite over every reader and every JSON the command line accepts (issue 29's acceptance).

Each reader starts from a valid file (written here) and reads :data:`CASES` mutations of it, each drawn from a
``numpy`` generator seeded by the reader's name and the case's number, so every run reads the same files and a
failure names the case that reproduces it: bytes flipped, the file cut short, a token spliced in (``nan``,
``1e999``, 400 digits, a NUL, an unpaired quote, ...), a slice repeated or removed; for JSON also a value
replaced by another type, a number beyond float64, ``Infinity``, 100,000-deep nesting, a key removed; for a
basis ``.npz`` an array replaced by one of another type or shape. A reader must either return what it promises
(samples with finite, non-negative values and directions above the horizon; a result, a comparison, a basis)
or raise :class:`~brdffit.errors.BrdfInputError` with one line; any other exception is a bug.

:data:`FOUND` keeps the inputs this suite found wrong once, read on every run. Not marked heavy: a few seconds.
"""

import json
import math
import zlib
from pathlib import Path

import numpy as np
import pytest

from brdffit import load_samples
from brdffit.cli.arguments import fit_file, json_argument
from brdffit.data.merl import N_BINS, write_merl_table
from brdffit.datadriven.basis import Basis, load_basis, save_basis
from brdffit.datadriven.directions import read_directions
from brdffit.errors import BrdfInputError
from brdffit.fitting.comparison.compare import Comparison, ModelScore, load_comparison
from brdffit.fitting.single.result import FitResult, load_result
from brdffit.physics.models.registry import model_for

#: Mutated files read per reader (MERL tables are 35 MB each, a basis 1.4 million bins: fewer).
CASES = 60
MERL_CASES = 6
BASIS_CASES = 16
#: What a mutation splices in.
TOKENS = [
    b"nan",
    b"inf",
    b"-inf",
    b"-1",
    b"-0",
    b"1e999",
    b"1e-320",
    b"9" * 400,
    b"\x00",
    b"\xff\xfe",
    b"\xc3",
    "é".encode(),
    b'"',
    b"{",
    b"[",
    b"]",
    b",",
    b"\n",
    b"\r",
    b"#",
    b"0x10",
    b"1_0",
    b" ",
    b"\t",
    b"Infinity",
    b"NaN",
    b"null",
    b"true",
]
#: What a JSON mutation puts in place of a value: ``"__DEEP__"`` becomes 100,000 nested lists, ``"__INFINITY__"``
#: the bare word Infinity, ``"__HUGE__"`` a number beyond float64's range.
REPLACEMENTS = [None, True, "x", "", [], {}, -1, 0, 1e308, 10**30, 2**63, [1, 2], {"a": 1}, "__DEEP__"]
REPLACEMENTS += ["__INFINITY__", "__HUGE__", [None], ["ward"], -1e-300]

SPECIAL = {
    '"__DEEP__"': "[" * 100_000 + "]" * 100_000,
    '"__INFINITY__"': "Infinity",
    '"__HUGE__"': "1e400",
}

WARD = {"rho_d": [0.3, 0.2, 0.1], "rho_s": [0.1, 0.08, 0.05], "alpha": 0.2}

VALID_CSV = (
    "# a run\ntheta_i,phi_i,theta_o,phi_o,r,g,b,sigma,weight\n"
    "10,0,20,90,0.1,0.2,0.3,0.01,1\n30,0,45,180,0.5,0.4,0.3,0.02,2\n60,0,30,0,0.2,0.2,0.2,0.01,1\n"
)
VALID_ALTA = (
    "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n#VS 1\n#CHANNELS value\n"
    "0.2 0 0.4 3.1 0.5 0.01\n0.5 0 0.3 1.0 0.25 0.02\n1.0 0.5 0.2 2.0 0.1 0.01\n"
)
VALID_ASTM = (
    'SOURCE fuzz\nSAMPLE_NAME "krylon blue"\nFORMAT ASTM E1392-96\nNUM_POINTS 3\n'
    "VARS theta_i,phi_i,theta_s,phi_s,R,G,B\n30,0,45,180,0.1,0.2,0.3\n30,0,45,90,0,0,0\n10,0,20,0,0.5,0.5,0.5\n"
)
VALID_DIRECTIONS = "theta_i,phi_i,theta_o,phi_o\n10,0,20,90\n30,0,45,180\n"


def result() -> FitResult:
    return FitResult("ward", {}, ("r", "g", "b"), WARD, "log", 0.5, 0.01, 3, 7, True, warnings=["a warning"])


def valid_comparison() -> str:
    score = ModelScore("ward", 7, 1.0, 2.0, 0.1, 0.01, [0.1, 0.12], result(), [True, True], ["a note"])
    return Comparison("x.csv", 3, ("r", "g", "b"), "log", 2, "random", 0, [score]).to_json()


def rng_of(reader: str, case: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(reader.encode()), case])


def mutate_bytes(data: bytes, rng: np.random.Generator) -> bytes:
    """One of: bytes flipped, cut short, a token spliced in, a slice repeated, a slice removed."""
    data = bytearray(data)
    kind = rng.integers(5)
    at = int(rng.integers(len(data) + 1))
    if kind == 0:
        for _ in range(int(rng.integers(1, 9))):
            data[int(rng.integers(len(data)))] = int(rng.integers(256))
    elif kind == 1:
        del data[at:]
    elif kind == 2:
        data[at:at] = TOKENS[int(rng.integers(len(TOKENS)))]
    else:
        end = min(len(data), at + int(rng.integers(1, 40)))
        data[at:at] = data[at:end] if kind == 3 else b""
        if kind == 4:
            del data[at:end]
    return bytes(data)


def mutate_json(text: str, rng: np.random.Generator) -> bytes:
    """A value of the JSON replaced (or a key removed), else (one case in three) its bytes mutated."""
    if rng.integers(3) == 0:
        return mutate_bytes(text.encode(), rng)
    content = json.loads(text)
    nodes = list(_nodes(content))
    parent, key = nodes[int(rng.integers(len(nodes)))]
    if isinstance(parent, dict) and rng.integers(4) == 0:
        del parent[key]
    else:
        parent[key] = REPLACEMENTS[int(rng.integers(len(REPLACEMENTS)))]
    out = json.dumps(content)
    for placeholder, replacement in SPECIAL.items():
        out = out.replace(placeholder, replacement)
    return out.encode()


def _nodes(value, parent=None, key=None):
    """``(parent, key)`` of every value below the top."""
    if parent is not None:
        yield parent, key
    children = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for child_key, child in list(children):
        yield from _nodes(child, value, child_key)


# ---------------------------------------------------------------------- what each reader must give
def check_samples(samples) -> None:
    assert samples.n_samples > 0
    assert np.all(np.isfinite(samples.values)) and np.all(samples.values >= 0)
    assert np.all(samples.wi[:, 2] > 0) and np.all(samples.wo[:, 2] > 0)
    assert np.allclose(np.linalg.norm(samples.wi, axis=1), 1.0) and np.allclose(np.linalg.norm(samples.wo, axis=1), 1)
    if samples.sigma is not None:
        assert np.all(np.isfinite(samples.sigma)) and np.all(samples.sigma > 0)


def read_csv(path):
    check_samples(load_samples(path, format="csv"))


def read_alta(path):
    check_samples(load_samples(path, format="alta"))


def read_astm(path):
    check_samples(load_samples(path, format="astm"))


def read_merl(path):
    check_samples(load_samples(path, format="merl", subsample=1000))


def read_directions_file(path):
    wi, wo = read_directions(path)
    assert np.all(np.isfinite(wi)) and np.all(np.isfinite(wo))


def read_result(path):
    assert isinstance(load_result(path), FitResult)
    assert isinstance(fit_file(str(path)), FitResult)


def read_comparison(path):
    """As ``compare``'s readers and as ``export``/``render`` read a fit file (a comparison's best fit)."""
    assert isinstance(load_comparison(path), Comparison)
    assert isinstance(fit_file(str(path)), FitResult)


def read_params(path):
    """``synth --params`` / ``fit --start``: JSON, then the model's parameters checked."""
    params = json_argument(str(path), "--params")
    model_for("ward", params)


def read_basis(path):
    assert isinstance(load_basis(path), Basis)


def one_line(reader, path: Path, description: str) -> None:
    try:
        reader(path)
    except BrdfInputError as error:
        assert "\n" not in str(error), f"{description}: a message of several lines: {error}"
    except Exception as error:
        raise AssertionError(f"{description}: {type(error).__name__}: {error}"[:2000]) from error


# ---------------------------------------------------------------------- the text and JSON readers
TEXT_READERS = {
    "csv": (read_csv, VALID_CSV, "samples.csv", mutate_bytes),
    "alta": (read_alta, VALID_ALTA, "samples.dat", mutate_bytes),
    "astm": (read_astm, VALID_ASTM, "samples.astm", mutate_bytes),
    "directions": (read_directions_file, VALID_DIRECTIONS, "directions.csv", mutate_bytes),
    "result": (read_result, result().to_json(), "result.json", mutate_json),
    "comparison": (read_comparison, valid_comparison(), "comparison.json", mutate_json),
    "params": (read_params, json.dumps(WARD), "params.json", mutate_json),
}

#: Inputs found wrong once (reader, bytes, what it was): read on every run.
FOUND: list[tuple[str, bytes, str]] = [
    # read_directions decoded with Path.read_text: a UnicodeDecodeError escaped (directions case 0).
    ("directions", b"theta_i,phi_i,theta_o,phi_o\n10,0,\xbf0,90\n", "not UTF-8"),
    # csv.Error escaped read_directions: a field beyond csv's 128 KiB limit; a bare carriage return inside a row
    # once the file was decoded without universal newlines (directions case 284, while fixing the case above).
    ("directions", b"theta_i,phi_i,theta_o,phi_o\n10,0,20,90\n30,0,\r45,180\n", "a bare carriage return"),
    ("directions", b"theta_i,phi_i,theta_o,phi_o\n10,0,20," + b"9" * 200_000 + b"\n", "a field of 200,000 digits"),
    # A comparison of no models loaded; export and render then asked for its best: IndexError (comparison case 39).
    ("comparison", json.dumps({**json.loads(valid_comparison()), "models": []}).encode(), "no models"),
]


@pytest.mark.parametrize("reader", sorted(TEXT_READERS))
def test_the_valid_file_reads(reader, tmp_path):
    function, valid, name, _ = TEXT_READERS[reader]
    path = tmp_path / name
    path.write_text(valid)
    function(path)


@pytest.mark.parametrize("reader", sorted(TEXT_READERS))
def test_mutated_files_read_or_fail_in_one_line(reader, tmp_path):
    function, valid, name, mutate = TEXT_READERS[reader]
    path = tmp_path / name
    for case in range(CASES):
        path.write_bytes(mutate(valid if mutate is mutate_json else valid.encode(), rng_of(reader, case)))
        one_line(function, path, f"{reader} case {case}")


@pytest.mark.parametrize("index", range(len(FOUND)), ids=[f"{reader}:{why}" for reader, _, why in FOUND])
def test_what_the_fuzz_found_once(index, tmp_path):
    reader, data, why = FOUND[index]
    function, _, name, _ = TEXT_READERS[reader]
    path = tmp_path / name
    path.write_bytes(data)
    one_line(function, path, why)


# ---------------------------------------------------------------------- MERL and basis files (binary)
@pytest.fixture(scope="module")
def merl_bytes(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("merl") / "grey.binary"
    write_merl_table(np.full((N_BINS, 3), 0.2), path)
    return path.read_bytes()


def test_mutated_merl_tables_read_or_fail_in_one_line(merl_bytes, tmp_path):
    """Mutations near the header (the dimensions) and anywhere in the table (a NaN, a huge value, bytes cut)."""
    path = tmp_path / "table.binary"
    for case in range(MERL_CASES):
        rng = rng_of("merl", case)
        data = bytearray(merl_bytes)
        kind = case % 3
        if kind == 0:  # the header: three int32 dimensions
            data[int(rng.integers(12))] = int(rng.integers(256))
        elif kind == 1:  # a value: NaN, infinity, a huge or negative number
            at = 12 + 8 * int(rng.integers(N_BINS * 3))
            data[at : at + 8] = np.float64(rng.choice([math.nan, math.inf, 1e308, -1.0])).tobytes()
        else:
            del data[int(rng.integers(len(data))) :]
        path.write_bytes(bytes(data))
        one_line(read_merl, path, f"merl case {case}")


def basis_arrays() -> dict:
    """A one-component basis over MERL's bins (zeros: small once compressed)."""
    return dict(
        kind=np.array("brdffit-pca-basis"),
        version=np.array(1),
        mapping=np.array("log-relative"),
        mean=np.zeros(N_BINS),
        reference=np.ones(N_BINS),
        components=np.zeros((1, N_BINS), dtype=np.float32),
        filled=np.ones(N_BINS, dtype=bool),
        explained=np.array([1.0]),
        materials=np.array(["a.binary"]),
    )


ARRAY_REPLACEMENTS = [
    np.array("x"),
    np.array(3),
    np.array([]),
    np.zeros(5),
    np.full(N_BINS, np.nan),
    np.zeros((2, 3, 4)),
    np.array([1, 2], dtype=np.int8),
    np.array(["a", "b"]),
    np.ones(N_BINS, dtype=np.int64),
]


def test_the_valid_basis_reads(tmp_path):
    path = tmp_path / "basis.npz"
    np.savez_compressed(path, **basis_arrays())
    read_basis(path)


def test_mutated_basis_files_read_or_fail_in_one_line(tmp_path):
    """An array replaced by one of another type or shape, or the archive's bytes mutated."""
    path = tmp_path / "basis.npz"
    np.savez_compressed(path, **basis_arrays())
    valid = path.read_bytes()
    for case in range(BASIS_CASES):
        rng = rng_of("basis", case)
        if case % 2:
            path.write_bytes(mutate_bytes(valid, rng))
        else:
            arrays = basis_arrays()
            names = sorted(arrays)
            arrays[names[int(rng.integers(len(names)))]] = ARRAY_REPLACEMENTS[
                int(rng.integers(len(ARRAY_REPLACEMENTS)))
            ]
            with path.open("wb") as handle:
                np.savez_compressed(handle, **arrays)
        one_line(read_basis, path, f"basis case {case}")


def test_a_saved_basis_reads(tmp_path):
    """The fixture's arrays are a basis as ``save_basis`` writes it (the suite fuzzes the real layout)."""
    arrays = basis_arrays()
    basis = Basis(
        str(arrays["mapping"]),
        arrays["mean"],
        arrays["reference"],
        arrays["components"],
        arrays["filled"],
        arrays["explained"],
        ("a.binary",),
    )
    save_basis(basis, tmp_path / "saved.npz")
    assert load_basis(tmp_path / "saved.npz").n_components == 1


def test_what_the_fuzz_found_once_in_basis_files(tmp_path):
    """A member whose deflate stream is corrupt raised zlib.error (basis case 35); a 0-d ``materials`` array a
    TypeError (basis case 112)."""
    import zipfile

    path = tmp_path / "basis.npz"
    np.savez_compressed(path, **basis_arrays())
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        member = archive.getinfo("mean.npy")
    start = member.header_offset + 30 + len(member.filename.encode()) + len(member.extra)
    data[start] = 0xFF  # the first deflate block's type: 3, which does not exist
    path.write_bytes(bytes(data))
    one_line(read_basis, path, "a corrupt deflate stream")
    np.savez_compressed(path, **{**basis_arrays(), "materials": np.array("a.binary")})
    one_line(read_basis, path, "materials a 0-d array")
