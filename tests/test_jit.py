"""``brdffit._jax.jit`` across threads: a program is traced once, however many threads compile it at the same
time. ``fit_batch`` fits batches on several threads, each compiling the bucket's programs in the background; JAX
shared their compilation but traced them once per thread (the solve ~1.5 s each, measured), until the first call
of a signature ran under a lock of its own."""

import jax
import pytest

import data_synth
from brdffit import cache, fit_batch

TRACE_EVENT = "/jax/core/compile/jaxpr_trace_duration"


@pytest.fixture
def traced():
    """The names of the functions JAX traces for compilation meanwhile (its monitoring events)."""
    names = []

    def listener(event, seconds, fun_name=None, **_):
        if event == TRACE_EVENT:
            names.append(fun_name)

    jax.monitoring.register_event_duration_secs_listener(listener)
    yield names
    jax.monitoring.unregister_event_duration_listener(listener)


def test_batches_on_two_threads_trace_each_program_once(monkeypatch, traced):
    monkeypatch.setattr(cache, "_enabled", None)  # no stored programs: every new program is traced
    params = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.2}
    samples = [data_synth.synthesize("ward", params, *data_synth.uniform_random(300, seed=k)) for k in range(4)]
    # max_steps of its own: programs no other test compiled in this process; 2 batches of 2 on 2 threads
    results = fit_batch(samples, "ward", threads=2, max_steps=97)
    assert all(result.converged for result in results)
    assert traced.count("solve") == 1 and traced.count("_bucket_screens") <= 1


def test_a_bucket_says_when_its_starts_are_searched_and_its_programs_compiled(monkeypatch):
    """``solve_bucket``'s stages, which ``fit_batch`` uses to start its other threads: once the first batch's
    programs are compiled, or after its search when that traced nothing (every program was compiled before)."""
    from brdffit._programs import traced
    from brdffit.fitting.buckets import solve_bucket
    from brdffit.fitting.losses import get_loss
    from brdffit.physics.models import get_model

    monkeypatch.setattr(cache, "_enabled", None)
    params = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.2}
    samples = [data_synth.synthesize("ward", params, *data_synth.uniform_random(200, seed=k)) for k in range(2)]
    options = dict(n_starts=3, max_steps=93, dtype="float64", seed=0, strategy="loop")
    for compiles in (True, False):
        stages = []
        before = traced()
        solve_bucket(
            get_model("ward"),
            get_loss("log"),
            samples,
            None,
            on_stage=lambda s, stages=stages: stages.append((s, traced())),
            **options,
        )
        assert [stage for stage, _ in stages] == ["searched", "compiled"]
        assert (stages[0][1] > before) == compiles  # the first call traced its programs, the second nothing
