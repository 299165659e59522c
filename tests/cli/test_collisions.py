"""No output destroys an input or another output (issue 29, item 2): every command declares the files it reads and
writes (``brdffit/cli/files.py``), and a collision is one line, exit status 2, before any work, nothing written."""

import argparse
import os
import shutil

import pytest
from datadriven.conftest import basis_file, library  # noqa: F401 (fixtures: a real basis, for --model pca)
from paths import EXAMPLE, EXAMPLE_PARAMS

from brdffit import fit
from brdffit.cli import COMMANDS, build_parser, main
from brdffit.cli.arguments import FILE_METAVARS
from brdffit.data_synth.capture import synth_capture

#: Metavars of every other argument (a number, a name, a list of names or values, an address).
OTHER_METAVARS = {
    "NAME", "KIND", "K", "W", "DEG", "NAME=VALUE[,…]", "NAME=LO:HI[,…]", "Q", "UNIT", "T", "N", "M", "TYPE",
    "ADDRESS", "METHOD", "SPEC,…", "L", "DEG,…", "TARGET", "FORMAT", "PIXELS", "X", "LEVEL", "NAME[,…]", "true|false",
    "ETA", "SHELL", "X,Y,Z", "E", "I[,I…]", "ROWS,COLUMNS", "MM", "TAU",
}  # fmt: skip


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """A result file of the shipped example."""
    path = tmp_path_factory.mktemp("result") / "oak.lambert.json"
    fit(EXAMPLE, "lambert").save(path)
    return path


@pytest.fixture
def folder(tmp_path, result, basis_file):  # noqa: F811
    """A folder holding the files a command line may name: samples, a result, start parameters (also under a
    binary-looking name, as a user may give them), a directions file, a basis."""
    (tmp_path / "oak.csv").write_text(EXAMPLE.read_text())
    (tmp_path / "oak.png").write_text(EXAMPLE.read_text())  # samples under a figure's name
    (tmp_path / "fit.json").write_bytes(result.read_bytes())
    (tmp_path / "oak.slices.png").write_bytes(result.read_bytes())  # a result under the name of oak.csv's figure
    (tmp_path / "start.json").write_text(EXAMPLE_PARAMS.read_text())
    (tmp_path / "s.npz").write_text(EXAMPLE_PARAMS.read_text())
    (tmp_path / "directions.csv").write_text("theta_i,phi_i,theta_o,phi_o\n10,0,20,180\n")
    shutil.copy(basis_file, tmp_path / "b.npz")
    (tmp_path / "table.binary").write_bytes(b"not a table")
    synth_capture(tmp_path / "cap", "lambert", shape=(2, 2), n_images=2)
    return tmp_path


#: Each output of each command against an input or another output: the command line (paths relative to the test's
#: folder) and the piece of the message.
COLLISIONS = [
    # the four cases of the issue
    (["fit", "oak.csv", "--uncertainty", "laplace", "--corner", "x.png", "-o", "x.png"], "also the output of"),
    (["fit", "oak.csv", "--uncertainty", "mcmc", "--chain", "x.npz", "-o", "x.npz"], "also the output of"),
    (["fit", "oak.csv", "--start", "s.npz", "--uncertainty", "mcmc", "--chain", "s.npz"], "is the input s.npz"),
    (["fit", "oak.csv", "--start", "start.json", "-o", "start.json"], "is the input start.json (--start)"),
    # fit: every output against every input and every other output
    (["fit", "oak.csv", "--uncertainty", "mcmc", "--chain", "oak.csv"], "is the input oak.csv (SAMPLES)"),
    (["fit", "oak.csv", "--uncertainty", "laplace", "--corner", "oak.csv"], "is the input oak.csv (SAMPLES)"),
    (["fit", "oak.csv", "--uncertainty", "mcmc", "--corner", "start.json", "--start", "start.json"], "(--start)"),
    (["fit", "oak.csv", "--uncertainty", "mcmc", "--chain", "c.npz", "--corner", "c.npz"], "also the output of"),
    (["fit", "oak.csv", "--uncertainty", "mcmc", "--chain", "oak.ward.json"], "also the output of -o oak.ward.json"),
    (["fit", "oak.csv", "--basis", "b.npz", "--model", "pca", "-o", "b.npz"], "is the input b.npz (--basis)"),
    (
        ["fit", "oak.csv", "--basis", "b.npz", "--model", "pca", "--uncertainty", "mcmc", "--chain", "b.npz"],
        "(--basis)",
    ),
    (["fit", "oak.csv", "start.json", "--start", "./out/oak.ward.json", "-o", "out/"], "(--start)"),
    (["fit", "oak.csv", "--start", "start.json", "-o", "./sub/../start.json"], "is the input"),
    # the other commands
    (["compare", "oak.csv", "-o", "oak.csv"], "is the input oak.csv (SAMPLES)"),
    (["compare", "oak.csv", "--basis", "b.npz", "-o", "b.npz"], "(--basis)"),
    (["report", "oak.csv", "-o", "oak.csv"], "is the input oak.csv (SAMPLES)"),
    (["report", "oak.csv", "--basis", "b.npz", "-o", "b.npz"], "(--basis)"),
    (["plot", "fit.json", "oak.png", "--kind", "slices", "-o", "oak.png"], "is the input oak.png (FILE)"),
    (["plot", "oak.slices.png", "oak.csv", "--kind", "slices", "-o", "./"], "is the input oak.slices.png (FILE)"),
    (["export", "fit.json", "--to", "gltf", "-o", "fit.json"], "is the input fit.json (RESULT.json)"),
    (["export", "fit.json", "--to", "merl", "--samples", "table.binary", "-o", "table.binary"], "(--samples)"),
    (["render", "fit.json", "-o", "fit.json"], "is the input fit.json (RESULT.json)"),
    (["render", "fit.json", "--samples", "oak.png", "-o", "oak.png"], "is the input oak.png (--samples)"),
    (["synth", "--params", "start.json", "--model", "ward", "-o", "start.json"], "(--params)"),
    (
        [
            "synth",
            "--params",
            "start.json",
            "--model",
            "ward",
            "--directions",
            "directions.csv",
            "-o",
            "directions.csv",
        ],
        "(--directions)",
    ),
    (["convert", "oak.csv", "oak.csv"], "OUT oak.csv: is the input oak.csv (IN)"),
    (["basis", "build", "table.binary", "-o", "table.binary"], "is the input table.binary (LIB)"),
    (["basis", "directions", "b.npz", "-o", "b.npz"], "is the input b.npz (BASIS)"),
    (["svbrdf", "fit", "cap", "-o", "cap"], "is the input cap (CAPTURE)"),
    (["svbrdf", "fit", "cap/capture.json", "-o", "cap"], "is the input cap (CAPTURE)"),
    (["svbrdf", "fit", "cap", "-o", "cap/img_000.npy"], "is the input cap/img_000.npy (CAPTURE)"),
]


@pytest.mark.parametrize(("argv", "piece"), COLLISIONS, ids=[" ".join(argv) for argv, _ in COLLISIONS])
def test_a_collision_is_one_line_before_any_work(folder, monkeypatch, capsys, no_fit, argv, piece):
    monkeypatch.chdir(folder)
    (folder / "sub").mkdir()
    before = {path.name: path.read_bytes() for path in folder.iterdir() if path.is_file()}
    status, out, err = run(argv, capsys)
    assert status == 2 and err.startswith("brdffit: error: ") and err.count("\n") == 1, err
    assert piece in err, err
    assert out == ""
    after = {path.name: path.read_bytes() for path in folder.iterdir() if path.is_file()}
    assert after == before and sorted(os.listdir(folder / "sub")) == []
    assert not (folder / "out").exists()


def test_a_hard_link_to_an_input_is_that_input(folder, monkeypatch, capsys, no_fit):
    """Compared as the system resolves them: another name of the same file (a hard link) is the same file."""
    monkeypatch.chdir(folder)
    os.link(folder / "oak.csv", folder / "also-oak.json")
    status, _, err = run(["fit", "oak.csv", "-o", "also-oak.json"], capsys)
    assert status == 2 and "is the input oak.csv (SAMPLES)" in err, err


def _file_arguments(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    """``(command words, option or positional name, action)`` for every argument of ``parser`` and its actions."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _file_arguments(sub, (*prefix, name))
        elif action.option_strings or action.dest not in ("help", "command"):
            if not isinstance(action, argparse._HelpAction | argparse._VersionAction):
                yield prefix, (action.option_strings or [action.metavar])[0], action


#: For each command (and action), a command line that gives every argument that names a file its own file; the
#: declared files must name them all.
EVERY_FILE = {
    ("fit",): [
        *["fit", "oak.csv", "--start", "start.json", "--model", "pca", "--basis", "b.npz", "--uncertainty", "mcmc"],
        *["--chain", "c.npz", "--corner", "c.png", "-o", "r.json"],
    ],
    ("compare",): ["compare", "oak.csv", "--basis", "b.npz", "-o", "c.json"],
    ("report",): ["report", "oak.csv", "--basis", "b.npz", "--held-back", "cap", "-o", "r.html"],
    ("plot",): ["plot", "fit.json", "oak.csv", "--kind", "slices", "-o", "p.png"],
    ("export",): ["export", "fit.json", "--to", "merl", "--samples", "table.binary", "-o", "e.binary"],
    ("render",): ["render", "fit.json", "--samples", "oak.csv", "-o", "r.png"],
    ("synth",): [
        *["synth", "--params", "start.json", "--model", "pca", "--basis", "b.npz"],
        *["--directions", "directions.csv", "-o", "s.csv"],
    ],
    ("convert",): ["convert", "oak.csv", "oak.dat"],
    ("info",): ["info", "oak.csv"],
    ("models",): ["models"],
    ("basis", "build"): ["basis", "build", "table.binary", "-o", "b2.npz"],
    ("basis", "directions"): ["basis", "directions", "b.npz", "-o", "d.csv"],
    ("svbrdf", "fit"): ["svbrdf", "fit", "cap", "--model", "pca", "--basis", "b.npz", "-o", "maps"],
    ("svbrdf", "render"): ["svbrdf", "render", "cap", "--light", "0,0,1", "--camera", "0,0,1", "-o", "r.exr"],
    ("synth", "capture"): [
        *["synth", "capture", "cap2", "--params", "start.json", "--params", "s.npz", "--model", "pca"],
        *["--basis", "b.npz"],
    ],
}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_argument_that_names_a_file_is_declared(folder, monkeypatch, command):
    """Each argument whose metavar says it names a file is among the files its command declares (so it is checked
    against all the others); an argument with a metavar this test does not know must be classified here first."""
    monkeypatch.chdir(folder)
    parser = build_parser(command)
    arguments = list(_file_arguments(parser))
    unknown = {action.metavar for _, _, action in arguments if action.metavar} - FILE_METAVARS - OTHER_METAVARS
    assert not unknown, f"classify these metavars as naming a file or not: {unknown}"
    for words in {words for words, _, _ in arguments if words in EVERY_FILE and words[0] == command}:  # others: -q
        argv = EVERY_FILE[words]
        args = parser.parse_args(argv)
        declared = args.declared_files(args)
        named = {os.path.basename(path) for _, path in (*declared.inputs, *declared.outputs)}
        for option_words, option, action in arguments:
            if option_words != words or action.metavar not in FILE_METAVARS:
                continue
            given = getattr(args, action.dest)
            assert given is not None, f"{' '.join(words)}: give {option} in EVERY_FILE"
            for path in given if isinstance(given, list) else [given]:
                assert path in named, f"{' '.join(words)} {option} {path}: not declared by the command's files()"
