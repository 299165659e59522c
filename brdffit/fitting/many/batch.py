"""Fit one model to many datasets: a scanned material library, the texels of a spatially varying BRDF.

The datasets are grouped into buckets whose problems stack (``buckets.bucket_key``: one padded size, channel
count and set of columns) and each bucket is fitted in a few compiled programs (``buckets.solve_bucket``): the
start search of all its datasets in one, every Levenberg-Marquardt run in another. ``strategy`` says how a
program goes through the datasets of a bucket:

* ``loop`` (the default on a CPU): one after another inside the program, each solve ending when it converges;
  a vectorised while-loop would run every fit until the slowest one ends, which on a CPU costs more than it
  saves;
* ``vmap`` (the default on a GPU): all at once, which fills the device.

Models with several lobes (Lafortune) are fitted lobe by lobe, one dataset at a time (``fit.py``), unless
every dataset has its start.

The units of work (a batch of a bucket, or one dataset fitted lobe by lobe) run on ``threads`` threads, by default
one per CPU core: a compiled program runs its datasets one after another on one core, and XLA runs with the GIL
released, so a second batch fills the second core (1,000 Ward fits of 500 samples with compiled programs, on 2
cores: 1.3–1.6 s on one thread, 0.8–1.0 s on two). A bucket is cut into a multiple of ``threads`` batches that
together hold at most ``buckets.BATCH_SAMPLES`` samples; each dataset's programs treat it alone, so the results do
not depend on the cut. The other units start once the first has its programs compiled (or found them compiled
after its start search): in a fresh process compilation is most of the time, and the other units' work beside it
on 2 cores made 20 × 100k Ward slower than one thread (7.4 s against 6.4 s, compile included).
"""

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..._jax import float64
from ...checks import choice, whole_number
from ...data.samples import Samples
from ...errors import BrdfInputError
from ..single.defaults import MAX_STEPS, N_STARTS
from ..single.fit import checked, fit_one, start_vector
from ..single.result import FitResult
from ..single.stacked import StackedFit, default_strategy
from .buckets import WorkUnit, fitted_alone, work_units
from .threads import run_units, usable_cores

STRATEGIES = ("auto", "loop", "vmap")


@float64
def fit_many(
    samples: Sequence[Samples],
    model: str = "ward",
    loss: str = "log",
    *,
    strategy: str = "auto",
    progress: bool | None = None,
    max_theta: float | None = None,
    start: dict[str, Any] | Sequence[dict[str, Any]] | None = None,
    n_starts: int = N_STARTS,
    max_steps: int = MAX_STEPS,
    dtype: str = "float64",
    seed: int = 0,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    threads: int | None = None,
    **model_options: Any,
) -> list[FitResult]:
    """Fit ``model`` to each of ``samples``; the arguments are those of :func:`brdffit.fit_batch`."""
    choice("strategy", strategy, STRATEGIES)
    strategy = default_strategy() if strategy == "auto" else strategy
    if threads is None:  # one thread per core; on a GPU one, whose programs fill the device
        threads = 1 if strategy == "vmap" else usable_cores()
    threads = whole_number("threads", threads)
    samples = list(samples)
    if not samples:
        raise BrdfInputError("fit_batch needs at least one dataset")
    starts = starts_per_dataset(start, len(samples))
    held = dict(fixed=fixed, bounds=bounds)
    kept_by_check = [checked(one, model, loss, max_theta, dtype, **held, **model_options) for one in samples]
    built, built_loss = kept_by_check[0][0], kept_by_check[0][1]
    kept = [one for _, _, one, _ in kept_by_check]
    n_starts = whole_number("n_starts", n_starts)
    max_steps = whole_number("max_steps", max_steps)
    vectors = [
        None if one is None else start_vector(built, one, data.n_channels)
        for one, data in zip(starts, kept, strict=True)
    ]
    options = dict(n_starts=n_starts, max_steps=max_steps, dtype=dtype, seed=seed, strategy=strategy)
    results: list[FitResult | None] = [None] * len(kept)

    def fit_unit(unit: WorkUnit, on_stage: Callable[[str], None] | None) -> int:
        """Fit the datasets of ``unit`` into ``results``; how many they were."""
        if fitted_alone(built, unit.given):
            (index,) = unit.indices
            one = {"max_theta": max_theta, "n_starts": n_starts, "max_steps": max_steps, "seed": seed}
            results[index] = fit_one(kept[index], built, built_loss, dtype=dtype, start=starts[index], **held, **one)
            return 1
        given = np.stack([vectors[i] for i in unit.indices]) if unit.given else None
        constraints = kept_by_check[unit.indices[0]][3]  # one per channel count; a bucket has one
        hold = None if constraints is None else constraints.hold()
        unit_samples = [kept[i] for i in unit.indices]
        fit = StackedFit(built, built_loss, unit_samples, hold, stack=unit.stack, on_stage=on_stage, **options)
        solved = fit.solve(fit.starts(given))
        fitted = fit.results(solved, max_theta=max_theta, constraints=constraints)
        for index, result in zip(unit.indices, fitted, strict=True):
            results[index] = result
        return len(unit.indices)

    units = work_units(built, kept, [vector is not None for vector in vectors], threads)
    bar = progress_bar(len(samples), progress)
    try:
        run_units(units, fit_unit, threads, bar)
    finally:
        bar.close()
    return results


def starts_per_dataset(start, count: int) -> list:
    """``fit_batch``'s ``start`` as one entry (a parameter dictionary or None) per dataset."""
    starts = list(start) if isinstance(start, Sequence) else [start] * count
    if len(starts) != count:
        raise BrdfInputError(f"{len(starts)} starts for {count} datasets; give one per dataset or one for all")
    return starts


def progress_bar(total: int, enabled: bool | None):
    """A bar of ``total`` fits on stderr."""
    from tqdm.auto import tqdm

    # disable=None: tqdm shows the bar only when its stream (stderr) is a terminal.
    return tqdm(total=total, unit="fit", disable=None if enabled is None else not enabled, leave=False)
