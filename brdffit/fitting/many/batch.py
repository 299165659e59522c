"""Fit one model to many datasets: a scanned material library, the texels of a spatially varying BRDF.

The datasets are grouped into buckets whose problems stack (``buckets.bucket_key``: one padded size, channel
count and set of columns) and each bucket is fitted in a few compiled programs (``single/stacked.StackedFit``): the
start search of all its datasets in one, every Levenberg-Marquardt run in another. ``strategy`` says how a
program goes through the datasets of a bucket:

* ``loop`` (the default on a CPU): one after another inside the program, each solve ending when it converges;
  a vectorised while-loop would run every fit until the slowest one ends, which on a CPU costs more than it
  saves;
* ``vmap`` (the default on a GPU): all at once, which fills the device.

Models with several lobes (Lafortune) are fitted lobe by lobe, one dataset at a time (``single/fit.py``), unless
every dataset has its start; so is the data-driven model (``buckets.fitted_alone``).

The units of work (a batch of a bucket, or one dataset fitted lobe by lobe) run on ``threads`` threads, by default
one per CPU core: a compiled program runs its datasets one after another on one core, and XLA runs with the GIL
released, so a second batch fills the second core (1,000 Ward fits of 500 samples with compiled programs, on 2
cores: 1.3–1.6 s on one thread, 0.8–1.0 s on two). A bucket is cut into a multiple of ``threads`` batches that
together hold at most ``buckets.BATCH_SAMPLES`` samples; each dataset's programs treat it alone, so the results do
not depend on the cut. The other units start once the first has its programs compiled (``threads.py``): in a fresh
process compilation is most of the time, and the other units' work beside it
on 2 cores made 20 × 100k Ward slower than one thread (7.4 s against 6.4 s, compile included).
"""

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..._jax import float64
from ..._progress import progress_bar
from ...checks import choice, whole_number
from ...data.samples import Samples
from ...errors import BrdfInputError
from ...physics.models.model import LobeModel
from ..options import HOLDING_NOTHING, SOLVING, Holding, Solving
from ..single.fit import Setup, checked, fit_checked, start_vector
from ..single.result import FitResult
from ..single.stacked import StackedFit, default_strategy
from ..solver.hold import free_hold
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
    solving: Solving = SOLVING,
    holding: Holding = HOLDING_NOTHING,
    threads: int | None = None,
    on_checked: Callable[[Setup], None] = lambda setup: None,
    priors: Sequence[tuple[np.ndarray, np.ndarray]] | None = None,
    **model_options: Any,
) -> list[FitResult]:
    """Fit ``model`` to each of ``samples``; the arguments are those of :func:`brdffit.fit_batch` (``solving`` and
    ``holding`` the objects its keywords make, ``fitting/options.py``); ``on_checked`` is called with each dataset's
    :class:`~brdffit.fitting.single.fit.Setup` before any fit (``brdffit.fit_batch`` checks an MCMC's walkers so).
    ``priors``: for each dataset a Gaussian prior on the solver's vector, its mean and weight (k,) each
    (``solver/hold.py``; a spatially varying fit's smoothness, ``svbrdf/smoothing.py``), or None."""
    choice("strategy", strategy, STRATEGIES)
    strategy = default_strategy() if strategy == "auto" else strategy
    if threads is None:  # one thread per core; on a GPU one, whose programs fill the device
        threads = 1 if strategy == "vmap" else usable_cores()
    threads = whole_number("threads", threads)
    if strategy == "vmap":  # its programs fill the device; two at once on a 2-core CPU hung in XLA (512 texels)
        threads = 1
    samples = list(samples)
    if not samples:
        raise BrdfInputError("fit_batch needs at least one dataset")
    starts = starts_per_dataset(start, len(samples))
    if priors is not None and len(priors) != len(samples):
        raise BrdfInputError(f"{len(priors)} priors for {len(samples)} datasets; give one per dataset")
    setups = [checked(one, model, loss, max_theta, holding, **model_options) for one in samples]
    for setup in setups:  # what the caller checks of every dataset before any fit (the walkers of an MCMC)
        on_checked(setup)
    built, built_loss = setups[0].model, setups[0].loss
    kept = [setup.samples for setup in setups]
    # A lobe model's starts as the solver's vectors, checked here; the data-driven model's fits take theirs as given
    # (each fitted alone, ``buckets.fitted_alone``; ``datadriven/fit.py`` checks them).
    vectors = [
        None if one is None or not isinstance(built, LobeModel) else start_vector(built, one, data.n_channels)
        for one, data in zip(starts, kept, strict=True)
    ]
    if priors is not None:
        _check_priors(built, priors, vectors)
    results: list[FitResult | None] = [None] * len(kept)

    def fit_unit(unit: WorkUnit, on_stage: Callable[[str], None] | None) -> int:
        """Fit the datasets of ``unit`` into ``results``; how many they were."""
        if fitted_alone(built, unit.given):
            (index,) = unit.indices
            results[index] = fit_checked(setups[index], solving, starts[index])
            return 1
        present = [vector for vector in (vectors[i] for i in unit.indices) if vector is not None]
        given = np.stack(present) if unit.given else None  # a unit given starts has one for each dataset
        constraints = setups[unit.indices[0]].constraints  # one per channel count; a bucket has one
        hold = None if constraints is None else constraints.hold()
        if priors is not None:  # each dataset's own: arrays (D, k) beside the hold's (k,)
            means, weights = (np.stack([priors[i][part] for i in unit.indices]) for part in (0, 1))
            hold = (free_hold(means.shape[1]) if hold is None else hold)._replace(
                prior_mean=means, prior_weight=weights
            )
        unit_samples = [kept[i] for i in unit.indices]
        options = dict(solving=solving, strategy=strategy, stack=unit.stack, on_stage=on_stage)
        fit = StackedFit(built, built_loss, unit_samples, hold, **options)
        solved = fit.solve(fit.starts(given))
        fitted = fit.results(solved, max_theta=max_theta, constraints=constraints)
        for index, result in zip(unit.indices, fitted, strict=True):
            results[index] = result
        return len(unit.indices)

    units = work_units(built, kept, [vector is not None for vector in vectors], threads)
    bar = progress_bar(len(samples), "fit", progress)
    try:
        run_units(units, fit_unit, threads, bar)
    finally:
        bar.close()
    return every_fitted(results)


def _check_priors(model, priors: Sequence[tuple[np.ndarray, np.ndarray]], vectors: list) -> None:
    """A one-line error, before any fit, unless every dataset of a lobe model has a start (a prior's fit is not
    raced from the grid: the race compares data costs) and a prior's mean and weight of its vector's length."""
    if not isinstance(model, LobeModel):
        raise BrdfInputError(f"a {model.name} fit takes no prior on its parameters")
    for index, (vector, (mean, weight)) in enumerate(zip(vectors, priors, strict=True)):
        if vector is None:
            raise BrdfInputError(f"dataset {index} has a prior but no start: a prior's fit starts where it is given")
        if np.shape(mean) != vector.shape or np.shape(weight) != vector.shape:
            raise BrdfInputError(
                f"dataset {index}'s prior has a mean of shape {np.shape(mean)} and a weight of shape"
                f" {np.shape(weight)}; its vector has {vector.size} entries"
            )


def every_fitted(results: list[FitResult | None]) -> list[FitResult]:
    """``results``, once every dataset's fit has filled its place."""
    fitted = [result for result in results if result is not None]
    assert len(fitted) == len(results), "a dataset was left unfitted"
    return fitted


def starts_per_dataset(start, count: int) -> list:
    """``fit_batch``'s ``start`` as one entry (a parameter dictionary or None) per dataset."""
    starts = list(start) if isinstance(start, Sequence) else [start] * count
    if len(starts) != count:
        raise BrdfInputError(f"{len(starts)} starts for {count} datasets; give one per dataset or one for all")
    return starts
