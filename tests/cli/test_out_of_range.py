"""Data beyond float64's range (issue 29, item 3): a fit whose cost or error is not finite has no result file (JSON
holds no infinity). One fit: one line naming the file, exit status 2, nothing written. In a batch: that dataset's
error line and no file, every other result written, exit status 2."""

import dataclasses
import json
import math

import pytest
from paths import EXAMPLE

from brdffit import BrdfInputError, fit
from brdffit.cli import main


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def write_with(path, value=None, sigma=None):
    """The example with one value replaced (row 4, channel r) or with a sigma column (0.01; row 6 replaced)."""
    header, *rows = EXAMPLE.read_text().splitlines()
    if value is not None:
        cells = rows[3].split(",")
        cells[4] = value
        rows[3] = ",".join(cells)
    if sigma is not None:
        header += ",sigma"
        rows = [f"{row},{sigma if index == 5 else '0.01'}" for index, row in enumerate(rows)]
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


@pytest.fixture
def out_of_range(tmp_path):
    """A value whose square overflows (the rmse is inf), and a sigma whose inverse square does (the cost is inf)."""
    return {
        "rmse": write_with(tmp_path / "huge.csv", value="1e308"),
        "cost": write_with(tmp_path / "tiny-sigma.csv", sigma="1e-300"),
    }


@pytest.mark.parametrize("what", ["rmse", "cost"])
def test_one_fit_that_is_not_finite_is_one_line_and_writes_nothing(out_of_range, tmp_path, capsys, what):
    samples = out_of_range[what]
    output = tmp_path / "result.json"
    status, out, err = run(["fit", samples, "--model", "lambert", "-o", output], capsys)
    assert status == 2 and err.count("\n") == 1, err
    assert err.startswith(f"brdffit: error: {samples}: the fit's {what} is inf, not a finite number"), err
    assert out == "" and not output.exists()
    assert sorted(path.name for path in tmp_path.iterdir()) == ["huge.csv", "tiny-sigma.csv"]


def test_in_a_batch_the_others_are_written(out_of_range, tmp_path, capsys):
    """The good files before and after the bad ones are written; each bad one has its own error line."""
    first, last = tmp_path / "a.csv", tmp_path / "z.csv"
    first.write_text(EXAMPLE.read_text())
    last.write_text(EXAMPLE.read_text())
    folder = tmp_path / "out"
    argv = ["fit", first, out_of_range["rmse"], out_of_range["cost"], last, "--model", "lambert", "-o", f"{folder}/"]
    status, out, err = run(argv, capsys)
    assert status == 2, err
    assert sorted(path.name for path in folder.iterdir()) == ["a.lambert.json", "z.lambert.json"]
    errors = [line for line in err.splitlines() if line.startswith("brdffit: error: ")]
    named = [line.removeprefix("brdffit: error: ").partition(": ")[0] for line in errors]
    assert named == [str(out_of_range["rmse"]), str(out_of_range["cost"])]
    assert all(line.endswith("; not written") for line in errors)
    assert out.count("(not written)") == 2
    for name in ("a", "z"):
        assert json.loads((folder / f"{name}.lambert.json").read_text())["fit"]["converged"] is True


def test_a_result_that_is_not_finite_is_no_json():
    """The library says which number is not finite, in one line, instead of the JSON encoder's ValueError."""
    result = dataclasses.replace(fit(EXAMPLE, "lambert"), rmse=math.inf)
    assert result.non_finite().startswith("the fit's rmse is inf")
    with pytest.raises(BrdfInputError, match="the fit's rmse is inf"):
        result.to_json()
    assert dataclasses.replace(result, rmse=1.0).non_finite() is None


def test_a_fit_that_is_not_finite_writes_no_chain(out_of_range, tmp_path, capsys):
    """Issue 29: with ``--uncertainty mcmc --chain`` the chain was written while sampling, before the result was found
    not finite: the command refused the result but left the chain. A result that is not finite gets no estimate."""
    samples, output, chain = out_of_range["rmse"], tmp_path / "result.json", tmp_path / "chain.npz"
    argv = ["fit", samples, "--model", "lambert", "--uncertainty", "mcmc", "--walkers", "8", "--steps", "40"]
    status, out, err = run([*argv, "--burn", "10", "--chain", chain, "-o", output], capsys)
    assert status == 2 and err.count("\n") == 1, err
    assert err.startswith(f"brdffit: error: {samples}: the fit's rmse is inf, not a finite number"), err
    assert out == "" and sorted(path.name for path in tmp_path.iterdir()) == ["huge.csv", "tiny-sigma.csv"]
