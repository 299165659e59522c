"""Stored programs (``brdffit/_programs/stored.py``): a jitted function's program is kept on disk under a signature
computed without tracing, read back by a later call (or process) instead of tracing, and never trusted when it
is stale, unreadable or cannot be named."""

import hashlib
import hmac
import importlib.metadata
import json
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from paths import EXAMPLE, ROOT

from brdffit._programs import cache, jit
from brdffit._programs import stored as stored_programs
from brdffit.errors import InputWarning


def _scaled_sum(scale, x):
    return scale * jnp.sum(jnp.sin(x))


class Unnamed:
    """A static argument without a cache key: it names no program."""

    def __hash__(self):
        return 0

    def __eq__(self, other):
        return isinstance(other, Unnamed)


def _with_static(kind, x):
    return jnp.sum(x) * 2.0


scaled_sum = jit(_scaled_sum)
with_static = jit(_with_static, static_argnums=0)


@pytest.fixture
def programs(tmp_path, monkeypatch):
    """A cache of its own and an empty table of loaded programs; the folder of stored programs."""
    monkeypatch.setattr(cache, "_enabled", tmp_path)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    return tmp_path / "programs"


def stored_files(folder):
    return sorted(folder.glob(f"*{stored_programs.SUFFIX}"))


def test_a_program_is_stored_once_and_read_back_without_exporting(programs, monkeypatch):
    x = np.linspace(0.0, 1.0, 7)
    expected = 3.0 * np.sum(np.sin(x))
    assert float(scaled_sum(np.asarray(3.0), x)) == pytest.approx(expected, rel=1e-15)
    (stored,) = stored_files(programs)
    mac, header, _ = stored.read_bytes().split(b"\n", 2)
    assert len(mac) == 64 and json.loads(header) == {"named_tuples": []}

    monkeypatch.setattr(stored_programs, "_loaded", {})  # a later process: nothing loaded yet

    def no_export(*args, **kwargs):
        raise AssertionError("a stored program was exported again")

    monkeypatch.setattr(jax.export, "export", no_export)
    assert float(scaled_sum(np.asarray(3.0), x)) == pytest.approx(expected, rel=1e-15)
    assert stored_files(programs) == [stored]
    # another shape is another program
    monkeypatch.undo()
    monkeypatch.setattr(cache, "_enabled", programs.parent)
    scaled_sum(np.asarray(3.0), np.ones(5))
    assert len(stored_files(programs)) == 2


def test_a_stale_or_broken_program_is_never_read(programs, monkeypatch):
    x = np.arange(4.0)
    scaled_sum(np.asarray(2.0), x)
    (stored,) = stored_files(programs)
    # another brdffit source or JAX: another signature, another file
    monkeypatch.setattr(stored_programs, "_loaded", {})
    monkeypatch.setattr(stored_programs, "_environment", lambda: ["another source", "another jax"])
    assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    assert len(stored_files(programs)) == 2
    # a file cut short (a crash while writing elsewhere): exported again, the answer still right
    monkeypatch.undo()
    monkeypatch.setattr(cache, "_enabled", programs.parent)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    stored.write_bytes(stored.read_bytes()[:150])
    with pytest.warns(InputWarning, match="not signed by this cache"):
        assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    assert stored.stat().st_size > 150


def test_a_call_that_cannot_be_named_runs_as_a_plain_jit(programs):
    identity = ["m.f", ["tuple", []]]
    assert stored_programs._signature(identity, (Unnamed(), np.ones(3)), (0,)) is None
    assert float(with_static(Unnamed(), np.ones(3))) == 6.0
    assert stored_programs._signature(identity, (1.5, [1, 2]), ()) is None  # not arrays
    assert stored_files(programs) == []


def test_no_program_is_stored_while_the_cache_is_off(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "_enabled", None)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    assert float(scaled_sum(np.asarray(1.0), np.zeros(3))) == 0.0
    assert not (tmp_path / "programs").exists()


def test_a_warm_process_fits_without_tracing_the_solver(tmp_path):
    """The second process fits the example from the stored programs: the same result, and optimistix (which only
    tracing the solver needs) is never imported."""
    script = (
        "import sys, brdffit\n"
        "brdffit.enable_compilation_cache(sys.argv[1])\n"
        "result = brdffit.fit(sys.argv[2], 'ward')\n"
        "print(repr(result.cost), 'optimistix' in sys.modules)\n"
    )
    outputs = [
        subprocess.run(
            [sys.executable, "-c", script, str(tmp_path / "cache"), str(EXAMPLE)],
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
        ).stdout.split()
        for _ in range(2)
    ]
    (cold_cost, cold_traced), (warm_cost, warm_traced) = outputs
    assert cold_traced == "True" and warm_traced == "False"
    assert float(warm_cost) == float(cold_cost)


def test_threads_that_ask_for_a_program_while_it_is_published_get_the_compiled_call(programs, monkeypatch):
    """Issue 29, item 1: a thread that asks for a program while another is storing it gets the compiled call, never
    the raw ``Exported`` ("'Exported' object is not callable" in batch fits with the cache on). The first thread's
    ``jax.jit`` of the exported program is held open (0.3 s) and the others, released together by a barrier, ask
    for the same program meanwhile: exactly the moment where the raw program was visible to them."""
    real_jit = jax.jit
    compiling = threading.Event()

    def slow_jit(fun, *args, **kwargs):
        if isinstance(getattr(fun, "__self__", None), jax.export.Exported):
            compiling.set()
            time.sleep(0.3)
        return real_jit(fun, *args, **kwargs)

    lazy_jax = stored_programs.jax  # brdffit's stand-in for JAX: it holds copies of JAX's names once looked up
    assert lazy_jax.jit is real_jit
    monkeypatch.setattr(lazy_jax, "jit", slow_jit)
    x = np.linspace(0.0, 1.0, 9)
    expected = 2.0 * np.sum(np.sin(x))
    late = 15
    barrier = threading.Barrier(late)

    def first():
        return float(scaled_sum(np.asarray(2.0), x))

    def meanwhile():
        assert compiling.wait(timeout=60)
        barrier.wait(timeout=60)
        return float(scaled_sum(np.asarray(2.0), x))

    with ThreadPoolExecutor(late + 1) as pool:
        futures = [pool.submit(first)] + [pool.submit(meanwhile) for _ in range(late)]
        results = [future.result() for future in futures]
    assert results == pytest.approx([expected] * (late + 1), rel=1e-15)
    assert len(stored_files(programs)) == 1


# Issue 29, item 8: the cache folder is untrusted input. A program is run only if this cache signed it (for its
# signature); anything else is said in one warning, exported again and replaced.


def _tripled_sum(scale, x):
    return 3.0 * scale * jnp.sum(jnp.sin(x))


def _later_process(monkeypatch):
    monkeypatch.setattr(stored_programs, "_loaded", {})


def _payload(stored):
    """The serialized program in a stored file (after its HMAC and header lines)."""
    return stored.read_bytes().split(b"\n", 2)[2]


def _sign(key: bytes, signature: str, body: bytes) -> bytes:
    """A stored file's first line, as the format is documented: HMAC-SHA256 (hex) of the signature, a newline and the
    rest of the file."""
    return hmac.new(key, signature.encode() + b"\n" + body, hashlib.sha256).hexdigest().encode()


def _assert_read_back_quietly(monkeypatch, x):
    """A later process runs the replaced file without a warning (warnings are errors here) and without exporting."""
    _later_process(monkeypatch)
    monkeypatch.setattr(jax.export, "export", lambda *args, **kwargs: pytest.fail("exported again"))
    assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)


def test_a_planted_program_is_never_run(programs, monkeypatch):
    """Another program for the same call, written where ours would be (unsigned, as brdffit wrote them before, or
    signed by another cache's key): ours is compiled again, with one warning, and the planted file replaced. Before,
    the planted program ran: the fit reported its numbers (3× here)."""
    x = np.linspace(0.0, 1.0, 7)
    scaled_sum(np.asarray(2.0), x)
    (stored,) = stored_files(programs)
    shapes = (jax.ShapeDtypeStruct((), np.float64), jax.ShapeDtypeStruct(x.shape, np.float64))
    planted_body = b'{"named_tuples": []}\n' + bytes(jax.export.export(jax.jit(_tripled_sum))(*shapes).serialize())
    other_key = _sign(b"k" * 32, stored.stem, planted_body)
    for planted in (planted_body, other_key + b"\n" + planted_body):
        stored.write_bytes(planted)
        _later_process(monkeypatch)
        with pytest.warns(InputWarning, match="is not used .not signed by this cache"):
            assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
        assert stored.read_bytes() != planted
    _assert_read_back_quietly(monkeypatch, x)


def test_a_header_naming_a_module_never_imports_it(programs, monkeypatch):
    """``"this:__name__"`` in a header made brdffit import ``this`` (any module). Unsigned, the file is refused before
    its header is read; signed (a key that leaked), a module other than brdffit's is never imported."""
    monkeypatch.delitem(sys.modules, "this", raising=False)
    x = np.linspace(0.0, 1.0, 7)
    scaled_sum(np.asarray(2.0), x)
    (stored,) = stored_files(programs)
    body = b'{"named_tuples": ["this:__name__"]}\n' + _payload(stored)
    for signed, reason in ((False, "not signed by this cache"), (True, "of a module that is not loaded")):
        key = (programs / "key").read_bytes() if signed else None
        stored.write_bytes(_sign(key, stored.stem, body) + b"\n" + body if signed else body)
        _later_process(monkeypatch)
        with pytest.warns(InputWarning, match=reason):
            assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
        assert "this" not in sys.modules
    _assert_read_back_quietly(monkeypatch, x)


def test_sixteen_flipped_bytes_are_one_warning_and_a_recompile(programs, monkeypatch):
    """Flipped bytes in a program made every later fit fail ("Failed to deserialize StableHLO") until the folder was
    deleted: now the file fails its HMAC, is compiled again and replaced."""
    x = np.linspace(0.0, 1.0, 7)
    scaled_sum(np.asarray(2.0), x)
    (stored,) = stored_files(programs)
    content = bytearray(stored.read_bytes())
    start = content.index(b"\n", 65) + 1  # the payload: after the HMAC and the header
    for index in np.random.default_rng(16).choice(np.arange(start, len(content)), 16, replace=False):
        content[index] ^= 0xFF
    stored.write_bytes(bytes(content))
    _later_process(monkeypatch)
    with pytest.warns(InputWarning, match="not signed by this cache"):
        assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    _assert_read_back_quietly(monkeypatch, x)


@pytest.mark.parametrize("library", ["jax", "optimistix", "equinox", "lineax"])
def test_a_new_version_of_a_traced_library_never_reuses_a_program(programs, monkeypatch, library):
    """A program is keyed by the versions of what it holds: after an upgrade it is exported anew, into a new file."""
    x = np.arange(4.0)
    scaled_sum(np.asarray(2.0), x)
    assert len(stored_files(programs)) == 1
    real_version = importlib.metadata.version
    monkeypatch.setattr(importlib.metadata, "version", lambda name: "99.0" if name == library else real_version(name))
    if library == "jax":
        monkeypatch.setattr(stored_programs.jax, "__version__", "99.0")
    stored_programs._environment.cache_clear()
    try:
        _later_process(monkeypatch)
        scaled_sum(np.asarray(2.0), x)
        assert len(stored_files(programs)) == 2
    finally:
        monkeypatch.undo()
        stored_programs._environment.cache_clear()


@pytest.mark.parametrize("fault", ["others may write it", "another user owns it"])
def test_a_cache_folder_that_is_not_ours_alone_is_not_used(tmp_path, monkeypatch, fault):
    folder = tmp_path / "cache"
    folder.mkdir()
    if fault == "others may write it":
        folder.chmod(0o777)
        reason = "may be written by others"
    else:
        real_stat = os.stat
        monkeypatch.setattr(os, "getuid", lambda: real_stat(folder).st_uid + 1)
        reason = "is owned by user"
    monkeypatch.setattr(cache, "_enabled", None)
    with pytest.warns(InputWarning, match=f"the compilation cache {folder} {reason}.*not used"):
        assert cache.enable_compilation_cache(folder) is None
    assert cache.programs_folder() is None


def test_a_signed_program_that_fails_to_compile_is_exported_again(programs, monkeypatch):
    """A file this cache signed whose program JAX cannot compile (its StableHLO's bytes changed before it was signed:
    what a JAX that reads programs otherwise would meet): one warning, the program exported again and its file
    replaced, the call answered; before, every later call failed ("Failed to deserialize StableHLO")."""
    x = np.linspace(0.0, 1.0, 7)
    scaled_sum(np.asarray(2.0), x)
    (stored,) = stored_files(programs)
    _, header, payload = stored.read_bytes().split(b"\n", 2)
    stablehlo = payload.find(jax.export.deserialize(bytearray(payload)).mlir_module_serialized[:64])
    assert stablehlo > 0
    payload = bytearray(payload)
    payload[stablehlo : stablehlo + 16] = bytes(byte ^ 0xFF for byte in payload[stablehlo : stablehlo + 16])
    body = header + b"\n" + bytes(payload)
    stored.write_bytes(_sign((programs / "key").read_bytes(), stored.stem, body) + b"\n" + body)
    _later_process(monkeypatch)
    with pytest.warns(InputWarning, match=r"the stored program .* failed \(.*\); it is compiled again and replaced"):
        assert float(scaled_sum(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    _assert_read_back_quietly(monkeypatch, x)
