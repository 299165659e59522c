"""``-`` is standard input for every input and standard output for every output (``cli/files.py``): read and written
as files are, with every check; the product alone on standard output, what the command says on standard error;
messages name ``-``; no temporary file is left."""

import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from paths import EXAMPLE, ROOT

from brdffit import FitResult, load_result
from brdffit.cli import main

WARD = FitResult(
    "ward", {}, ("r", "g", "b"), {"rho_d": [0.14, 0.09, 0.05], "rho_s": [0.036, 0.031, 0.021], "alpha": 0.146},
    "log", 0.0, 0.0, 1, 0, True,
)  # fmt: skip


@pytest.fixture
def stdin(monkeypatch):
    """``stdin(data)``: standard input holds ``data`` (bytes or text)."""

    def give(data):
        data = data if isinstance(data, bytes) else data.encode()
        monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))

    return give


@pytest.mark.slow
def test_samples_and_results_come_from_standard_input(stdin, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    temporary = tmp_path.parent / f"{tmp_path.name}-temporary"  # this test's own: another test's may come and go
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    stdin(Path(EXAMPLE).read_bytes())
    assert main(["info", "-"]) == 0
    assert capsys.readouterr().out.startswith("-: csv, 10368 samples × 3 channel(s)")
    stdin(Path(EXAMPLE).read_bytes())
    assert main(["fit", "-", "--model", "lambert"]) == 0  # named after standard input
    assert "lambert fit of -" in capsys.readouterr().out and load_result(tmp_path / "stdin.lambert.json")
    stdin(WARD.to_json())
    assert main(["export", "-", "--to", "mitsuba"]) == 0
    assert (
        'type="roughconductor"' in (tmp_path / "stdin.xml").read_text()
        or "blendbsdf" in (tmp_path / "stdin.xml").read_text()
    )
    capsys.readouterr()
    stdin('{"rho_d": [0.4]}')
    assert main(["synth", "--model", "lambert", "--params", "-", "--geometry", "in-plane", "-o", "grey.csv"]) == 0
    assert (tmp_path / "grey.csv").read_text().startswith("theta_i,phi_i,theta_o,phi_o,value")
    assert list(temporary.iterdir()) == []  # every temporary copy removed


@pytest.mark.slow
def test_products_go_to_standard_output_and_the_rest_to_standard_error(stdin, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    stdin(WARD.to_json())
    assert main(["export", "-", "--to", "mitsuba", "-o", "-"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("<!-- brdffit") and out.rstrip().endswith("</bsdf>")
    assert err.startswith("wrote -: a Mitsuba 3 BSDF of -")
    stdin(Path(EXAMPLE).read_bytes())
    assert main(["convert", "-", "-"]) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[:2] == Path(EXAMPLE).read_text().splitlines()[:2] and "to - (csv)" in err
    assert main(["synth", "--model", "lambert", "--params", '{"rho_d": [0.5]}', "-o", "-", "-q"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("theta_i,phi_i,theta_o,phi_o,value") and err == ""
    # every command says "wrote -" (plot named its temporary file, deleted by then; fit said nothing)
    assert main(["fit", str(EXAMPLE), "--model", "lambert", "-o", "-"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["model"] == "lambert" and err.rstrip().endswith("wrote -")
    assert sorted(path.name for path in tmp_path.iterdir()) == []  # nothing written here


def test_bad_input_on_standard_input_is_one_line_naming_it(stdin, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    stdin("theta_i,phi_i,theta_o,phi_o,value\n10,0,95,0,0.1\n")
    assert main(["info", "-"]) == 2
    assert capsys.readouterr().err.startswith("brdffit: error: -: row 1 (line 2), column theta_o: 95 is outside")
    stdin("{bad")
    assert main(["export", "-", "--to", "mitsuba", "-o", "-"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("brdffit: error: -: not a readable JSON file")
    assert main(["plot", "-", "-", "-o", "x.png"]) == 2
    assert "only one input can be - (standard input is one stream)" in capsys.readouterr().err


def test_a_figure_on_standard_output_says_wrote_dash(tmp_path):
    """``plot -o -`` said it wrote its temporary file, deleted by then (found trying the tool as a new user)."""
    result = tmp_path / "ward.json"
    WARD.save(result)
    argv = [sys.executable, "-m", "brdffit", "plot", str(result), str(EXAMPLE), "--kind", "slices", "-o", "-"]
    done = subprocess.run(argv, capture_output=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0 and done.stdout.startswith(b"\x89PNG"), done.stderr
    assert done.stderr.decode() == "wrote -\n"


def test_a_binary_product_reaches_standard_output_byte_for_byte(tmp_path):
    """A MERL table (34,992,012 bytes) through a pipe, as a shell gives it: the same bytes as the file ``-o`` writes."""
    result = tmp_path / "ward.json"
    WARD.save(result)
    run = [sys.executable, "-m", "brdffit", "export", str(result), "--to", "merl"]
    done = subprocess.run([*run, "-o", "-"], capture_output=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    assert subprocess.run([*run, "-o", "w.binary"], cwd=tmp_path, capture_output=True, timeout=300).returncode == 0
    assert len(done.stdout) == 34_992_012 and done.stdout == (tmp_path / "w.binary").read_bytes()
    assert done.stderr.decode().startswith("wrote -: a MERL table")
    assert json.loads(WARD.to_json())["model"] == "ward" and ROOT.exists()


def test_a_command_that_ran_jax_exits_at_once_with_its_output_whole(tmp_path):
    """``brdffit fit`` leaves without the interpreter's teardown once JAX ran (``cli._exit``): the result printed to a
    pipe is whole, the status is the command's, and a process with Dask loaded is left to tear down as usual."""
    fit = [sys.executable, "-m", "brdffit", "fit", str(EXAMPLE), "--model", "lambert", "-q"]
    done = subprocess.run([*fit, "-o", "-"], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0 and "Traceback" not in done.stderr
    assert json.loads(done.stdout)["model"] == "lambert"
    refused = subprocess.run([*fit, "--fix", "nope=1"], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert refused.returncode == 2 and refused.stderr.startswith("brdffit: error:")
    probe = (
        "import sys, brdffit.cli\n"
        "exits = []\n"
        "brdffit.cli.os._exit = lambda status: exits.append(status) or sys.exit(status)\n"
        "sys.modules['jax'] = sys.modules.get('jax') or __import__('jax')\n"
        "try:\n"
        "    brdffit.cli._exit(3)\n"
        "except SystemExit as leaving:\n"
        "    print(exits, leaving.code)\n"
        "exits.clear()\n"
        "import threading, time\n"
        "threading.Thread(target=time.sleep, args=(0.5,)).start()\n"
        "try:\n"
        "    brdffit.cli._exit(5)\n"
        "except SystemExit as leaving:\n"
        "    print(exits, leaving.code)\n"
        "sys.modules['distributed'] = object()\n"
        "exits.clear()\n"
        "try:\n"
        "    brdffit.cli._exit(4)\n"
        "except SystemExit as leaving:\n"
        "    print(exits, leaving.code)\n"
    )
    lines = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, check=True)
    assert lines.stdout.split("\n")[:3] == ["[3] 3", "[] 5", "[] 4"]  # a thread alive, Dask: the teardown runs
    # under a profiler the teardown runs, so that it writes its findings
    profile = tmp_path / "fit.prof"
    profiled = [sys.executable, "-m", "cProfile", "-o", str(profile), "-m", "brdffit", *fit[3:], "-o", "r.json"]
    assert subprocess.run(profiled, capture_output=True, cwd=tmp_path, timeout=300).returncode == 0
    assert profile.stat().st_size > 0
