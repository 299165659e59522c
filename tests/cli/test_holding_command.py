"""``--fix`` and ``--bounds`` on the command line: parsed, written to the result, read back by ``--start``, refused
in one line (exit 2, nothing written) when wrong."""

import json

import pytest

from brdffit import data_synth, save_samples
from brdffit.cli import main

TRUTH = {"kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5], "m": 0.2, "eta": 1.5}
DIELECTRIC = ["--model", "cook-torrance", "--fresnel", "dielectric"]


@pytest.fixture(scope="module")
def samples_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("holding") / "plastic.csv"
    wi, wo = data_synth.hemisphere_grid(5, 12, 12)
    save_samples(data_synth.synthesize("cook-torrance", TRUTH, wi, wo, noise=0.01, seed=2, fresnel="dielectric"), path)
    return path


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_fix_and_bounds_reach_the_result_and_the_table(samples_file, tmp_path, capsys):
    output = tmp_path / "held.json"
    argv = ["fit", samples_file, *DIELECTRIC, "--fix", "eta=1.5,kd=[0.1,0.2,0.3]", "--bounds", "m=0.05:0.5"]
    status, out, err = run([*argv, "--fix", "ks=0.5", "-o", output], capsys)
    assert status == 0, err
    content = json.loads(output.read_text())
    assert content["fit"]["fixed"] == {"eta": 1.5, "kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5]}
    assert content["fit"]["bounds"] == {"m": [0.05, 0.5]}
    assert content["params"]["eta"] == 1.5 and content["params"]["kd"] == [0.1, 0.2, 0.3]
    assert "= 1.5" in out and "= 0.1" in out and "bounds: m in [0.05, 0.5]" in out
    assert abs(content["params"]["m"] - 0.2) < 0.006  # the one free parameter, within 3% (recovery tolerance)


def test_a_result_with_fixed_parameters_is_a_start(samples_file, tmp_path, capsys):
    first, again, unheld = tmp_path / "first.json", tmp_path / "again.json", tmp_path / "unheld.json"
    assert run(["fit", samples_file, *DIELECTRIC, "--fix", "eta=1.5", "-o", first], capsys)[0] == 0
    assert run(["fit", samples_file, *DIELECTRIC, "--start", first, "--fix", "eta=1.5", "-o", again], capsys)[0] == 0
    held, refitted = json.loads(first.read_text()), json.loads(again.read_text())
    assert refitted["fit"]["n_steps"] <= 2  # it starts at the optimum
    assert refitted["fit"]["cost"] == pytest.approx(held["fit"]["cost"], rel=1e-9)
    status, _, err = run(["fit", samples_file, *DIELECTRIC, "--start", first, "-o", unheld], capsys)
    assert status == 0, err
    free = json.loads(unheld.read_text())
    assert free["fit"]["fixed"] == {} and free["fit"]["cost"] <= held["fit"]["cost"] * (1 + 1e-9)


@pytest.mark.slow
def test_compare_holds_the_models_that_have_the_parameter(samples_file, tmp_path, capsys):
    output = tmp_path / "compare.json"
    models = "cook-torrance:fresnel=dielectric,ward"
    status, out, err = run(["compare", samples_file, "--models", models, "--fix", "eta=1.5", "-o", output], capsys)
    assert status == 0, err
    entries = {entry["spec"]: entry for entry in json.loads(output.read_text())["models"]}
    assert entries["cook-torrance:fresnel=dielectric"]["fixed"] == {"eta": 1.5}
    assert entries["cook-torrance:fresnel=dielectric"]["k"] == 7 and entries["ward"]["fixed"] == {}
    assert "cook-torrance:fresnel=dielectric: held: eta = 1.5" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--fix", "eta=0.5"], "--fix: eta = 0.5 is outside its domain > 1"),
        (["--fix", "eta"], "--fix eta: give NAME=VALUE"),
        (["--fix", "eta=abc"], "--fix eta=abc: 'abc' is not a number or a list of numbers"),
        (["--fix", "eta=1.5,eta=1.6"], "--fix: eta is given twice"),
        (["--fix", "eta=1.5,"], "--fix: an empty item"),
        (["--fix", "kd=[0.1,0.2]"], "--fix: kd has 2 values but the samples have 3 channel(s)"),
        (["--fix", "alpha=0.1"], "--fix: cook-torrance has no parameter 'alpha'"),
        (["--bounds", "m=0.1"], "--bounds m=0.1: give the range as LO:HI"),
        (["--bounds", "m=a:b"], "--bounds m=a:b: give the range as LO:HI"),
        (["--bounds", "m=0:1"], "--bounds: m from 0 to 1 reaches outside its domain > 0"),
        (["--fix", "m=0.2", "--bounds", "m=0.1:0.3"], "--bounds: m is also fixed"),
        (["--fix", "kd=0,ks=0,m=0.1,eta=1.5"], "--fix: every parameter of cook-torrance is fixed"),
    ],
)
def test_bad_holds_are_one_line_exit_2_and_write_nothing(samples_file, tmp_path, capsys, argv, message):
    output = tmp_path / "never.json"
    status, _, err = run(["fit", samples_file, *DIELECTRIC, *argv, "-o", output], capsys)
    assert status == 2
    assert err.startswith(f"brdffit: error: {message}")
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not output.exists()


def test_compare_refuses_a_name_no_model_has(samples_file, capsys):
    status, _, err = run(["compare", samples_file, "--models", "ward,lambert", "--fix", "eta=1.5"], capsys)
    assert status == 2 and "--fix: no compared model has a parameter 'eta'" in err
