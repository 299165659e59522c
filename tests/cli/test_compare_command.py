"""``brdffit compare`` end to end: the ranking printed, the JSON written, bad input refused before any fit."""

import json

import pytest

from brdffit import data_synth, save_samples
from brdffit.cli import main


@pytest.fixture(scope="module")
def samples_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("compare") / "ward.csv"
    wi, wo = data_synth.hemisphere_grid(6, 9, 12)
    params = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}
    save_samples(data_synth.synthesize("ward", params, wi, wo, noise=0.01, seed=1), path)
    return path


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_compare_prints_the_ranking_and_writes_the_json(samples_file, tmp_path, capsys):
    output = tmp_path / "compare.json"
    status, out, err = run(["compare", samples_file, "--models", "lambert,ward", "--folds", 3, "-o", output], capsys)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[0].startswith(f"models compared on {samples_file}: 648 samples × 1 channel(s), loss log")
    assert "3 folds each holding out whole light directions, seed 0" in lines[1]
    assert lines[3].split()[:3] == ["1", "*", "ward"] and lines[4].split()[:2] == ["2", "lambert"]
    assert lines[-1] == f"wrote {output}"
    content = json.loads(output.read_text())
    assert content["best"] == "ward" and [m["spec"] for m in content["models"]] == ["ward", "lambert"]


def test_dash_writes_the_json_to_standard_output(samples_file, capsys):
    status, out, err = run(["compare", samples_file, "--models", "lambert", "--folds", 2, "-o", "-"], capsys)
    assert status == 0
    assert json.loads(out)["best"] == "lambert" and "models compared on" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--models", "wrd"], "brdffit: error: model spec 'wrd': 'wrd' is not a model; choose one of:"),
        (
            ["--models", "lafortune:x"],
            "brdffit: error: model spec 'lafortune:x': lobes='x' is not allowed; give a whole number from 1 to 8",
        ),
        (["--folds", "1"], "brdffit: error: --folds 1 is not allowed; give a whole number ≥ 2"),
        (["--loss", "l3"], "brdffit: error: --loss 'l3' is not a loss"),
        (["--models", ""], "brdffit: error: --models: give at least one model to compare"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(samples_file, capsys, argv, message):
    status, out, err = run(["compare", samples_file, *argv], capsys)
    assert status == 2 and out == ""
    assert err.startswith(message) and err.count("\n") == 1


def test_the_input_is_never_the_output(samples_file, capsys):
    before = samples_file.read_bytes()
    status, _, err = run(["compare", samples_file, "-o", samples_file], capsys)
    assert status == 2 and "is the input" in err
    assert samples_file.read_bytes() == before
