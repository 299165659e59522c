"""Hostile and absurd inputs (issue 29, item 6): each is one line and exit status 2 before the work, or a documented
cap, never a traceback, a hang or an allocation the input did not pay for."""

import contextlib
import io
import json
import os
import re
import socket
import subprocess
import sys
import threading
import types
import zipfile

import numpy as np
import pytest
from paths import ROOT

import brdffit.api
import brdffit.datadriven.basis
from brdffit import data_synth, fit, save_samples
from brdffit.cli import main
from brdffit.datadriven.basis import load_basis
from brdffit.errors import BrdfInputError


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def one_line_error(status, err, *pieces):
    assert status == 2 and err.startswith("brdffit: error: ") and err.count("\n") == 1, err
    for piece in pieces:
        assert piece in err, err


def _edited(result: dict, edit) -> str:
    content = json.loads(json.dumps(result))
    edit(content)
    return json.dumps(content)


@pytest.mark.parametrize(
    "text, piece",
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        (lambda r: json.dumps(r).replace('"n_samples": 432', '"n_samples": Infinity'), "Infinity is not a JSON number"),
        (lambda r: json.dumps(r).replace('"n_steps": ', '"n_steps": 1e400, "x": '), "1e400 is beyond float64's range"),
        (lambda r: _edited(r, lambda c: c.update(model=["ward"])), "model must be a JSON string"),
        (lambda r: _edited(r, lambda c: c.update(model_options=[])), "model_options must be a JSON object"),
        (lambda r: _edited(r, lambda c: c.update(channels="value")), "channels must be a JSON list"),
        (lambda r: _edited(r, lambda c: c.update(params=[1])), "params must be a JSON object"),
    ],
    ids=["deep", "infinity", "overflow", "model-list", "options-list", "channels-string", "params-list"],
)
def test_a_bad_result_file_is_one_line(files, tmp_path, capsys, text, piece):
    result = json.loads((files / "ward.json").read_text())
    assert result["fit"]["n_samples"] == 432  # what the edits replace
    bad = tmp_path / "bad.json"
    bad.write_text(text(result) if callable(text) else text)
    for argv in (
        ["export", bad, "--to", "gltf", "-o", tmp_path / "x.gltf"],
        ["plot", bad, files / "ward.csv", "-o", f"{tmp_path}/figures/"],
    ):
        status, _, err = run(argv, capsys)
        one_line_error(status, err, str(bad), piece)
    assert sorted(path.name for path in tmp_path.iterdir()) == ["bad.json"]


def test_a_bad_comparison_entry_is_one_line(files, tmp_path, capsys):
    comparison = {
        "samples": "x.csv",
        "n_samples": 3,
        "channels": ["value"],
        "loss": "log",
        "folds": 5,
        "fold_kind": "random",
        "seed": 0,
        "criterion": "cv_loss",
        "models": [{"model": ["ward"], "model_options": [], "params": {}}],
    }
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(comparison))
    status, _, err = run(["export", bad, "--to", "gltf", "-o", tmp_path / "x.gltf"], capsys)
    one_line_error(status, err, "models[].model must be a JSON string")


@pytest.mark.parametrize(
    "start, piece",
    [
        ('{"rho_d": [Infinity]}', "Infinity is not a JSON number"),
        ('{"a": ' * 100_000 + "1" + "}" * 100_000, "nested too deeply"),
    ],
)
def test_bad_inline_json_is_one_line(files, capsys, no_fit, start, piece):
    status, _, err = run(["fit", files / "ward.csv", "--start", start], capsys)
    one_line_error(status, err, "--start (inline JSON): not valid JSON", piece)


def test_a_json_file_larger_than_any_brdffit_writes_is_refused_unread(tmp_path, capsys, files):
    huge = tmp_path / "huge.json"
    with huge.open("w") as stream:
        stream.truncate(65 * 2**20)  # 65 MiB of NUL characters: never parsed
    status, _, err = run(["export", huge, "--to", "gltf", "-o", tmp_path / "x.gltf"], capsys)
    one_line_error(status, err, "larger than 64 MiB")


def _npz(members: dict[str, bytes], compression=zipfile.ZIP_STORED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def _npy_header(shape: tuple, descr: str = "<f4") -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": descr, "fortran_order": False, "shape": shape})
    return buffer.getvalue()


def test_a_basis_declaring_five_tebibytes_is_refused_before_allocating(tmp_path):
    """numpy allocates what a member's header declares before reading it: 5 TiB in a file of a few hundred bytes."""
    path = tmp_path / "big.npz"
    path.write_bytes(_npz({"components.npy": _npy_header((5 * 2**40 // 4,)) + bytes(16)}))
    with pytest.raises(BrdfInputError, match=r"components.npy declares an array of shape \(1374389534720,\)"):
        load_basis(path)


def test_a_basis_that_expands_beyond_its_size_is_refused(tmp_path, monkeypatch):
    """A zip bomb: zeros compress ~1000 to 1 (200 components from 10 MB); a basis's float32 components do not. The
    slack is set to 0 here so that a 40 MB bomb shows the rule (the real one allows 64 MiB besides)."""
    monkeypatch.setattr(brdffit.datadriven.basis, "EXPANSION_SLACK", 0)
    zeros = _npy_header((10_000_000,)) + bytes(40_000_000)
    path = tmp_path / "bomb.npz"
    path.write_bytes(_npz({"components.npy": zeros}, zipfile.ZIP_DEFLATED))
    with pytest.raises(BrdfInputError, match=re.escape("bomb.npz: expands to 38 MiB from 0.0 MiB")):
        load_basis(path)


def test_an_npy_renamed_npz_is_not_a_basis(tmp_path):
    path = tmp_path / "renamed.npz"
    with path.open("wb") as stream:
        np.save(stream, np.zeros(3))
    with pytest.raises(BrdfInputError, match=re.escape("renamed.npz: not a basis file")):
        load_basis(path)


def _cli(*argv, timeout=60):
    """The command line in a process of its own: a hang (a FIFO, /dev/zero) fails by the timeout, not the suite."""
    return subprocess.run(
        [sys.executable, str(ROOT / "cli.py"), *map(str, argv)], capture_output=True, text=True, timeout=timeout
    )


@pytest.mark.parametrize("command", [["info"], ["fit"], ["convert", "IN", "out.csv"]])
def test_a_device_or_a_fifo_input_is_refused(tmp_path, command):
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    for source in ("/dev/zero", fifo):
        argv = [source if word == "IN" else tmp_path / word if word.endswith(".csv") else word for word in command]
        if len(command) == 1:
            argv.append(source)
        done = _cli(*argv)
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert f"{source}: is not a regular file (a device or a pipe)" in done.stderr


SYNTH = ["synth", "--model", "lambert", "--params", '{"rho_d": [0.5]}']


@pytest.mark.parametrize(
    "argv, piece",
    [
        (
            [*SYNTH, "--n-theta", "10000000"],
            "--n-incident 8 × --n-theta 10000000 × --n-phi 36 is 2,880,000,000 direction pairs; at most 2,000,000",
        ),
        (
            [*SYNTH, "--geometry", "random", "--n-samples", "1000000000000"],
            "--n-samples 1000000000000 is 1,000,000,000,000 direction pairs; at most 2,000,000",
        ),
    ],
)
def test_synth_sizes_are_capped_before_anything_is_made(tmp_path, capsys, argv, piece):
    status, _, err = run([*argv, "-o", tmp_path / "s.csv"], capsys)
    one_line_error(status, err, piece)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "options, piece",
    [
        (["--max-steps", "1000000000000"], "--max-steps 1000000000000 is not allowed; give a whole number from 1 to"),
        (["--uncertainty", "mcmc", "--walkers", "1000000000"], "--walkers 1000000000 is not allowed; give a whole"),
        (["--uncertainty", "mcmc", "--walkers", "5000", "--steps", "100000"], "is 500,000,000 chain positions"),
    ],
)
def test_fit_sizes_are_capped_before_the_fit(files, tmp_path, capsys, no_fit, options, piece):
    status, _, err = run(["fit", files / "ward.csv", *options, "-o", tmp_path / "r.json"], capsys)
    one_line_error(status, err, piece)


def test_a_dollar_in_a_channel_name_is_drawn_as_typed(tmp_path, capsys):
    """matplotlib reads text between two ``$`` as math: a channel named ``$r^^$`` failed every figure."""
    samples = data_synth.synthesize("lambert", {"rho_d": [0.3]}, *data_synth.hemisphere_grid(4, 9, 12))
    csv = tmp_path / "dollar.csv"
    save_samples(samples, csv)
    csv.write_text(csv.read_text().replace(",value", ",$r^^$", 1))
    fit(str(csv), "lambert").save(tmp_path / "dollar.json")
    status, _, err = run(["plot", tmp_path / "dollar.json", csv, "-o", f"{tmp_path}/figures/"], capsys)
    assert status == 0 and err == "", err
    assert len(list((tmp_path / "figures").iterdir())) == 4


@pytest.fixture
def not_dask():
    """A TCP service that answers anything with an HTTP response (not Dask's protocol); its address."""
    server = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        while not stop.is_set():
            try:
                connection, _ = server.accept()
            except OSError:
                return
            with connection:
                with contextlib.suppress(OSError):
                    connection.recv(1024)
                    connection.sendall(b"HTTP/1.0 200 OK\r\nContent-Type: text/plain\r\n\r\nnot dask\n" * 50)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    server.close()
    thread.join(timeout=10)


@pytest.mark.slow
def test_a_scheduler_address_that_is_not_dask_is_one_line(files, tmp_path, capsys, no_fit, not_dask):
    """Dask read the HTTP bytes as a frame length and asked for 3 EiB: a MemoryError traceback, exit 1."""
    pytest.importorskip("distributed", reason="dask[distributed] (the cluster extra) is not installed")
    status, _, err = run(["fit", files / "ward.csv", "--scheduler", not_dask, "-o", tmp_path / "r.json"], capsys)
    one_line_error(status, err, f"--scheduler {not_dask}: no Dask scheduler answers there")
    assert list(tmp_path.iterdir()) == []


def test_workers_killed_by_a_fit_are_one_line(files, tmp_path, capsys, monkeypatch):
    """Dask gives up on a task that killed its workers (``KilledWorker``): one line, exit 2, nothing written."""
    distributed = pytest.importorskip("distributed", reason="dask[distributed] (the cluster extra) is not installed")

    def killed(*args, **kwargs):
        raise distributed.KilledWorker("fit-3f2a", types.SimpleNamespace(address="tcp://127.0.0.1:40000"), 3)

    monkeypatch.setattr(brdffit.api, "fit_batch", killed)
    # no real cluster (tests/test_cluster.py starts those): Dask's event loop, started in a worker that has run
    # hundreds of tests, once took over its 10 s to start
    monkeypatch.setattr(distributed, "LocalCluster", lambda **options: contextlib.nullcontext())
    monkeypatch.setattr(distributed, "Client", lambda cluster: contextlib.nullcontext("a client"))
    status, _, err = run(["fit", files / "ward.csv", "--workers", "1", "-o", tmp_path / "r.json"], capsys)
    one_line_error(
        status, err, "--workers 1: Dask workers died while fitting (attempted to run task 'fit-3f2a' on 4 different"
    )
    assert list(tmp_path.iterdir()) == []


def test_a_local_cluster_that_does_not_start_is_one_line(files, tmp_path, capsys, monkeypatch):
    """Dask's event loop that does not start within its 10 s (a loaded machine) raises a bare ``AssertionError``:
    one line, exit 2, nothing written."""
    distributed = pytest.importorskip("distributed", reason="dask[distributed] (the cluster extra) is not installed")

    def not_started(**options):
        raise AssertionError

    monkeypatch.setattr(distributed, "LocalCluster", not_started)
    status, _, err = run(["fit", files / "ward.csv", "--workers", "2", "-o", tmp_path / "r.json"], capsys)
    one_line_error(status, err, "--workers 2: a local Dask cluster did not start (AssertionError); nothing written")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", ["dict", "xml"])
def test_a_channel_name_cannot_put_code_or_markup_into_an_export(tmp_path, kind, capsys):
    """A result's channel name reaches the export's comments (``one channel (…): written as grey``): a line break in
    it must not end a Python comment and start code, nor ``-->`` end an XML comment and start elements."""
    import json
    import runpy
    import xml.etree.ElementTree as ElementTree

    from brdffit.cli import main

    marker = tmp_path / "ran"
    hostile = f"v\nimport pathlib; pathlib.Path({str(marker)!r}).touch()\n# --><bsdf type='diffuse'/><!--"
    result = {
        "model": "lambert",
        "model_options": {},
        "channels": [hostile],
        "params": {"rho_d": [0.3]},
        "fit": {"loss": "log", "cost": 0, "rmse": 0, "n_samples": 1, "n_steps": 1, "converged": True},
    }
    (tmp_path / "fit.json").write_text(json.dumps(result))
    output = tmp_path / ("fit.mitsuba.py" if kind == "dict" else "fit.xml")
    argv = ["export", str(tmp_path / "fit.json"), "--to", "mitsuba", "--format", kind, "-o", str(output)]
    assert main(argv) == 0
    if kind == "dict":
        loaded = runpy.run_path(str(output))
        assert not marker.exists() and loaded["bsdf"]["type"] == "diffuse"
    else:
        root = ElementTree.fromstring(output.read_text())
        assert root.tag == "bsdf" and len(root) == 1  # the diffuse BSDF and its reflectance, nothing injected
