"""ASTM E1392 text files (brdffit/data/astm.py): reading by hand, units, round trip, errors, fuzzing."""

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import random_directions
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brdffit.data.astm import read_astm, write_astm
from brdffit.data.samples import Samples
from brdffit.errors import BrdfInputError

S30, C30 = math.sin(math.radians(30)), math.cos(math.radians(30))
S45, C45 = math.sin(math.radians(45)), math.cos(math.radians(45))
VARS = "VARS theta_i,phi_i,theta_s,phi_s,R,G,B\n"


def astm_file(tmp_path, body: str, name: str = "data.astm") -> Path:
    path = tmp_path / name
    path.write_text(body, encoding="utf-8")
    return path


def cornell(rows: list[str], vars_line: str = VARS, count: int | None = None) -> str:
    return (
        "SOURCE Cornell University Program of Computer Graphics\n"
        'SAMPLE_NAME "krylon blue"\n'
        "FORMAT ASTM E1392-96\n"
        f"NUM_POINTS {len(rows) if count is None else count}\n" + vars_line + "".join(r + "\n" for r in rows)
    )


# ---------------------------------------------------------------------- reading
def test_degrees_by_hand(tmp_path):
    """θi = 30°, φi = 0; viewer at θs = 45° on the far side (φs = 180°) and at φs = 90°."""
    path = astm_file(tmp_path, cornell(["30,0,45,180,0.1,0.2,0.3", "30, 0, 45, 90, 0, 0, 0"]))
    samples = read_astm(path)
    np.testing.assert_allclose(samples.wi, [[S30, 0, C30]] * 2, atol=1e-15)
    np.testing.assert_allclose(samples.wo, [[-S45, 0, C45], [0, S45, C45]], atol=1e-15)
    assert samples.values.tolist() == [[0.1, 0.2, 0.3], [0, 0, 0]]
    assert samples.channels == ("r", "g", "b") and samples.source == str(path)


def test_radians_when_every_angle_is_within_two_pi(tmp_path):
    """Cornell's files hold radians (libbsdf and the RIT parser read them so): 0.5236 rad is 30°."""
    rows = [f"{math.radians(30)!r},0,{math.radians(45)!r},{math.pi!r},0.1,0.2,0.3"]
    samples = read_astm(astm_file(tmp_path, cornell(rows)))
    np.testing.assert_allclose(samples.wi, [[S30, 0, C30]], atol=1e-15)
    np.testing.assert_allclose(samples.wo, [[-S45, 0, C45]], atol=1e-15)
    # One angle beyond 2π makes the whole file degrees: 1 and 2 are then 1° and 2°.
    samples = read_astm(astm_file(tmp_path, cornell(["1,0,2,180,0.1,0.2,0.3", "1,0,2,0,0.1,0.2,0.3"])))
    np.testing.assert_allclose(samples.theta_i, [1, 1])
    np.testing.assert_allclose(samples.theta_o, [2, 2])


def test_one_row_in_degrees_among_radians_is_refused_as_mixed(tmp_path):
    """A degree-valued row among radians once turned the whole file into degrees silently: it is named instead."""
    radian_rows = [f"{math.radians(30)!r},0,{math.radians(5 * k)!r},{math.pi!r},0.1,0.2,0.3" for k in range(20)]
    rows = [*radian_rows[:7], "30,0,45,180,0.1,0.2,0.3", *radian_rows[7:]]
    with pytest.raises(BrdfInputError, match=r"line 13: an angle beyond ±2π .* the units are mixed"):
        read_astm(astm_file(tmp_path, cornell(rows)))


def test_tolerant_layout(tmp_path):
    """Keywords in any case, unknown keywords, blank and # lines, tabs, white-space cells, columns in any order."""
    body = (
        "\n# written by hand\nsource somewhere\nnum_points\t2\nSOMETHING else entirely\n"
        "vars\tR,phi_s,theta_s,G,theta_i,phi_i,B\n\n"
        "0.1 180 45 0.2 30 0 0.3\n\n0.1\t90\t45\t0.2\t30\t0\t0.3\n"
    )
    samples = read_astm(astm_file(tmp_path, body))
    np.testing.assert_allclose(samples.wi, [[S30, 0, C30]] * 2, atol=1e-15)
    np.testing.assert_allclose(samples.wo, [[-S45, 0, C45], [0, S45, C45]], atol=1e-15)
    assert samples.values.tolist() == [[0.1, 0.2, 0.3]] * 2 and samples.channels == ("r", "g", "b")
    # A trailing comma after the last cell is allowed.
    samples = read_astm(astm_file(tmp_path, cornell(["30,0,45,180,0.1,0.2,0.3,"])))
    assert samples.values.tolist() == [[0.1, 0.2, 0.3]]


@pytest.mark.parametrize(
    ("names", "channels"),
    [
        ("X,Y,Z", ("x", "y", "z")),
        ("400,410,420", ("400", "410", "420")),
        ("400nm,410nm,420.5nm", ("400", "410", "420.5")),
        ("BRDF", ("BRDF",)),
    ],
)
def test_channel_names(tmp_path, names, channels):
    cells = ",".join(["0.1"] * len(channels))
    body = cornell([f"30,0,45,180,{cells}"], vars_line=f"VARS theta_i,phi_i,theta_s,phi_s,{names}\n")
    assert read_astm(astm_file(tmp_path, body)).channels == channels


# ---------------------------------------------------------------------- writing
@pytest.mark.parametrize(
    "channels", [("r", "g", "b"), ("value",), ("x", "y", "z"), tuple(str(w) for w in range(400, 701, 10))]
)
def test_write_read_round_trip(tmp_path, rng, channels):
    n = 250
    original = Samples.from_arrays(
        random_directions(rng, n), random_directions(rng, n), rng.random((n, len(channels))), channels=channels
    )
    path = tmp_path / "out.astm"
    write_astm(original, path)
    lines = path.read_text().splitlines()
    assert lines[2] == f"NUM_POINTS {n}" and lines[3].startswith("VARS theta_i,phi_i,theta_s,phi_s,")
    back = read_astm(path)
    assert back.channels == channels and back.n_samples == n
    np.testing.assert_allclose(back.wi, original.wi, atol=1e-12)
    np.testing.assert_allclose(back.wo, original.wo, atol=1e-12)
    np.testing.assert_allclose(back.values, original.values, rtol=1e-15)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.astm"]


def test_write_uses_cornell_column_names_and_radians(tmp_path):
    original = Samples.from_arrays([[S30, 0, C30]], [[-S45, 0, C45]], [[0.1, 0.2, 0.3]], channels=("r", "g", "b"))
    write_astm(original, tmp_path / "o.astm")
    lines = (tmp_path / "o.astm").read_text().splitlines()
    assert lines[3] == "VARS theta_i,phi_i,theta_s,phi_s,R,G,B"
    np.testing.assert_allclose(
        [float(x) for x in lines[4].split(",")], [math.pi / 6, 0, math.pi / 4, math.pi, 0.1, 0.2, 0.3]
    )


@pytest.mark.parametrize(
    ("channels", "message"),
    [
        (("red band",), "channel name 'red band' cannot be an ASTM VARS column"),
        (("a,b",), "channel name 'a,b' cannot be an ASTM VARS column"),
        (("theta_i",), "channel name 'theta_i' cannot be an ASTM VARS column"),
        (("400", "400nm"), "channels 400, 400nm would read back as the same column"),
    ],
)
def test_write_errors(tmp_path, channels, message):
    samples = Samples.from_arrays([[0, 0, 1]], [[0, 0, 1]], [[0.1] * len(channels)], channels=channels)
    with pytest.raises(BrdfInputError, match=None) as caught:
        write_astm(samples, tmp_path / "o.astm")
    assert message in str(caught.value) and not (tmp_path / "o.astm").exists()


# ---------------------------------------------------------------------- errors
GOOD = ["30,0,45,180,0.1,0.2,0.3", "30,0,45,90,0.1,0.2,0.3"]

ERRORS = [
    ("", "empty file"),
    ("NUM_POINTS 0\n" + VARS, "no data rows (no line starting with a number after the header)"),
    (VARS + "30,0,45,180,0.1,0.2,0.3\n", "no NUM_POINTS line before the data (e.g. 'NUM_POINTS 1439')"),
    ("NUM_POINTS 1\n30,0,45,180,0.1,0.2,0.3\n", "no VARS line before the data"),
    (cornell(GOOD).replace("NUM_POINTS 2", "NUM_POINTS two"), "line 4: NUM_POINTS 'two' is not a whole number"),
    (cornell(GOOD).replace("NUM_POINTS 2", "NUM_POINTS 2\nnum_points 2"), "line 5: NUM_POINTS appears twice"),
    (cornell(GOOD, count=3), "NUM_POINTS (line 4) says 3 points, but the file has 2 data rows (truncated?)"),
    (cornell(GOOD, count=1), "NUM_POINTS (line 4) says 1 points, but the file has 2 data rows"),
    (
        cornell(GOOD, "VARS theta_i,phi_i,theta_r,phi_r,R\n"),
        "line 5: VARS lacks theta_s, phi_s; it must name theta_i, phi_i, theta_s, phi_s",
    ),
    (cornell(GOOD, "VARS theta_i,phi_i,theta_s,phi_s\n"), "line 5: VARS names no value column"),
    (
        cornell(GOOD, "VARS theta_i,phi_i,theta_s,phi_s,R,,B\n"),
        "line 5: VARS 'theta_i,phi_i,theta_s,phi_s,R,,B' has an",
    ),
    (cornell(GOOD, "VARS theta_i,phi_i,theta_s,phi_s,R,r,B\n"), "line 5: VARS names column 'r' twice"),
    (cornell(GOOD, "VARS theta_i,phi_i,theta_s,phi_s,400,400nm\n"), "line 5: VARS names the same channel twice"),
    (cornell([*GOOD, "30,0,45,180,0.1,0.2"]), "line 8: 6 cells, but VARS (line 5) names 7 columns"),
    (cornell([*GOOD, "30,0,45,180,0.1,,0.3"]), "line 8, column G: an empty cell is not a number"),
    (cornell([*GOOD, "30,0,45,180,0.1,abc,0.3"]), "line 8, column G: 'abc' is not a number"),
    (cornell([*GOOD, "30,0,45,180,0.1,NaN,0.3"]), "line 8, column G: nan is not allowed (values must be finite)"),
    (cornell([*GOOD, "30,0,inf,180,0.1,0.2,0.3"]), "line 8, column theta_s: inf is not allowed (values must be"),
    (cornell([*GOOD, "30,0,45,180,0.1,-0.2,0.3"]), "line 8, channel g: -0.2 is negative (negative reflectance"),
    (
        cornell([*GOOD, "90,0,45,180,0.1,0.2,0.3"]),
        "line 8, column theta_i: 90 is outside [0, 90) degrees (directions must be above the horizon);"
        " angles are read as degrees because some angle in the file is beyond ±2π",
    ),
    (cornell([*GOOD, "30,0,-5,180,0.1,0.2,0.3"]), "line 8, column theta_s: -5 is outside [0, 90) degrees"),
    (cornell([*GOOD, "30,400,45,180,0.1,0.2,0.3"]), "line 8, column phi_i: 400 is outside [-360, 360] degrees"),
    (
        cornell(["0.5,0,1.6,3,0.1,0.2,0.3"]),
        "line 6, column theta_s: 1.6 is outside [0, 1.5708) radians (directions must be above the horizon);"
        " angles are read as radians because every angle in the file is within ±2π",
    ),
    (cornell([*GOOD, "NUM_POINTS 3"]), "line 8: 2 cells, but VARS (line 5) names 7 columns"),
    (cornell(["30,0,45,x,0.1,0.2,0.3", *GOOD]), "line 6, column phi_s: 'x' is not a number"),
]


@pytest.mark.parametrize(("body", "message"), ERRORS)
def test_errors_name_the_file_and_line(tmp_path, body, message):
    path = astm_file(tmp_path, body)
    with pytest.raises(BrdfInputError) as caught:
        read_astm(path)
    text = str(caught.value)
    assert text.startswith(f"{path}: ") and message in text and "\n" not in text, text


def test_unreadable_files(tmp_path):
    latin = tmp_path / "latin.astm"
    latin.write_bytes(b"SAMPLE_NAME caf\xe9\nNUM_POINTS 1\n")
    nul = tmp_path / "nul.astm"
    nul.write_bytes(b"NUM_POINTS 1\n\0\0")
    cases = {
        tmp_path / "missing.astm": "no such file",
        tmp_path: "is a folder, not an ASTM E1392 file",
        latin: "not a text file (not UTF-8); an ASTM E1392 file is text",
        nul: "binary content (NUL bytes)",
    }
    for path, message in cases.items():
        with pytest.raises(BrdfInputError) as caught:
            read_astm(path)
        assert str(caught.value).startswith(f"{path}: ") and message in str(caught.value), caught.value


# ---------------------------------------------------------------------- fuzzing
SEED = cornell(["30,0,45,180,0.1,0.2,0.3", "30,0,45,90,0.01,0.02,0.03", "60,0,10,0,1,2,3"])
TOKENS = st.sampled_from(
    [
        "NUM_POINTS",
        "VARS",
        "theta_i",
        "phi_s",
        "R",
        "400nm",
        "3",
        "2",
        "0",
        "-1",
        "90",
        "360",
        "1e400",
        "nan",
        "-inf",
        "x",
        "",
        ",",
        ",,",
        " ",
        "\n",
        "\t",
        "#",
        "1_0",
        "é",
        "\0",
        "6.2832",
        "1.5707963267948966",
    ]
)


def _mutate(text: str, data: st.DataObject) -> str:
    for _ in range(data.draw(st.integers(1, 4))):
        choice = data.draw(st.integers(0, 4))
        if choice == 0:  # truncate
            text = text[: data.draw(st.integers(0, len(text)))]
        elif choice == 1:  # replace a cell or word
            separator = data.draw(st.sampled_from([",", " "]))
            words = text.split(separator)
            words[data.draw(st.integers(0, len(words) - 1))] = data.draw(TOKENS)
            text = separator.join(words)
        elif choice == 2:  # insert a token or random text
            at = data.draw(st.integers(0, len(text)))
            text = text[:at] + data.draw(st.one_of(TOKENS, st.text(max_size=12))) + text[at:]
        elif choice == 3:  # drop or duplicate a line
            lines = text.split("\n")
            index = data.draw(st.integers(0, len(lines) - 1))
            if data.draw(st.booleans()):
                del lines[index]
            else:
                lines.insert(index, lines[index])
            text = "\n".join(lines)
        else:  # change a header value
            text = text.replace(
                data.draw(st.sampled_from(["NUM_POINTS 3", "R,G,B", "theta_i,phi_i", "SOURCE"])),
                data.draw(st.sampled_from(["NUM_POINTS 2", "NUM_POINTS", "X,Y", "R,G,B,A", "phi_i,theta_i", "VARS"])),
            )
    return text


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_fuzzed_files_raise_only_brdf_input_error(data):
    text = _mutate(SEED, data)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.astm"
        if data.draw(st.booleans()):
            path.write_text(text, encoding="utf-8")
        else:
            path.write_bytes(text.encode("utf-8")[:-1] + data.draw(st.binary(max_size=8)))
        try:
            samples = read_astm(path)
        except BrdfInputError as error:
            assert str(error).startswith(f"{path}: ") and "\n" not in str(error)
        else:
            assert isinstance(samples, Samples) and samples.n_samples >= 1
            assert np.all(np.isfinite(samples.values)) and np.all(samples.values >= 0)
            assert np.all(samples.wi[:, 2] > 0) and np.all(samples.wo[:, 2] > 0)
