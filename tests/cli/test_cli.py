"""The command line end to end: fit, synth, models, --help, --version, exit statuses, bad input."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from paths import EXAMPLE, EXAMPLE_PARAMS, ROOT

from brdffit import load_result, load_samples
from brdffit.cli import COMMANDS, main

GEOMETRY = "theta_i,phi_i,theta_o,phi_o"


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


# ------------------------------------------------------------------ bad input
# Each case: the samples file's text and the pieces its one-line message must contain.
BAD_SAMPLES = {
    "unknown column": (f"{GEOMETRY},value,foo\n10,0,20,90,0.1,1\n", ["header (line 1)", "unknown column 'foo'"]),
    "unknown geometry-like column": (f"{GEOMETRY},theta_h,value\n10,0,20,90,5,0.1\n", ["unknown column 'theta_h'"]),
    "missing column": ("theta_i,phi_i,theta_o,value\n10,0,20,0.1\n", ["missing column 'phi_o'"]),
    "no geometry": ("a,b,value\n1,2,0.1\n", ["no geometry columns", "theta_i, phi_i, theta_o, phi_o or wi_x"]),
    "two geometries": (
        f"{GEOMETRY},wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,value\n" + "0," * 10 + "0.1\n",
        ["both angle and direction-vector columns"],
    ),
    "no value column": (f"{GEOMETRY}\n10,0,20,90\n", ["no value columns"]),
    "partial rgb": (f"{GEOMETRY},r,g\n10,0,20,90,0.1,0.2\n", ["missing column 'b'"]),
    "duplicate column": (f"{GEOMETRY},value,value\n10,0,20,90,0.1,0.1\n", ["column 'value' appears twice"]),
    "non-numeric cell": (
        f"{GEOMETRY},value\n10,0,20,90,0.1\n10,0,abc,90,0.1\n",
        ["row 2 (line 3), column theta_o: 'abc' is not a number"],
    ),
    "empty cell": (f"{GEOMETRY},value\n10,0,20,90,\n", ["row 1 (line 2), column value: an empty cell is not a number"]),
    "wrong cell count": (
        f"# c\n{GEOMETRY},value\n10,0,20,90,0.1\n10,0,20,0.1\n",
        ["row 2 (line 4): 4 cells, but the header names 5 columns"],
    ),
    "NaN": (
        f"{GEOMETRY},r,g,b\n10,0,20,90,0.1,nan,0.3\n",
        ["row 1 (line 2), column g: nan is not allowed (values must be finite)"],
    ),
    "infinite": (
        f"{GEOMETRY},value\n10,0,20,90,0.1\n10,0,20,90,inf\n",
        ["row 2 (line 3), column value: inf is not allowed"],
    ),
    "negative reflectance": (
        f"{GEOMETRY},value\n10,0,20,90,-0.01\n",
        ["row 1 (line 2), column value: -0.01: negative reflectance is not allowed"],
    ),
    "theta at the horizon": (
        f"{GEOMETRY},value\n10,0,90,90,0.1\n",
        ["column theta_o: 90 is outside [0, 90) degrees (directions must be above the horizon)"],
    ),
    "negative theta": (f"{GEOMETRY},value\n-10,0,20,90,0.1\n", ["column theta_i: -10 is outside [0, 90) degrees"]),
    "phi out of range": (f"{GEOMETRY},value\n10,400,20,90,0.1\n", ["column phi_i: 400 is outside [-360, 360] degrees"]),
    "direction below the horizon": (
        "wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,value\n0,0,1,0,0,1,0.1\n0.6,0,-0.8,0,0,1,0.1\n",
        ["row 2 (line 3), column wi_z: -0.8 ≤ 0: the direction is below the horizon"],
    ),
    "not a unit vector": (
        "wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,value\n0,0,2,0,0,1,0.1\n",
        ["columns wi_x, wi_y, wi_z: length 2 is not 1"],
    ),
    "empty file": ("", ["empty table (no header row and no data)"]),
    "only comments": ("# nothing here\n\n", ["empty table (no header row and no data)"]),
    "header only": (f"{GEOMETRY},value\n", ["empty table (a header row but no data rows)"]),
    "sigma not positive": (
        f"{GEOMETRY},value,sigma\n10,0,20,90,0.1,0\n",
        ["row 1 (line 2), column sigma: 0: sigma must be > 0"],
    ),
    "sigma of an unknown channel": (
        f"{GEOMETRY},r,g,b,sigma_x\n10,0,20,90,0.1,0.1,0.1,1\n",
        ["unknown column 'sigma_x'"],
    ),
    "sigma missing for a channel": (
        f"{GEOMETRY},r,g,b,sigma_r,sigma_g\n10,0,20,90,0.1,0.1,0.1,1,1\n",
        ["missing column 'sigma_b'"],
    ),
    "negative weight": (f"{GEOMETRY},value,weight\n10,0,20,90,0.1,-1\n", ["column weight: -1: weight must be ≥ 0"]),
    "all weights zero": (f"{GEOMETRY},value,weight\n10,0,20,90,0.1,0\n", ["every weight is 0"]),
}


def assert_bad_input(status, out, err, pieces, folder, before):
    assert status == 2
    assert err.startswith("brdffit: error: ") and err.count("\n") == 1, err
    for piece in pieces:
        assert piece in err, (piece, err)
    assert "Traceback" not in err
    assert sorted(os.listdir(folder)) == before, "nothing may be written"


@pytest.mark.parametrize("case", list(BAD_SAMPLES))
def test_bad_samples_file(case, tmp_path, capsys):
    text, pieces = BAD_SAMPLES[case]
    samples = tmp_path / "samples.csv"
    samples.write_text(text)
    before = sorted(os.listdir(tmp_path))
    status, out, err = run(["fit", samples, "-o", tmp_path / "result.json"], capsys)
    assert_bad_input(status, out, err, [str(samples), *pieces], tmp_path, before)


def test_not_a_text_file(tmp_path, capsys):
    samples = tmp_path / "samples.csv"
    samples.write_bytes(b"\xff\xfe\x00\x01binary")
    status, out, err = run(["fit", samples, "-o", tmp_path / "r.json"], capsys)
    assert_bad_input(status, out, err, [str(samples), "not a text file"], tmp_path, ["samples.csv"])


@pytest.mark.parametrize(
    ("argv", "pieces"),
    [
        (
            ["--model", "lafortun"],
            ["--model 'lafortun' is not a model; choose one of: lambert, ward, ward-aniso, ward-duer, cook-torrance"],
        ),
        (["--loss", "l3"], ["--loss 'l3' is not a loss; choose one of: log, l2, cosine, cbrt, relative"]),
        (["--fresnel", "schlick"], ["--fresnel does not apply to model ward"]),
        (["--model", "cook-torrance", "--fresnel", "glass"], ["--fresnel 'glass' is not known"]),
        (["--model", "lafortune", "--lobes", "0"], ["--lobes 0 is not allowed"]),
        (
            ["--quantity", "radiance"],
            ["--quantity 'radiance' is not allowed; choose one of: brdf, reflectance-factor, cosine-weighted"],
        ),
        (["--angles", "gradians"], ["--angles 'gradians' is not allowed"]),
        (["--max-theta", "0"], ["--max-theta 0.0 is not allowed"]),
        (["--max-theta", "abc"], ["argument --max-theta: invalid float value: 'abc'"]),
        (["--starts", "0"], ["--starts 0 is not allowed; give a whole number ≥ 1"]),
        (["--start", "{bad json"], ["--start (inline JSON): not valid JSON"]),
        (["--start", '{"rho_d": [0.1]}'], ["--start: ward: missing parameter 'rho_s'"]),
        (
            ["--model", "phong", "--start", '{"rho_d": [0.1, 0.1, 0.1], "rho_s": [0.1, 0.1, 0.1], "n": 1e9}'],
            ["--start: n = 1e+09 is far beyond its plausible range (≤ 10000), where a fit cannot move"],
        ),
        (["--dtype", "float16"], ["--dtype 'float16' is not allowed; choose one of: float64, float32"]),
        (["--bogus"], ["unrecognized arguments: --bogus"]),
    ],
)
def test_bad_options(argv, pieces, tmp_path, capsys):
    samples = tmp_path / "samples.csv"
    samples.write_text(EXAMPLE.read_text())
    status, out, err = run(["fit", samples, "-o", tmp_path / "result.json", *argv], capsys)
    assert_bad_input(status, out, err, pieces, tmp_path, ["samples.csv"])


def test_a_result_or_a_folder_given_for_another_file_is_named_so(tmp_path, capsys):
    """A result file given as samples said "no geometry columns", a folder given as a result "[Errno 21] Is a
    directory" (found trying the tool as a new user)."""
    result = tmp_path / "result.json"
    assert run(["fit", EXAMPLE, "--model", "lambert", "-o", result], capsys)[0] == 0
    for argv, piece in [
        (["info", result], f"{result}: a JSON file, not samples: samples are read from CSV, MERL, ALTA and ASTM"),
        (["fit", result, "-o", tmp_path / "again.json"], f"{result}: a JSON file, not samples"),
        (["export", tmp_path, "--to", "mitsuba", "-o", tmp_path / "x.xml"], f"{tmp_path}: is a folder; give a brdffit"),
    ]:
        status, out, err = run(argv, capsys)
        assert_bad_input(status, out, err, [piece], tmp_path, ["result.json"])


def test_missing_file(tmp_path, capsys):
    status, out, err = run(["fit", tmp_path / "absent.csv", "-o", tmp_path / "result.json"], capsys)
    assert_bad_input(status, out, err, [f"{tmp_path / 'absent.csv'}: no such file"], tmp_path, [])


def test_output_folder_must_exist(tmp_path, capsys):
    status, out, err = run(["fit", EXAMPLE, "-o", tmp_path / "nowhere" / "r.json"], capsys)
    assert_bad_input(status, out, err, ["-o", "folder", "does not exist"], tmp_path, [])


def test_usage_errors_are_one_line(capsys):
    status, _, err = run([], capsys)
    assert status == 2 and err.count("\n") == 1 and "the following arguments are required: COMMAND" in err
    status, _, err = run(["fit"], capsys)
    assert status == 2 and err.count("\n") == 1 and "SAMPLES" in err


# ------------------------------------------------------------------ working runs
def test_fit_prints_a_table_and_writes_the_result(tmp_path, capsys):
    output = tmp_path / "result.json"
    status, out, err = run(["fit", EXAMPLE, "--model", "ward", "-o", output], capsys)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[0] == f"ward fit of {EXAMPLE}: 10368 samples × 3 channel(s), loss log"
    assert lines[1].split() == ["parameter", "r", "g", "b"]
    assert [line.split()[0] for line in lines[2:5]] == ["rho_d", "rho_s", "alpha"]
    assert "converged" in lines[5] and lines[-1] == f"wrote {output}"

    content = json.loads(output.read_text())
    assert list(content) == ["brdffit_version", "model", "model_options", "channels", "params", "fit"]
    assert content["model"] == "ward" and content["model_options"] == {} and content["channels"] == ["r", "g", "b"]
    assert list(content["params"]) == ["rho_d", "rho_s", "alpha"]
    assert list(content["fit"]) == [
        "loss",
        "cost",
        "rmse",
        "n_samples",
        "n_steps",
        "converged",
        "message",
        "dtype",
        "warnings",
        "quantity",
        "max_theta",
        "reading",
        "fixed",
        "bounds",
        "n_values",
        "sigma",
    ]
    assert content["fit"]["converged"] is True and content["fit"]["n_samples"] == 10368
    assert content["fit"]["n_values"] == 10368 * 3 and content["fit"]["sigma"] is False
    assert content["fit"]["quantity"] == "brdf" and content["fit"]["max_theta"] is None
    # The example was made from these parameters with 1% noise (Makefile target `examples`).
    truth = json.loads(EXAMPLE_PARAMS.read_text())
    for name in ("rho_d", "rho_s"):
        np.testing.assert_allclose(content["params"][name], truth[name], rtol=0.01)
    assert content["params"]["alpha"] == pytest.approx(truth["alpha"], rel=0.01)
    assert oct(output.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_default_output_name(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, _, _ = run(["fit", EXAMPLE, "--model", "lambert"], capsys)
    assert status == 0 and (tmp_path / "ward-pickled-oak.lambert.json").exists()


def test_not_converged_exits_1_and_still_writes(tmp_path, capsys):
    output = tmp_path / "result.json"
    status, out, err = run(["fit", EXAMPLE, "--model", "cook-torrance", "--max-steps", "2", "-o", output], capsys)
    assert status == 1
    assert "NOT converged" in out and err.startswith(f"brdffit: warning: {EXAMPLE}: the fit did not converge")
    result = load_result(output)
    assert result.converged is False and result.message


def test_synth_then_fit_round_trip(tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"kd": [0.2], "ks": [0.4], "m": 0.2, "f0": 0.3}))
    samples = tmp_path / "ct.csv"
    status, out, err = run(
        [
            "synth",
            "--model",
            "cook-torrance",
            "--params",
            params,
            "--geometry",
            "random",
            "--n-samples",
            "3000",
            "--noise",
            "0.005",
            "--seed",
            "3",
            "-o",
            samples,
        ],
        capsys,
    )
    assert status == 0, err
    assert out.strip() == f"wrote 3000 samples × 1 channel(s) of cook-torrance to {samples}"
    assert load_samples(samples).n_samples == 3000
    status, out, err = run(["fit", samples, "--model", "cook-torrance", "-o", tmp_path / "ct.json"], capsys)
    assert status == 0, err
    fitted = load_result(tmp_path / "ct.json").params
    assert fitted["m"] == pytest.approx(0.2, rel=0.02) and fitted["f0"] == pytest.approx(0.3, rel=0.05)
    # A result file works as --params, and carries its model.
    status, out, err = run(
        ["synth", "--params", tmp_path / "ct.json", "--geometry", "in-plane", "-o", tmp_path / "again.csv"], capsys
    )
    assert status == 0 and "of cook-torrance" in out


def test_synth_keeps_a_result_files_channel_names(tmp_path, capsys):
    result = {
        "model": "lambert",
        "model_options": {},
        "channels": ["x", "y", "z"],
        "params": {"rho_d": [0.2, 0.3, 0.4]},
    }
    (tmp_path / "xyz.json").write_text(json.dumps(result))
    status, _, err = run(["synth", "--params", tmp_path / "xyz.json", "-o", tmp_path / "xyz.csv"], capsys)
    assert status == 0, err
    assert load_samples(tmp_path / "xyz.csv").channels == ("x", "y", "z")


def test_synth_sigma_column(tmp_path, capsys):
    status, _, err = run(
        [
            "synth",
            "--model",
            "lambert",
            "--params",
            '{"rho_d": [0.5]}',
            "--noise",
            "0.02",
            "--sigma-column",
            "--geometry",
            "random",
            "--n-samples",
            "10",
            "-o",
            tmp_path / "s.csv",
        ],
        capsys,
    )
    assert status == 0, err
    samples = load_samples(tmp_path / "s.csv")
    np.testing.assert_allclose(samples.sigma, 0.02 * 0.5 / np.pi, rtol=1e-15)


@pytest.mark.parametrize(
    ("argv", "piece"),
    [
        (["--model", "ward", "--params", "{}"], "ward: missing parameter 'rho_d'"),
        (["--params", '{"rho_d": [0.1]}'], "--model is required unless --params is a result file"),
        (
            ["--model", "lambert", "--params", '{"rho_d": [0.1]}', "--geometry", "spiral"],
            "--geometry 'spiral' is not known",
        ),
        (
            ["--model", "lambert", "--params", '{"rho_d": [0.1]}', "--n-phi", "4", "--geometry", "random"],
            "--n-phi does not apply to --geometry random",
        ),
        (["--model", "lambert", "--params", '{"rho_d": [0.1]}', "--n-theta", "0"], "--n-theta 0 is not allowed"),
        (
            ["--model", "lambert", "--params", '{"rho_d": [0.1]}', "--noise-kind", "pink"],
            "--noise-kind 'pink' is not allowed",
        ),
        (["--model", "lambert", "--params", '{"rho_d": [0.1]}', "--noise", "-1"], "--noise -1.0 is not allowed"),
        (["--model", "lambert", "--params", "missing.json"], "--params missing.json: no such file"),
    ],
)
def test_synth_bad_input(argv, piece, tmp_path, capsys):
    status, out, err = run(["synth", *argv, "-o", tmp_path / "s.csv"], capsys)
    assert_bad_input(status, out, err, [piece], tmp_path, [])


def test_models_lists_every_model_with_domains(capsys):
    status, out, _ = run(["models"], capsys)
    assert status == 0
    for name in ("lambert", "ward", "ward-aniso", "ward-duer", "cook-torrance", "blinn-phong", "phong", "lafortune"):
        assert f"\n{name}\n" in f"\n{out}"
    assert (
        "alpha: > 0" in out
        and "f0: [0, 1]" in out
        and "--fresnel conductor: kd: [C] ≥ 0; ks: [C] ≥ 0 (held at 1 unless freed); m: > 0; eta: [C] > 0; k: [C] ≥ 0"
        in out
    )


def test_help_and_version(capsys):
    status, out, _ = run(["--version"], capsys)
    assert status == 0 and out.strip() == "brdffit 0.1.0"
    status, out, _ = run(["fit", "--help"], capsys)
    assert status == 0 and "--max-theta DEG" in out and "--loss NAME" in out


def test_output_piped_into_a_closed_reader(tmp_path):
    """`brdffit fit … | head`: no traceback, and the result is written before anything is printed."""
    script = Path(sys.executable).with_name("brdffit")
    output = tmp_path / "r.json"
    pipeline = f"'{script}' fit '{EXAMPLE}' --model lambert -o '{output}' | true"  # the reader is gone at once
    done = subprocess.run(["bash", "-c", pipeline], capture_output=True, text=True, check=False)
    assert done.stderr == "" and output.exists()


def test_console_script_and_checkout_shim(tmp_path):
    """`brdffit` (installed) and `python cli.py` (checkout) are the same program, in a fresh process."""
    script = Path(sys.executable).with_name("brdffit")
    for command in ([str(script)], [sys.executable, str(ROOT / "cli.py")]):
        done = subprocess.run(
            [*command, "fit", str(tmp_path / "absent.csv")], capture_output=True, text=True, check=False
        )
        assert done.returncode == 2 and done.stderr == f"brdffit: error: {tmp_path / 'absent.csv'}: no such file\n"
        assert done.stdout == ""


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_commands_help_ends_with_examples_that_parse(command, capsys):
    """``brdffit COMMAND --help`` ends with two or three examples, and each is a command line the parser accepts (its
    files need not exist: parsing checks the flags and their values' forms)."""
    import shlex

    from brdffit.cli import EXAMPLES, build_parser

    assert main([command, "--help"]) == 0
    shown = capsys.readouterr().out.rstrip().splitlines()
    examples = EXAMPLES[command]
    assert 2 <= len(examples) <= 3 and shown[-len(examples) - 1 :] == ["examples:", *(f"  {e}" for e in examples)]
    for example in examples:
        words = shlex.split(example.split(" | ")[0])
        assert words[:2] == ["brdffit", command]
        build_parser(command).parse_args(words[1:])  # a usage error raises


@pytest.mark.parametrize("where", ["before", "after"])
def test_quiet_prints_nothing_but_keeps_the_product_and_the_warnings(where, tmp_path, capsys):
    """``-q`` (before or after the command): no table, no ``wrote`` line; the file is written; with ``-o -`` the
    result alone reaches standard output; warnings still reach standard error."""
    quiet = ["-q", "fit"] if where == "before" else ["fit", "-q"]
    output = tmp_path / "oak.json"
    assert main([*quiet, EXAMPLE, "--model", "lambert", "-o", output]) == 0
    out, _ = capsys.readouterr()
    assert out == "" and load_result(output).model == "lambert"
    assert main([*quiet, EXAMPLE, "--model", "cook-torrance", "--fresnel", "conductor", "-o", "-"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["model"] == "cook-torrance"
    assert "brdffit: warning:" in err and "cost" not in err  # the caveats, not the table


def test_info_models_and_batch_fits_print_json_for_scripts(tmp_path, capsys):
    """``--json``: ``info`` gives the numbers its lines show, ``models`` every model with its parameters, and a batch
    of fits one object per samples file with the result file it wrote; ``--json`` with ``-o -`` is refused (both
    would go to standard output)."""
    from brdffit import MODELS

    assert main(["info", EXAMPLE, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert main(["info", EXAMPLE]) == 0
    text = capsys.readouterr().out
    assert info["n_samples"] == 10368 and info["channels"] == ["r", "g", "b"]
    assert f"{info['n_samples']} samples × 3 channel(s)" in text and f"{info['light_directions']} distinct" in text
    assert f"median {info['values']['g']['median']:.4g}" in text and info["quantity"]["read_as"] == "brdf"
    assert main(["models", "--json"]) == 0
    models = {one["name"]: one for one in json.loads(capsys.readouterr().out)}
    assert list(models) == list(MODELS)
    assert [p["name"] for p in models["ward"]["parameters"]] == ["rho_d", "rho_s", "alpha"]
    conductor = models["cook-torrance"]["parameters_by_option"]["fresnel"]["conductor"]
    assert {p["name"]: p["held"] for p in conductor}["ks"] == 1.0
    copies = [tmp_path / name for name in ("a.csv", "b.csv")]
    for copy in copies:
        copy.write_bytes(Path(EXAMPLE).read_bytes())
    assert main(["fit", *copies, "--model", "lambert", "-o", f"{tmp_path / 'fits'}/", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [row["samples"] for row in rows] == [str(copy) for copy in copies]
    assert all(load_result(row["result"]).cost == row["cost"] and row["error"] is None for row in rows)
    assert main(["fit", EXAMPLE, "--model", "lambert", "-o", "-", "--json"]) == 2
    assert "--json prints to standard output, where -o - sends the result" in capsys.readouterr().err


def test_shell_completion_completes_commands_options_and_file_names(tmp_path, capsys):
    """``--print-completion bash`` prints shtab's script for every command; bash, sourcing it, completes a command, an
    option and a file name where an argument names a file (what a user's shell does on Tab)."""
    import shutil

    assert main(["--print-completion", "bash"]) == 0
    script = tmp_path / "brdffit.bash"
    script.write_text(capsys.readouterr().out)
    (tmp_path / "oak.csv").write_text("")
    if shutil.which("bash") is None:
        pytest.skip("bash is not installed")

    def complete(*words: str) -> list[str]:
        line = " ".join(["brdffit", *words])
        code = (
            f"source {script}; COMP_WORDS=(brdffit {' '.join(words)}); COMP_CWORD={len(words)};"
            f" COMP_LINE='{line}'; COMP_POINT={len(line)}; _shtab_brdffit; echo ${{COMPREPLY[@]}}"
        )
        done = subprocess.run(["bash", "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=60)
        assert done.returncode == 0, done.stderr
        return done.stdout.split()

    assert complete("ex") == ["export"]
    assert complete("export", "--t") == ["--to"]
    assert complete("fit", "oa") == ["oak.csv"]
    assert main(["--print-completion", "fish"]) == 2
    assert "--print-completion takes one shell: bash, zsh, tcsh" in capsys.readouterr().err


def test_a_fits_caveats_are_said_once_where_the_table_is_seen(tmp_path, monkeypatch, capsys):
    """The table lists a fit's caveats; the ``brdffit: warning:`` lines repeat them on standard error only where the
    table went elsewhere (standard output a file or a pipe). On a terminal, and with ``-o -`` (the table on standard
    error), each caveat is printed once."""
    argv = ["fit", EXAMPLE, "--model", "cook-torrance", "--fresnel", "conductor", "-o"]
    assert main([*argv, "-"]) == 0
    err = capsys.readouterr().err
    caveat = "k[r] = 1e-12 lies on an end of its domain"
    assert err.count(caveat) == 1 and f"  warning: {caveat}" in err
    assert main([*argv, tmp_path / "a.json"]) == 0  # standard output captured, as a pipe: standard error says them too
    out, err = capsys.readouterr()
    assert out.count(caveat) == 1 and err.count(caveat) == 1
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main([*argv, tmp_path / "b.json"]) == 0  # a terminal: the table is seen, its caveats not said again
    out, err = capsys.readouterr()
    assert out.count(caveat) == 1 and caveat not in err
