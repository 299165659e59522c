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
