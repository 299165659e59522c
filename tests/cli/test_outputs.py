"""Files are sacred: every output is checked before any work, inputs are never overwritten, links are followed,
``-o -`` is standard output, and Ctrl-C leaves nothing half-written."""

import json
import os

import pytest
from paths import EXAMPLE

import brdffit.api
from brdffit.cli import main


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def samples(tmp_path):
    path = tmp_path / "samples.csv"
    path.write_text(EXAMPLE.read_text())
    return path


def one_line_error(status, err, *pieces):
    assert status == 2 and err.startswith("brdffit: error: ") and err.count("\n") == 1, err
    for piece in pieces:
        assert piece in err, err


def test_an_output_naming_the_input_is_refused_and_the_input_kept(samples, capsys, no_fit):
    before = samples.read_bytes()
    status, out, err = run(["fit", samples, "-o", samples], capsys)
    one_line_error(status, err, f"-o {samples}: is the input {samples}")
    assert samples.read_bytes() == before and out == ""


def test_an_output_linked_to_the_input_is_refused(samples, tmp_path, capsys, no_fit):
    link = tmp_path / "result.json"
    link.symlink_to(samples)
    status, _, err = run(["fit", samples, "-o", link], capsys)
    one_line_error(status, err, "is the input")
    assert link.is_symlink() and samples.read_text() == EXAMPLE.read_text()


def test_an_output_through_a_link_writes_the_target_and_keeps_the_link(samples, tmp_path, capsys):
    target = tmp_path / "results" / "ward.json"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "latest.json"
    link.symlink_to(target)
    status, _, _ = run(["fit", samples, "--model", "lambert", "-o", link], capsys)
    assert status == 0 and link.is_symlink() and os.readlink(link) == str(target)
    assert json.loads(target.read_text())["model"] == "lambert"
    assert sorted(os.listdir(target.parent)) == ["ward.json"]  # no temporary file left beside it


@pytest.mark.parametrize(
    ("output", "piece"),
    [
        ("/dev/null", "is not a regular file"),
        ("FOLDER", "is a folder; give a file name, or"),
        ("missing/r.json", "folder"),
    ],
)
def test_bad_outputs_are_refused_before_the_fit(samples, tmp_path, capsys, no_fit, output, piece):
    output = {"FOLDER": str(tmp_path), "missing/r.json": str(tmp_path / "missing" / "r.json")}.get(output, output)
    status, _, err = run(["fit", samples, "-o", output], capsys)
    one_line_error(status, err, f"-o {output}: {piece}")
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write to any folder, so an unwritable folder cannot be made")
def test_an_unwritable_folder_is_refused_before_the_fit(samples, tmp_path, capsys, no_fit):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    status, _, err = run(["fit", samples, "-o", locked / "r.json"], capsys)
    one_line_error(status, err, "is not writable")


@pytest.mark.parametrize(
    ("option", "name", "piece"),
    [
        ("--chain", "DEVICE", "is not a regular file"),
        ("--chain", "missing/c.npz", "does not exist"),
        ("--corner", "DEVICE", "is not a regular file"),
        ("--corner", "INPUT", "is the input"),
    ],
)
def test_chain_and_corner_outputs_are_checked_before_the_fit(samples, tmp_path, capsys, no_fit, option, name, piece):
    if name in ("INPUT", "DEVICE"):  # a link with the right suffix to the input, or to a device
        link = tmp_path / ("out.npz" if option == "--chain" else "out.png")
        link.symlink_to(samples if name == "INPUT" else "/dev/null")
        name = link
    elif name.startswith("missing"):
        name = tmp_path / name
    status, _, err = run(["fit", samples, "--uncertainty", "mcmc", option, name, "-o", tmp_path / "r.json"], capsys)
    one_line_error(status, err, piece)
    assert not (tmp_path / "r.json").exists()


def test_a_folder_named_with_a_slash_takes_the_default_name(samples, tmp_path, capsys):
    folder = tmp_path / "fits"
    folder.mkdir()
    status, _, _ = run(["fit", samples, "--model", "lafortune", "--lobes", "2", "-o", f"{folder}/"], capsys)
    assert status == 0 and os.listdir(folder) == ["samples.lafortune.lobes-2.json"]


def test_default_names_carry_the_options_that_change_the_result(samples, tmp_path, capsys, monkeypatch):
    """The name carries each option that differs from its default, so fits with other options do not collide."""
    monkeypatch.chdir(tmp_path)
    for options in (
        ["--model", "cook-torrance"],
        ["--model", "cook-torrance", "--fresnel", "none"],
        ["--model", "cook-torrance", "--distribution", "ggx", "--shadowing", "smith"],
        [],
    ):
        status, _, _ = run(["fit", samples, *options], capsys)
        assert status == 0
    assert sorted(name for name in os.listdir(tmp_path) if name.endswith(".json")) == [
        "samples.cook-torrance.distribution-ggx.shadowing-smith.json",
        "samples.cook-torrance.fresnel-none.json",
        "samples.cook-torrance.json",
        "samples.ward.json",
    ]


def test_dash_writes_the_result_to_standard_output_and_the_table_to_standard_error(samples, capsys):
    status, out, err = run(["fit", samples, "--model", "lambert", "-o", "-"], capsys)
    assert status == 0 and json.loads(out)["model"] == "lambert"
    assert "lambert fit of" in err and "rho_d" in err and err.rstrip().endswith("wrote -")  # as every command says
    status, _, err = run(["fit", samples, samples, "-o", "-"], capsys)
    one_line_error(status, err, "standard output takes one result")


def test_interrupted_exits_130_with_one_line_and_writes_nothing(samples, tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(brdffit.api, "fit", interrupted)
    status, out, err = run(["fit", samples, "-o", tmp_path / "r.json"], capsys)
    assert status == 130 and err == "brdffit: interrupted\n" and out == ""
    assert sorted(os.listdir(tmp_path)) == ["samples.csv"]


def test_synth_and_convert_never_overwrite_their_input(tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_text('{"rho_d": [0.5]}')
    status, _, err = run(["synth", "--model", "lambert", "--params", params, "-o", params], capsys)
    one_line_error(status, err, "is the input")
    assert params.read_text() == '{"rho_d": [0.5]}'
    copy = tmp_path / "samples.csv"
    copy.write_text(EXAMPLE.read_text())
    status, _, err = run(["convert", copy, copy], capsys)
    one_line_error(status, err, "is the input")
    assert copy.read_text() == EXAMPLE.read_text()
