"""``brdffit basis`` and the pca model on the command line, as a user runs them: build, info, directions, synth,
fit, compare, export; and every bad input in one line, exit 2, nothing written."""

import json

import numpy as np
import pytest

from brdffit import load_result, load_samples
from brdffit.cli import main
from brdffit.data.merl import read_merl


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.slow
def test_the_whole_loop(tmp_path, library, capsys):
    folder = library[0][0].parent
    basis = tmp_path / "basis.npz"
    status, out, _ = run(["basis", "build", *library[0][:6], "-o", basis, "--components", "4"], capsys)
    assert status == 0 and "4 components of 6 tables" in out and basis.exists()
    status, out, _ = run(["info", basis], capsys)
    assert status == 0 and "variance explained" in out and "sha256" in out
    directions = tmp_path / "directions.csv"
    argv = ["basis", "directions", basis, "-n", "20", "--candidates", "3000", "-o", directions]
    status, out, _ = run(argv, capsys)
    assert status == 0 and "condition number" in out
    assert directions.read_text().splitlines()[0] == "theta_i,phi_i,theta_o,phi_o"
    # A dense fit of a held-out table, then 20 noisy samples of it at the chosen pairs, as an instrument would give.
    dense = tmp_path / "dense.json"
    held_out = folder / "ward-7.binary"
    argv = ["fit", held_out, "--subsample", "1000", "--model", "pca", "--basis", basis, "-o", dense]
    status, out, _ = run(argv, capsys)
    assert status == 0 and "coefficients[3]" in out
    sparse = tmp_path / "sparse.csv"
    argv = ["synth", "--params", dense, "--directions", directions, "--noise", "0.01", "--seed", "2", "-o", sparse]
    assert run(argv, capsys)[0] == 0
    assert load_samples(sparse).n_samples == 20
    fitted = tmp_path / "sparse.json"
    argv = ["fit", sparse, "--model", "pca", "--basis", basis, "--uncertainty", "laplace", "-o", fitted]
    status, out, _ = run(argv, capsys)
    assert status == 0 and "±" in out
    result = load_result(fitted)
    assert result.model == "pca" and result.model_options["basis"] == str(basis.resolve())
    status, out, _ = run(["compare", sparse, "--models", "ward,pca", "--basis", basis, "--folds", "3"], capsys)
    assert status == 0 and f"pca:basis={basis.name} " in out and "sha256" not in out
    table = tmp_path / "fitted.binary"
    assert run(["export", fitted, "--to", "merl", "-o", table], capsys)[0] == 0
    exported = read_merl(table, subsample=2000, seed=1)
    np.testing.assert_allclose(exported.values, result.predict(exported.wi, exported.wo), rtol=1e-12)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["basis", "build", "absent.binary", "-o", "{tmp}/b.npz"], "absent.binary: no such file"),
        (["basis", "build", "{lib0}", "{lib1}", "-o", "{tmp}/b.npz", "--components", "9"], "--components 9"),
        (["basis", "build", "{lib0}", "{lib1}", "-o", "{tmp}/b.npz", "--mapping", "sqrt"], "--mapping sqrt"),
        (["basis", "build", "{lib0}", "{lib1}", "-o", "{lib0}"], "is the input"),
        (["basis", "directions", "{basis}", "-n", "0", "-o", "{tmp}/d.csv"], "-n"),
        (["basis", "directions", "{basis}", "--max-theta", "120", "-o", "{tmp}/d.csv"], "--max-theta 120"),
        (["basis", "directions", "{lib0}", "-o", "{tmp}/d.csv"], "not a basis file"),
        (["fit", "{lib0}", "--subsample", "50", "--model", "pca", "-o", "{tmp}/f.json"], "--basis FILE"),
        (["fit", "{lib0}", "--model", "pca", "--basis", "{lib0}", "-o", "{tmp}/f.json"], "not a basis file"),
        (["fit", "{lib0}", "--model", "pca", "--basis", "{basis}", "--ridge", "-1", "-o", "{tmp}/f.json"], "--ridge"),
        (["compare", "{lib0}", "--subsample", "50", "--models", "pca"], "basis FILE"),
        (["info", "{tmp}/absent.npz"], "no such file"),
        (
            ["fit", "{lib0}", "--subsample", "50", "--model", "pca", "--basis", "{basis}", "-o", "{basis}"],
            "is the input",
        ),
        (
            ["compare", "{lib0}", "--subsample", "50", "--models", "ward", "--basis", "{basis}"],
            "which --models does not",
        ),
        (["basis", "build", "{lib0}", "{lib1}", "-o", "-"], "a basis is a binary file"),
        (["basis", "directions", "{basis}", "-n", "8", "--candidates", "3", "-o", "{tmp}/d.csv"], "--candidates 3"),
        (
            [
                "synth",
                "--model",
                "ward",
                "--params",
                "{{}}",
                "--directions",
                "{basis}",
                "--geometry",
                "random",
                "-o",
                "{tmp}/s.csv",
            ],
            "--geometry does not apply to --directions",
        ),
        (
            [
                "fit",
                "{lib0}",
                "--subsample",
                "50",
                "--model",
                "pca",
                "--basis",
                "{basis}",
                "--dtype",
                "float32",
                "-o",
                "{tmp}/f.json",
            ],
            "--dtype float32 does not apply to model pca",
        ),
    ],
)
def test_bad_input_is_one_line(tmp_path, library, basis_file, capsys, argv, message):
    names = {"tmp": tmp_path, "lib0": library[0][0], "lib1": library[0][1], "basis": basis_file}
    before = sorted(tmp_path.iterdir())
    status, _, err = run([part.format(**names) for part in argv], capsys)
    assert status == 2, err
    assert err.count("\n") == 1 and message in err, err
    assert sorted(tmp_path.iterdir()) == before


@pytest.mark.slow
def test_a_result_whose_basis_changed(tmp_path, library, capsys):
    """A result records its basis's SHA-256: after the basis file is rebuilt differently, using the result is a
    one-line error, not a silently different material."""
    basis = tmp_path / "basis.npz"
    assert run(["basis", "build", *library[0][:4], "-o", basis, "--components", "3"], capsys)[0] == 0
    fitted = tmp_path / "fit.json"
    argv = ["fit", library[0][5], "--subsample", "100", "--model", "pca", "--basis", basis, "-o", fitted]
    assert run(argv, capsys)[0] == 0
    assert run(["basis", "build", *library[0][:4], "-o", basis, "--components", "2"], capsys)[0] == 0
    status, _, err = run(["export", fitted, "--to", "merl", "-o", tmp_path / "t.binary"], capsys)
    assert status == 2 and "SHA-256 differs" in err
    assert json.loads(fitted.read_text())["model_options"]["basis_sha256"]


def test_names_labels_and_the_basis_kept_safe(tmp_path, library, basis_file, capsys, monkeypatch):
    """A pca result is named ``STEM.pca.json`` (no path in the name), labelled by the basis's file name, and no
    output may overwrite the basis, not even through a result that names it."""
    monkeypatch.chdir(tmp_path)
    assert run(["fit", library[0][6], "--subsample", "200", "--model", "pca", "--basis", basis_file], capsys)[0] == 0
    result = tmp_path / "ward-6.pca.json"
    assert result.exists()
    status, out, _ = run(
        ["compare", library[0][6], "--subsample", "200", "--models", "pca", "--basis", basis_file, "--folds", "2"],
        capsys,
    )
    assert status == 0 and f"pca:basis={basis_file.name} " in out
    before = basis_file.read_bytes()
    status, _, err = run(["export", result, "--to", "merl", "-o", basis_file], capsys)
    assert status == 2 and "is the input" in err and basis_file.read_bytes() == before


def test_poorly_conditioned_directions_are_said(tmp_path, basis_file, capsys):
    argv = ["basis", "directions", basis_file, "-n", "10", "--max-theta", "5", "--candidates", "200"]
    status, _, err = run([*argv, "-o", tmp_path / "d.csv"], capsys)
    assert status == 0 and "barely determine" in err
