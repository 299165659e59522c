"""Stored executables (``brdffit/_programs/executables.py``): the executable XLA compiled from a stored program is
kept beside it and run by a later process without lowering or compiling, only where XLA has just compiled it (one the
compilation cache gave back serializes without its machine code), only with custom calls brdffit makes ready, and
never when its bytes are not the ones this cache signed.

The test workers run with JAX's compilation cache off (``conftest.py``), so no compile there reports a cache miss and
nothing is stored in-process unless a test says the compile was fresh (``fresh_compiles``); what crosses processes is
tested in subprocesses, each with a cache of its own."""

import json
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from paths import ROOT

from brdffit._programs import cache, executables, jit, signing
from brdffit._programs import stored as stored_programs
from brdffit.errors import InputWarning

needs_cpu_features = pytest.mark.skipif(
    executables.machine() is None, reason="the CPU's features cannot be read here: no executable is stored"
)


def _solved_sum(a, b):
    """A program with LAPACK custom calls (an LU factorization and triangular solves)."""
    return jnp.sum(jnp.linalg.solve(a, b))


def _scaled_sin(scale, x):
    """A program without custom calls."""
    return scale * jnp.sum(jnp.sin(x))


solved_sum = jit(_solved_sum)
scaled_sin = jit(_scaled_sin)
A = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
B = np.array([1.0, 2.0, 3.0])
EXPECTED = float(np.sum(np.linalg.solve(A, B)))


@pytest.fixture
def programs(tmp_path, monkeypatch):
    """A cache of its own and an empty table of loaded programs; the folder of stored programs."""
    monkeypatch.setattr(cache, "_enabled", tmp_path)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    return tmp_path / "programs"


@pytest.fixture
def fresh_compiles(monkeypatch):
    """Every compile reports a compilation-cache miss, as a compile by XLA does where JAX's cache is on."""
    counts = iter(range(10**6))
    monkeypatch.setattr(executables, "_cache_events", lambda: (0, next(counts)))


def executable_files(folder):
    return sorted(folder.glob(f"*{executables.SUFFIX}"))


def _later_process(monkeypatch):
    monkeypatch.setattr(stored_programs, "_loaded", {})


def _no_compiling(monkeypatch):
    """Compiling an exported program fails the test: a later call must load its executable."""
    real_jit = stored_programs.jax.jit

    def refuse(fun, *args, **kwargs):
        if isinstance(getattr(fun, "__self__", None), jax.export.Exported):
            pytest.fail("a stored program was compiled again")
        return real_jit(fun, *args, **kwargs)

    monkeypatch.setattr(stored_programs.jax, "jit", refuse)


@needs_cpu_features
def test_an_executable_is_stored_with_its_custom_calls_and_loaded_without_compiling(
    programs, fresh_compiles, monkeypatch
):
    assert float(solved_sum(A, B)) == pytest.approx(EXPECTED, rel=1e-14)
    (stored,) = executable_files(programs)
    mac, header, _ = stored.read_bytes().split(b"\n", 2)
    calls = json.loads(header)["custom_calls"]
    assert len(mac) == 64 and calls and all(call.startswith("lapack_") for call in calls)
    _later_process(monkeypatch)
    _no_compiling(monkeypatch)
    assert float(solved_sum(A, B)) == float(solved_sum(A, B)) == pytest.approx(EXPECTED, rel=1e-14)
    assert all(isinstance(program, jax.stages.Compiled) for program in stored_programs._loaded.values())
    assert executable_files(programs) == [stored]


def test_an_executable_the_compilation_cache_gave_back_is_not_stored(programs, monkeypatch):
    """No miss reported (the workers' cache is off; with it on, a hit): the executable may lack its machine code."""
    assert float(scaled_sin(np.asarray(2.0), np.ones(4))) == pytest.approx(8.0 * np.sin(1.0), rel=1e-15)
    assert executable_files(programs) == []
    assert len(sorted(programs.glob(f"*{stored_programs.SUFFIX}"))) == 1  # the program itself is stored


@needs_cpu_features
def test_custom_calls_brdffit_cannot_make_ready_are_never_stored(programs, fresh_compiles, monkeypatch):
    monkeypatch.setattr(executables, "_lapack_calls", lambda: frozenset())
    assert float(solved_sum(A, B)) == pytest.approx(EXPECTED, rel=1e-14)
    assert executable_files(programs) == []
    scaled_sin(np.asarray(2.0), np.ones(4))  # no custom call at all: stored
    assert len(executable_files(programs)) == 1


@needs_cpu_features
@pytest.mark.parametrize("fault", ["flipped bytes", "signed by another cache", "another program's"])
def test_an_executable_that_is_not_ours_is_removed_with_one_warning(programs, fresh_compiles, monkeypatch, fault):
    x = np.linspace(0.0, 1.0, 5)
    scaled_sin(np.asarray(2.0), x)
    (stored,) = executable_files(programs)
    content = bytearray(stored.read_bytes())
    if fault == "flipped bytes":
        for index in np.random.default_rng(3).choice(np.arange(200, len(content)), 16, replace=False):
            content[index] ^= 0xFF
    elif fault == "signed by another cache":
        body = bytes(content).split(b"\n", 1)[1]
        content = bytearray(signing.signed(b"k" * 32, stored.stem, body) + b"\n" + body)
    else:  # a file renamed to this program's name: its HMAC names the other program
        scaled_sin(np.asarray(2.0), np.ones(7))
        (other,) = [path for path in executable_files(programs) if path != stored]
        content = bytearray(other.read_bytes())
    stored.write_bytes(bytes(content))
    _later_process(monkeypatch)
    with pytest.warns(InputWarning, match=r"the stored executable .* is not used \(not signed by this cache"):
        assert float(scaled_sin(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    assert stored.read_bytes() != bytes(content)  # removed, and stored again from the fresh compile


@needs_cpu_features
def test_a_loaded_executable_that_fails_when_run_is_discarded_even_after_a_precompile(
    programs, fresh_compiles, monkeypatch
):
    """A background precompile (``compile_in_background``) of a loaded executable compiles nothing: it must not
    count as proof that the executable runs, or the first call's failure would reach the user, in every process."""
    x = np.linspace(0.0, 1.0, 5)
    scaled_sin(np.asarray(2.0), x)
    (stored,) = executable_files(programs)
    _later_process(monkeypatch)
    wrong = jax.jit(lambda a, b: a).lower(np.ones(3), np.ones(3)).compile()  # for other shapes: fails when called
    real_read, reads = executables._read, []
    monkeypatch.setattr(
        executables, "_read", lambda *args: reads.append(1) or (wrong if len(reads) == 1 else real_read(*args))
    )
    scaled_sin.precompile(np.asarray(2.0), x)
    with pytest.warns(InputWarning, match=r"the stored program .* failed \(.*\); it is compiled again and replaced"):
        assert float(scaled_sin(np.asarray(2.0), x)) == pytest.approx(2.0 * np.sum(np.sin(x)), rel=1e-15)
    assert executable_files(programs) == [stored]  # removed with its program, and stored again


def test_the_machine_names_the_cpu_and_xla_flags(monkeypatch):
    executables.machine.cache_clear()
    try:
        here = executables.machine()
        monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_enable_fast_math=false")
        executables.machine.cache_clear()
        assert here is None or executables.machine() != here
    finally:
        monkeypatch.undo()
        executables.machine.cache_clear()


#: A later process's view: its stored programs are executables it loaded, and it lowered no module to run them.
SCRIPT = """
import sys, brdffit, numpy as np
from jax._src.interpreters import mlir
from brdffit._programs import stored
sys.path.insert(0, sys.argv[2])
from test_executables import A, B, solved_sum
environment = stored._environment()
stored._environment = lambda: environment + [sys.argv[3]]  # another brdffit version: other signatures
brdffit.enable_compilation_cache(sys.argv[1])
lowered = []
real = mlir.lower_jaxpr_to_module
mlir.lower_jaxpr_to_module = lambda *args, **kwargs: lowered.append(1) or real(*args, **kwargs)
value = float(solved_sum(A, B))
kinds = sorted(type(program).__name__ for program in stored._loaded.values())
print(repr(value), len(lowered), ",".join(kinds))
"""


@pytest.mark.slow
@needs_cpu_features
def test_a_later_process_runs_the_executable_without_lowering(tmp_path):
    """Across processes, with JAX's compilation cache on: the first compiles and stores; the second loads the
    executable (LAPACK made ready first) and lowers nothing; with the executable gone, a compile the cache answers
    stores none, and the process after still runs. After an upgrade (new signatures, the cache still holding the
    old version's compiles of the same module) the executable is compiled by XLA and stored again."""

    def run(version="1"):
        command = [sys.executable, "-c", SCRIPT, str(tmp_path / "cache"), str(ROOT / "tests"), version]
        value, lowered, kinds = subprocess.run(
            command, capture_output=True, text=True, check=True, cwd=tmp_path
        ).stdout.split()
        return float(value), int(lowered), kinds

    programs = tmp_path / "cache" / "programs"
    cold = run()
    assert cold[0] == pytest.approx(EXPECTED, rel=1e-14) and cold[1] > 0
    assert len(executable_files(programs)) == 1
    warm = run()
    assert warm == (cold[0], 0, "Compiled")
    for path in executable_files(programs):
        path.unlink()
    given_back = run()
    assert given_back[0] == cold[0] and executable_files(programs) == []
    assert run()[0] == cold[0]
    upgraded = run("2")
    assert upgraded[0] == cold[0] and len(executable_files(programs)) == 1
    assert run("2") == (cold[0], 0, "Compiled")
