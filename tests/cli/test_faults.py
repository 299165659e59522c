"""Faults while a command writes (issue 29 items 4 and 5): a full disk or a folder that cannot be written is one line
naming the file, exit status 2, the old file kept and no temporary left; an interrupt (SIGINT, even one that JAX
swallows) writes nothing and exits 130; SIGTERM during MCMC leaves no temporary chain."""

import errno
import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest
from paths import EXAMPLE, ROOT

import brdffit._files
import brdffit.api
from brdffit.cli import main

OLD = "the old file\n"


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def full_disk(monkeypatch, output):
    """The atomic write of ``output`` fails as on a full disk, at the rename (after its temporary was written)."""
    replace = os.replace

    def failing(source, destination):
        if os.fspath(destination) == os.fspath(output):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return replace(source, destination)

    monkeypatch.setattr(brdffit._files.os, "replace", failing)


def unwritable_folder(monkeypatch, output):
    """``output``'s folder refuses a new file for it (as a folder made read-only after the command's checks)."""
    mkstemp = brdffit._files.tempfile.mkstemp

    def failing(*args, prefix="", **kwargs):
        if prefix == f".{output.stem}.":
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))
        return mkstemp(*args, prefix=prefix, **kwargs)

    monkeypatch.setattr(brdffit._files.tempfile, "mkstemp", failing)


def commands(files, out):
    """Each writing command with its output ``out`` (the file the fault must leave alone)."""
    return {
        "fit": ["fit", files / "ward.csv", "--model", "lambert", "-o", out.with_suffix(".json")],
        "synth": ["synth", "--model", "lambert", "--params", '{"rho_d": [0.5]}', "-o", out.with_suffix(".csv")],
        "convert": ["convert", files / "ward.csv", out.with_suffix(".csv")],
        "export": ["export", files / "ward.json", "--to", "gltf", "-o", out.with_suffix(".gltf")],
        "plot": ["plot", files / "ward.json", files / "ward.csv", "--kind", "slices", "-o", out.with_suffix(".png")],
        "--chain": [
            *["fit", files / "ward.csv", "--model", "lambert", "--uncertainty", "mcmc", "--walkers", "8"],
            *["--steps", "60", "--burn", "10", "-o", out.parent / "result.json", "--chain", out.with_suffix(".npz")],
        ],
        "--corner": [
            *["fit", files / "ward.csv", "--model", "lambert", "--uncertainty", "laplace"],
            *["-o", out.parent / "result.json", "--corner", out.with_suffix(".png")],
        ],
    }


@pytest.mark.parametrize("fault", [full_disk, unwritable_folder])
@pytest.mark.parametrize("command", ["fit", "synth", "convert", "export", "plot", "--chain", "--corner"])
def test_a_failed_write_is_one_line_naming_the_file_and_keeps_the_old_file(
    files, tmp_path, capsys, monkeypatch, command, fault
):
    argv = commands(files, tmp_path / "out")[command]
    output = argv[argv.index(command) + 1] if command.startswith("--") else argv[-1]
    output.write_text(OLD)
    fault(monkeypatch, output)
    status, _, err = run(argv, capsys)
    lines = err.splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].startswith("brdffit: error: "), err
    assert str(output) in lines[0] and "cannot be written" in lines[0], err
    assert output.read_text() == OLD
    assert not [path.name for path in tmp_path.iterdir() if ".tmp" in path.name]


def test_an_output_linked_to_a_pipe_is_refused_before_the_fit(files, tmp_path, capsys, no_fit):
    """``-o /dev/stdout`` with standard output a pipe: the link's resolved name (``pipe:[…]``) names nothing, so
    the check passed and the write failed after the fit, with a traceback."""
    reader, writer = os.pipe()
    try:
        link = tmp_path / "stdout"
        link.symlink_to(f"/proc/self/fd/{writer}")
        status, _, err = run(["fit", files / "ward.csv", "-o", link], capsys)
    finally:
        os.close(reader)
        os.close(writer)
    assert status == 2 and err.count("\n") == 1 and "is not a regular file (a device or a pipe)" in err, err


def swallowed_interrupt(monkeypatch):
    """The fit runs, and in the middle SIGINT arrives and its KeyboardInterrupt is swallowed, as JAX's
    ``_xla_gc_callback`` does ("Exception ignored in …"): the fit goes on and returns its result."""
    real_fit = brdffit.api.fit

    def fit_interrupted(*args, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler runs here
        except KeyboardInterrupt:
            pass
        return real_fit(*args, **kwargs)

    monkeypatch.setattr(brdffit.api, "fit", fit_interrupted)


@pytest.mark.parametrize("to_stdout", [False, True])
def test_a_swallowed_interrupt_writes_nothing_and_exits_130(files, tmp_path, capsys, monkeypatch, to_stdout):
    output = tmp_path / "result.json"
    output.write_text(OLD)
    # Python's own handler, whatever this process was started with (nohup ignores SIGINT, which brdffit then leaves).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    swallowed_interrupt(monkeypatch)
    status, out, err = run(
        ["fit", files / "ward.csv", "--model", "lambert", "-o", "-" if to_stdout else output], capsys
    )
    assert status == 130 and err.endswith("brdffit: interrupted\n") and err.count("brdffit: ") == 1, err
    assert "{" not in out and output.read_text() == OLD
    assert sorted(path.name for path in tmp_path.iterdir()) == ["result.json"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is the caller's again
    signal.signal(signal.SIGINT, previous)
    brdffit._files.write_text_atomic(output, "{}")  # and writes are allowed again: the stop was the command's


def test_an_ignored_interrupt_stays_ignored(files, tmp_path, capsys):
    """A command started with SIGINT ignored (``nohup``, a background job) leaves it ignored, as Python does."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        status, _, err = run(["fit", files / "ward.csv", "--model", "lambert", "-o", tmp_path / "r.json"], capsys)
        assert status == 0, err
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("suffix", [".npz", ".h5"])
def test_sigterm_during_mcmc_leaves_no_temporary(tmp_path, suffix):
    """A command killed by SIGTERM while it samples: exit status 143, one line, no ``.tmp.npz``/``.tmp.h5`` left."""
    if suffix == ".h5":
        pytest.importorskip("h5py")
    chain = tmp_path / f"chain{suffix}"
    argv = [sys.executable, ROOT / "cli.py", "fit", EXAMPLE, "--model", "lambert", "--uncertainty", "mcmc"]
    argv += ["--steps", "1000000", "--burn", "10", "-o", tmp_path / "r.json", "--chain", chain]
    process = subprocess.Popen(
        [str(a) for a in argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path
    )
    deadline = time.monotonic() + 120
    while not [path for path in tmp_path.iterdir() if ".tmp" in path.name]:  # the chain's temporary: sampling
        assert process.poll() is None and time.monotonic() < deadline, process.communicate()
        time.sleep(0.1)
    time.sleep(1.0)
    process.send_signal(signal.SIGTERM)
    try:  # the stop is seen between chunks of steps: seconds, more on a loaded machine
        _, err = process.communicate(timeout=180)
    finally:  # a process that did not stop is killed, and its pipes closed (else they leak into the next test)
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 143 and err.strip().splitlines()[-1] == "brdffit: terminated", err
    assert sorted(path.name for path in tmp_path.iterdir()) == []


def test_a_write_error_in_python_is_an_os_error_naming_the_file(tmp_path, monkeypatch):
    """The library raises it too (an ``OSError``, for code that catches those), and leaves no temporary."""
    full_disk(monkeypatch, tmp_path / "r.json")
    with pytest.raises(OSError, match=re.escape("r.json: cannot be written (No space left on device)")):
        brdffit._files.write_text_atomic(tmp_path / "r.json", json.dumps({}))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["fit", "compare"])
def test_a_result_for_standard_output_whose_reader_went_away_is_a_write_error(tmp_path, command):
    """``-o -`` into a pipe whose reader closed before the result: the result is lost, so exit status 2 and one line
    (it was 0, as for a table printed into ``| head``, where the files are written)."""
    argv = [sys.executable, ROOT / "cli.py", command, EXAMPLE, "-o", "-"]
    argv += ["--model", "lambert"] if command == "fit" else ["--models", "lambert", "--folds", "2"]
    process = subprocess.Popen(
        [str(a) for a in argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path
    )
    process.stdout.close()  # the reader goes away before the result
    err = process.stderr.read()
    process.stderr.close()
    assert process.wait(timeout=300) == 2, err
    assert err.strip().splitlines()[-1].startswith("brdffit: error: -o -: standard output was closed"), err
    assert "Traceback" not in err and "Exception ignored" not in err


def test_a_swallowed_sigterm_still_stops_a_long_chain(tmp_path, capsys):
    """A SIGTERM whose exception Python swallowed (raised inside a gc callback: "Exception ignored in …") has still
    stopped writes; the MCMC sees the stop at its next step and the command ends as terminated (143, one line), not
    after its million steps (a clean-clone run once waited 180 s on such a chain)."""
    import threading

    from brdffit import _files
    from brdffit.cli import Terminated, main

    argv = ["fit", str(EXAMPLE), "--model", "lambert", "--uncertainty", "mcmc", "--steps", "1000000"]
    timer = threading.Timer(2.0, _files.stop_writing, args=(Terminated,))  # the handler's stop, without its raise
    timer.start()
    try:
        status = main([*argv, "-o", str(tmp_path / "r.json")])
    finally:
        timer.cancel()
    assert status == 143 and capsys.readouterr().err.strip().endswith("brdffit: terminated")
    assert list(tmp_path.iterdir()) == []
