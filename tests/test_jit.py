"""``brdffit._programs.jit`` across threads, and what ``fit_batch``'s threads learn from it: a program's first call runs
under a lock of its own (two threads compiling a bucket's solve at once traced it twice, 1.5 s each, measured),
and a bucket says when its programs are compiled, so that the other threads start then."""

import threading
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import jaxlib
import numpy as np
import pytest

from brdffit import data_synth
from brdffit._programs import cache, jit
from brdffit._programs.first_calls import FirstCalls


def test_first_calls_of_one_signature_run_one_at_a_time():
    """Threads that call a new signature at once run its first call one after another (the later ones then find
    it compiled); calls of another signature do not wait for them."""
    first_calls = FirstCalls()
    spans = {"a": [], "b": []}
    meet = threading.Barrier(4)

    def call(key):
        def action():
            started = time.perf_counter()
            time.sleep(0.2)
            spans[key].append((started, time.perf_counter()))

        meet.wait()
        first_calls.run(key, action)

    threads = [threading.Thread(target=call, args=(key,)) for key in ("a", "a", "a", "b")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    (a1, a2, a3), ((b_start, b_end),) = sorted(spans["a"]), spans["b"]
    assert a1[1] <= a2[0] and a2[1] <= a3[0]  # one after another
    assert b_start < a1[1] and a1[0] < b_end  # beside the first "a"
    started = time.perf_counter()
    first_calls.run("a", lambda: None)  # a signature already called: no lock
    assert time.perf_counter() - started < 0.1


def test_a_bucket_says_when_its_starts_are_searched_and_its_programs_compiled(monkeypatch):
    """``StackedFit``'s stages, which ``fit_batch`` uses to start its other threads once the first batch's programs
    are compiled: the first call compiles them (it traces), the second finds them compiled (it traces nothing)."""
    from brdffit._programs.stored import traced
    from brdffit.fitting.objective.losses import get_loss
    from brdffit.fitting.options import Solving
    from brdffit.fitting.single.stacked import StackedFit
    from brdffit.physics.models.registry import get_model

    monkeypatch.setattr(cache, "_enabled", None)
    params = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.2}
    samples = [data_synth.synthesize("ward", params, *data_synth.uniform_random(200, seed=k)) for k in range(2)]
    options = dict(solving=Solving(n_starts=3, max_steps=93, dtype="float64", seed=0), strategy="loop")
    for compiles in (True, False):
        stages = []
        before = traced()
        fit = StackedFit(
            get_model("ward"),
            get_loss("log"),
            samples,
            on_stage=lambda s, stages=stages: stages.append((s, traced())),
            **options,
        )
        fit.solve(fit.starts())
        assert [stage for stage, _ in stages] == ["searched", "compiled"]
        assert (stages[0][1] > before) == compiles  # the first call traced its programs, the second nothing


def test_a_program_says_whether_it_is_compiled(monkeypatch):
    """``is_compiled``: false before a signature's first call, true after it (or after a precompile), per shape."""
    monkeypatch.setattr(cache, "_enabled", None)
    doubled = jit(lambda x: 2.0 * x)
    assert not doubled.is_compiled(np.ones(3))
    doubled(np.ones(3))
    assert doubled.is_compiled(np.ones(3)) and not doubled.is_compiled(np.ones(4))
    doubled.precompile(jax.ShapeDtypeStruct((4,), np.float64))
    assert doubled.is_compiled(np.ones(4))


def test_compiler_options_the_running_xla_does_not_know_are_left_out():
    """A private XLA flag a jaxlib does not know (jax 0.8 refuses one of brdffit's) is dropped, not fatal: the others
    are kept, and a program compiles with what is left."""
    from brdffit._programs.jit import CPU_COMPILER_OPTIONS, known_options

    options = CPU_COMPILER_OPTIONS | {"xla_cpu_no_such_option_anywhere": True}
    kept = known_options(options)
    assert kept.items() <= CPU_COMPILER_OPTIONS.items()
    if jaxlib.__version__ == _pinned("jaxlib"):  # constraints.txt's jaxlib knows brdffit's three; older ones may not
        assert kept == CPU_COMPILER_OPTIONS
    jax.jit(lambda x: 2.0 * x, compiler_options=kept).lower(1.0).compile()


def test_a_model_that_asks_for_xla_fusion_emitters_has_its_programs_compiled_with_them(monkeypatch):
    """A program whose static arguments or bound values hold a model with ``fusion_emitters`` (glTF's material
    without a sheen) compiles with :data:`EMITTER_COMPILER_OPTIONS`; one of another model (Ward, glTF's with a sheen)
    with the usual :data:`CPU_COMPILER_OPTIONS`; each with its own program."""
    import importlib
    from functools import partial

    from brdffit import get_model

    jit_module = importlib.import_module("brdffit._programs.jit")  # the package's ``jit`` is the function

    options = jit_module.compiler_options
    asked = _asked_options(monkeypatch, "emitters")

    def scaled(model, x):
        return (2.0 if model.fusion_emitters else 3.0) * x

    for model, emitters in (
        (get_model("gltf"), True),
        (get_model("ward"), False),
        (get_model("gltf", sheen=True), False),
    ):
        asked.clear()  # each model a program of its own, whose options are asked for when it is first compiled
        assert float(jit(scaled, static_argnums=0)(model, np.float64(1.0))) == (2.0 if emitters else 3.0)
        assert asked and set(asked) == {emitters}
        asked.clear()
        jit(partial(scaled, model), name=f"test.scaled.{model.name}", closes_over=(model,))(np.float64(1.0))
        assert asked and set(asked) == {emitters}
    if jax.default_backend() == "cpu" and "xla_cpu_use_fusion_emitters" in options(True):  # an XLA that knows it
        assert options(True) == options(False) | {"xla_cpu_use_fusion_emitters": True}


def _asked_options(monkeypatch, argument: str) -> list:
    """``jit.compiler_options`` patched to record its ``argument`` (``emitters`` or ``optimised``) at each call: the
    list it records in."""
    import importlib

    jit_module = importlib.import_module("brdffit._programs.jit")  # the package's ``jit`` is the function
    options, asked = jit_module.compiler_options, []

    def recorded(emitters=False, optimised=True):
        asked.append({"emitters": emitters, "optimised": optimised}[argument])
        return options(emitters, optimised)

    monkeypatch.setattr(jit_module, "compiler_options", recorded)
    return asked


def _pinned(package: str) -> str | None:
    """The version ``constraints.txt`` pins ``package`` at (``make test``'s venv), or None."""
    path = Path(__file__).resolve().parents[1] / "constraints.txt"
    for line in path.read_text().splitlines():
        name, _, version = line.partition("==")
        if name.strip().lower() == package:
            return version.strip()
    return None


def _hooked_sum(x):
    return jnp.sum(jnp.sin(x))


@pytest.mark.parametrize("stored", [False, True])
def test_precompile_with_calls_its_hook_once_the_program_is_lowered_before_it_is_compiled(
    stored, tmp_path, monkeypatch
):
    """``precompile_with(lowered, …)``: ``lowered()`` runs on the caller's thread once the program is traced and
    lowered (with the cache on: exported), before XLA compiles it, so that what it starts overlaps the compilation and
    not the tracing (``single/stacked.py``); not at all for a signature compiled already."""
    import importlib

    stored_programs = importlib.import_module("brdffit._programs.stored")
    executables = importlib.import_module("brdffit._programs.executables")
    monkeypatch.setattr(cache, "_enabled", tmp_path if stored else None)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    events = []
    ours = lambda name: "_hooked_sum" in str(name)
    lower, compile_, export, compiled_program = (
        jax.stages.Traced.lower,
        jax.stages.Lowered.compile,
        jax.export.export,
        executables.compiled_program,
    )

    def lowered_and_said(self, *args, **kwargs):
        result = lower(self, *args, **kwargs)
        events.extend(["lowered"] if ours(self.fun_name) else [])
        return result

    def exported_and_said(fun, *args, **kwargs):
        def made(*shapes):
            result = export(fun, *args, **kwargs)(*shapes)
            events.extend(["lowered"] if ours(result.fun_name) else [])
            return result

        return made

    def compiled_and_said(self, *args, **kwargs):
        events.extend(["compiled"] if ours(self._lowering._name) else [])
        return compile_(self, *args, **kwargs)

    def program_and_said(folder, name, key, exported, *args):
        events.extend(["compiled"] if ours(exported.fun_name) else [])
        return compiled_program(folder, name, key, exported, *args)

    monkeypatch.setattr(jax.stages.Traced, "lower", lowered_and_said)
    monkeypatch.setattr(jax.export, "export", exported_and_said)
    monkeypatch.setattr(jax.stages.Lowered, "compile", compiled_and_said)
    monkeypatch.setattr(executables, "compiled_program", program_and_said)
    hooked = jit(_hooked_sum)
    shape = jax.ShapeDtypeStruct((5,), np.float64)
    hooked.precompile_with(lambda: events.append("hook"), shape)
    said = [event for index, event in enumerate(events) if events.index(event) == index]  # export lowers within
    assert said == ["lowered", "hook", "compiled"] and events.count("hook") == 1
    assert max(i for i, event in enumerate(events) if event == "lowered") < events.index("hook")
    assert hooked.is_compiled(shape) and float(hooked(np.zeros(5))) == 0.0
    events.clear()
    hooked.precompile_with(lambda: events.append("hook"), shape)  # compiled already: nothing to overlap
    assert "hook" not in events


def test_a_function_jitted_unoptimised_compiles_with_llvm_passes_skipped_as_a_program_of_its_own(tmp_path, monkeypatch):
    """``jit(optimised=False)`` (a single fit's caveat screens): its programs compile with ``UNOPTIMISED`` added to the
    options (where the running XLA knows it), and are stored apart from those of the same function optimised."""
    import importlib

    from brdffit._programs.jit import UNOPTIMISED, known_options

    jit_module = importlib.import_module("brdffit._programs.jit")
    stored_programs = importlib.import_module("brdffit._programs.stored")
    monkeypatch.setattr(cache, "_enabled", tmp_path)
    monkeypatch.setattr(stored_programs, "_loaded", {})
    if jax.default_backend() == "cpu" and known_options(UNOPTIMISED):
        assert jit_module.compiler_options(False, False) == jit_module.compiler_options(False) | UNOPTIMISED
    asked = _asked_options(monkeypatch, "optimised")
    x = np.linspace(0.0, 1.0, 6)
    for optimised in (True, False):
        asked.clear()
        assert float(jit(_hooked_sum, optimised=optimised)(x)) == pytest.approx(np.sum(np.sin(x)), rel=1e-14)
        assert asked and set(asked) == {optimised}
    assert len(list((tmp_path / "programs").glob(f"*{stored_programs.SUFFIX}"))) == 2
