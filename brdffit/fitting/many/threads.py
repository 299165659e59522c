"""Units of work on threads: the first alone until its programs are compiled, the others beside it within a budget
of samples; one thread per CPU core by default."""

import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from contextlib import contextmanager

from ..._jax import float64
from .buckets import BATCH_SAMPLES, WorkUnit


def run_units(units: list["WorkUnit"], fit_unit: Callable, threads: int, bar) -> None:
    """``fit_unit(unit, on_stage)`` (how many datasets it fitted) for each of ``units``, on ``threads`` threads,
    each fitted count added to ``bar``.

    The first unit starts alone, the others once its programs are compiled: the event its ``on_stage("compiled")``
    sets (``single/stacked.StackedFit``: after the start search, when the solve's program is compiled too, or at
    once when the starts are given), or its end. The units running at once hold at most
    :data:`~.buckets.BATCH_SAMPLES` samples (one larger unit runs alone).
    A unit that fails stops those not yet started, and the failure is raised at once.
    """
    if threads == 1 or len(units) == 1:
        for unit in units:
            bar.update(fit_unit(unit, None))
        return
    compiled, stop = threading.Event(), threading.Event()
    budget = SampleBudget(BATCH_SAMPLES)

    @float64  # JAX's float64 switch is per thread
    def run(unit: WorkUnit, first: bool) -> int:
        if not first:
            compiled.wait()
        if stop.is_set():
            return 0
        with budget.taken(unit.stack * unit.size):
            if not first:
                return fit_unit(unit, None)

            def on_stage(stage: str) -> None:
                if stage == "compiled":
                    compiled.set()

            try:
                return fit_unit(unit, on_stage)
            except BaseException:
                stop.set()
                raise
            finally:
                compiled.set()

    pool = ThreadPoolExecutor(min(threads, len(units)), thread_name_prefix="brdffit-fit")
    pending = [pool.submit(run, unit, index == 0) for index, unit in enumerate(units)]
    try:
        for done in as_completed(pending):
            bar.update(done.result())
    except BaseException:  # a failed unit, or Ctrl-C: the units not yet started do nothing
        stop.set()
        compiled.set()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


class SampleBudget:
    """How many samples the units running at once may hold: a unit waits until its samples fit beside the others'
    (or, larger than the whole budget, until it runs alone)."""

    def __init__(self, total: int):
        self._total, self._used = total, 0
        self._changed = threading.Condition()

    @contextmanager
    def taken(self, samples: int):
        with self._changed:
            self._changed.wait_for(lambda: self._used == 0 or self._used + samples <= self._total)
            self._used += samples
        try:
            yield
        finally:
            with self._changed:
                self._used -= samples
                self._changed.notify_all()


def usable_cores() -> int:
    """The CPU cores this process may run on (its affinity, which a batch scheduler's allocation sets)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1
