"""Reading, checking and writing samples files (docs/samples.md).

The bad-input cases are exercised end to end through the command line in
``test_cli.py``; here the loader's successful paths and the array API.
"""

import math
import warnings

import numpy as np
import pytest
from conftest import directions_from_degrees, random_directions
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brdffit import BrdfInputError, InputWarning, Samples, load_samples, save_samples
from brdffit.cli import main


def write(tmp_path, text, name="samples.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_angles_with_one_value_column(tmp_path):
    path = write(tmp_path, "# a comment\ntheta_i,phi_i,theta_o,phi_o,value\n0,0,0,0,0.5\n\n30,0,45,180,0.25 # inline\n")
    samples = load_samples(path)
    assert samples.channels == ("value",) and samples.n_samples == 2 and samples.n_channels == 1
    np.testing.assert_allclose(samples.wi, directions_from_degrees([0, 30], [0, 0]), atol=1e-16)
    np.testing.assert_allclose(samples.wo, directions_from_degrees([0, 45], [0, 180]), atol=1e-16)
    np.testing.assert_array_equal(samples.values, [[0.5], [0.25]])
    assert samples.sigma is None and samples.weight is None and samples.source == str(path)


def test_whitespace_separated_vectors_are_normalised(tmp_path):
    text = "wi_x wi_y wi_z wo_x wo_y wo_z r g b\n0 0 1 0.6 0 0.8 0.1 0.2 0.3\n0 0 1.0004 0 0.6 0.8 0.1 0.2 0.3\n"
    samples = load_samples(write(tmp_path, text))
    assert samples.channels == ("r", "g", "b")
    np.testing.assert_allclose(np.linalg.norm(samples.wi, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(samples.wo[1], [0, 0.6, 0.8])


def test_radians_and_header_case(tmp_path):
    text = f"Theta_I,Phi_I,Theta_O,Phi_O,Value\n{math.pi / 6},0,{math.pi / 4},{math.pi},0.25\n"
    samples = load_samples(write(tmp_path, text), angles="radians")
    np.testing.assert_allclose(samples.wo, directions_from_degrees(45, 180), atol=1e-16)
    assert samples.channels == ("value",)  # the reserved names are matched without regard to case


def test_named_channels_sigma_and_weight(tmp_path):
    text = (
        "theta_i,phi_i,theta_o,phi_o,400,500,600,sigma_400,sigma_500,sigma_600,weight\n"
        "10,0,20,90,0.1,0.2,0.3,0.01,0.02,0.03,2\n"
    )
    samples = load_samples(write(tmp_path, text))
    assert samples.channels == ("400", "500", "600")
    np.testing.assert_array_equal(samples.sigma, [[0.01, 0.02, 0.03]])
    np.testing.assert_array_equal(samples.weight, [2.0])


def test_one_sigma_serves_every_channel(tmp_path):
    samples = load_samples(write(tmp_path, "theta_i,phi_i,theta_o,phi_o,r,g,b,sigma\n10,0,20,90,0.1,0.2,0.3,0.05\n"))
    np.testing.assert_array_equal(samples.sigma, [[0.05, 0.05, 0.05]])


@pytest.mark.parametrize(
    ("quantity", "factor"),
    [("brdf", 1.0), ("reflectance-factor", 1 / math.pi), ("cosine-weighted", 1 / math.cos(math.radians(60)))],
)
def test_quantities_become_brdf(tmp_path, quantity, factor):
    """R = π f and f·cos θi are converted to f; sigma scales the same way."""
    path = write(tmp_path, "theta_i,phi_i,theta_o,phi_o,value,sigma\n60,0,20,90,0.5,0.01\n")
    samples = load_samples(path, quantity=quantity)
    assert samples.values[0, 0] == pytest.approx(0.5 * factor, rel=1e-15)
    assert samples.sigma[0, 0] == pytest.approx(0.01 * factor, rel=1e-15)


def test_save_and_load_round_trip(tmp_path, rng):
    n = 50
    original = Samples.from_arrays(
        random_directions(rng, n),
        random_directions(rng, n),
        rng.random((n, 3)),
        channels=("r", "g", "b"),
        sigma=0.01 + rng.random((n, 3)),
        weight=rng.random(n),
    )
    save_samples(original, tmp_path / "out.csv")
    again = load_samples(tmp_path / "out.csv")
    # Vectors go through angles in degrees and back: ~1e-16 absolute.
    np.testing.assert_allclose(again.wi, original.wi, atol=1e-15)
    np.testing.assert_allclose(again.wo, original.wo, atol=1e-15)
    np.testing.assert_array_equal(again.values, original.values)
    np.testing.assert_array_equal(again.sigma, original.sigma)
    np.testing.assert_array_equal(again.weight, original.weight)
    assert again.channels == original.channels


def test_single_channel_round_trip_uses_value_and_sigma(tmp_path, rng):
    samples = Samples.from_arrays(
        random_directions(rng, 3), random_directions(rng, 3), [0.1, 0.2, 0.3], sigma=[0.01, 0.01, 0.02]
    )
    save_samples(samples, tmp_path / "one.csv")
    assert (tmp_path / "one.csv").read_text().splitlines()[0] == "theta_i,phi_i,theta_o,phi_o,value,sigma"
    assert load_samples(tmp_path / "one.csv").channels == ("value",)


def test_within_max_theta(rng):
    wi = directions_from_degrees([10, 50, 70], [0, 0, 0])
    wo = directions_from_degrees([20, 20, 20], [90, 90, 90])
    samples = Samples.from_arrays(wi, wo, [1.0, 2.0, 3.0])
    assert samples.within(None) is samples
    np.testing.assert_array_equal(samples.within(60).values[:, 0], [1.0, 2.0])
    with pytest.raises(BrdfInputError, match=r"no samples have θi and θo ≤ max_theta=5 degrees"):
        samples.within(5)
    with pytest.raises(BrdfInputError, match=r"^max_theta=95 is not allowed; give degrees in \(0, 90\]"):
        samples.within(95)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"values": [[-1.0], [0.1]]}, "<arrays>: row 0, column value: -1: negative reflectance is not allowed"),
        ({"values": [[np.nan], [0.1]]}, "row 0, column value: nan is not allowed"),
        ({"wi": [[0, 0, -1.0], [0, 0, 1.0]]}, "row 0, column wi_z: -1 ≤ 0: the direction is below the horizon"),
        ({"wo": [[0, 0, 1.0], [0, 0, 2.0]]}, "row 1, columns wo_x, wo_y, wo_z: length 2 is not 1"),
        ({"sigma": [0.0, 0.1]}, "row 0, column sigma_value: 0: sigma must be > 0"),
        ({"weight": [0.0, 0.0]}, "every weight is 0"),
        ({"wi": [[0, 0, 1.0]]}, "wi must have shape (2, 3)"),
        ({"channels": ("a", "b")}, "2 channel names for 1 value columns"),
    ],
)
def test_from_arrays_checks_like_the_file(change, message):
    arrays = {"wi": [[0, 0, 1.0], [0, 0, 1.0]], "wo": [[0, 0, 1.0], [0, 0, 1.0]], "values": [[0.2], [0.1]]} | change
    with pytest.raises(BrdfInputError) as error:
        Samples.from_arrays(**arrays)
    assert message in str(error.value)


_VALID = (
    "theta_i,phi_i,theta_o,phi_o,r,g,b,sigma,weight\n10,0,20,90,0.1,0.2,0.3,0.01,1\n30,0,45,180,0.5,0.4,0.3,0.02,2\n"
)
_CELL = st.sampled_from(
    ["", " ", "nan", "inf", "-1", "0", "1e400", "abc", ",", "#", "\n", "90", "-0", "1e-320", "\t", "\x00"]
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.one_of(st.text(max_size=300), st.lists(_CELL, max_size=12).map("".join)))
def test_the_reader_only_ever_raises_brdf_input_error(tmp_path, text):
    """Arbitrary text, and valid files with random cells spliced in, load or fail with one line."""
    for candidate in (text, _VALID[:40] + text + _VALID[40:], _VALID + text):
        path = tmp_path / "fuzz.csv"
        path.write_bytes(candidate.encode("utf-8", errors="replace"))
        try:
            samples = load_samples(path)
        except BrdfInputError as error:
            assert "\n" not in str(error) and str(error).startswith(str(path))
        else:
            assert np.all(np.isfinite(samples.values)) and np.all(samples.values >= 0)
            assert np.all(samples.wi[:, 2] > 0) and np.all(samples.wo[:, 2] > 0)


def test_angles_that_look_like_radians_read_as_degrees_warn(tmp_path, capsys):
    path = tmp_path / "radians.csv"
    path.write_text("theta_i,phi_i,theta_o,phi_o,value\n0.3,0,0.5,3.1,0.2\n1.2,0,0.7,0,0.1\n")
    with pytest.warns(InputWarning, match=r"every zenith angle is within \[0, π/2\].*give angles=radians"):
        load_samples(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        radians = load_samples(path, angles="radians")  # read as meant: no warning
    assert radians.theta_i.max() == pytest.approx(np.degrees(1.2), rel=1e-12)
    assert main(["info", str(path)]) == 0
    assert "brdffit: warning: " in capsys.readouterr().err  # the command line names its flag
    assert main(["info", str(path)]) == 0 and "--angles radians" in capsys.readouterr().err


def numbered_rows(n, bad_row=None, bad_cell="abc"):
    """A samples file of ``n`` rows with a comment line and a blank line after every third row; row ``bad_row``
    (from 1) has ``bad_cell`` as its value. Returns the text and the line each row is on."""
    lines, where = ["# made by a test", "theta_i,phi_i,theta_o,phi_o,value"], {}
    for row in range(1, n + 1):
        lines.append(f"10,0,{20 + row % 50},90,{bad_cell if row == bad_row else 0.1}")
        where[row] = len(lines)
        if row % 3 == 0:
            lines += ["# a comment", ""]
    return "\n".join(lines) + "\n", where


@pytest.mark.parametrize("bad_cell, problem", [("abc", "'abc' is not a number"), ("-0.5", "-0.5: negative")])
def test_a_bad_cell_past_the_first_chunk_names_its_row_and_line(tmp_path, monkeypatch, bad_cell, problem):
    """A cell the fast parser refuses ('abc') is found by reading the cells chunk by chunk; one it reads (-0.5) is
    judged on the table: either way the message names the row and its line, comments and blank lines counted."""
    from brdffit.data import csv

    monkeypatch.setattr(csv, "CHUNK_ROWS", 4)
    text, where = numbered_rows(20, bad_row=11, bad_cell=bad_cell)
    with pytest.raises(BrdfInputError, match=rf"row 11 \(line {where[11]}\), column value: {problem}"):
        load_samples(write(tmp_path, text))


def test_the_cell_by_cell_reading_gives_the_fast_parsers_table(tmp_path, monkeypatch):
    """A line of blanks sends the file to the cell-by-cell reader (numpy.loadtxt refuses it): same samples."""
    from brdffit.data import csv

    monkeypatch.setattr(csv, "CHUNK_ROWS", 4)
    text, _ = numbered_rows(20)
    fast = load_samples(write(tmp_path, text, "fast.csv"))
    slow = load_samples(write(tmp_path, text.replace("# a comment\n", "   \n"), "slow.csv"))
    for name in ("wi", "wo", "values"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name))
    assert fast.provenance.rows == slow.provenance.rows == 20


def test_underscores_are_not_numbers(tmp_path):
    """Python's float reads '1_000' (numpy.loadtxt does not); a samples file's cells are plain decimals."""
    with pytest.raises(BrdfInputError, match=r"row 1 \(line 2\), column value: '1_000' is not a number"):
        load_samples(write(tmp_path, "theta_i,phi_i,theta_o,phi_o,value\n10,0,20,90,1_000\n"))
