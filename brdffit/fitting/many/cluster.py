"""The work of :func:`brdffit.fit_batch`: here, or spread over a Dask cluster when one machine is not enough.

:func:`fit_here` fits a list of datasets in this process (``batch.py``: one bucket of datasets whose problems
stack at a time) and passes each result through a function on request (``brdffit.fit_batch``: its uncertainty).
:func:`fit_on_cluster` cuts the same work into *chunks* and gives each to a worker of a
``dask.distributed.Client`` as one task, which calls :func:`fit_here` there:

* datasets in memory are cut within the units :func:`fit_here` would cut them into (the batches of one bucket,
  ``buckets.work_units``), at most :data:`PER_TASK` at a time and fewer where that gives every worker
  four tasks; a bucket's programs treat each dataset alone, so the results are this process's (to 1e-12, the
  tests' tolerance: a program for another number of datasets may round differently);
* datasets given as paths are read on the workers, runs of consecutive paths: the client never holds the data;
* each worker keeps its compiled programs (JAX's persistent compilation cache, switched on in the task), so a
  worker pays the compilation of a bucket's programs once;
* a worker lost mid-run has its tasks re-run on another (Dask's scheduler does this), and the results come back
  in the order of the inputs.

:func:`on_workers` runs any such tasks (``fit_batch``'s chunks, the bands of a capture's tiles, ``svbrdf``), raising
a worker's bad input here in one line.

``dask[distributed]`` is the ``cluster`` extra (``pip install 'brdffit[cluster]'``).
"""

import os
import warnings
from collections.abc import Callable, Generator, Sequence
from contextlib import closing
from typing import Any, NamedTuple

from ..._progress import progress_bar
from ...data.load import load_samples
from ...data.samples import Samples
from ...errors import BrdfInputError
from ...physics.models.model import Model
from ..options import Holding
from ..single.fit import checked
from ..single.result import FitResult
from .batch import every_fitted, fit_many, starts_per_dataset
from .buckets import work_units

#: The most datasets one task fits: a few seconds of work for small ones, so that a lost worker costs little and
#: the progress bar moves, and enough that a task's programs stack many datasets.
PER_TASK = 256


def fit_here(
    samples: Sequence[Samples],
    model,
    loss: str,
    *,
    then: Callable[[FitResult, Samples], FitResult] | None = None,
    **fit_options: Any,
) -> list[FitResult]:
    """Each of ``samples`` fitted in this process (``fit_many``), each result then passed through ``then`` with the
    samples it was fitted to (``brdffit.fit_batch`` adds the uncertainty so: a function a worker can unpickle)."""
    results = fit_many(samples, model, loss, **fit_options)
    if then is None:
        return results
    max_theta = fit_options.get("max_theta")
    return [then(result, one.within(max_theta)) for result, one in zip(results, samples, strict=True)]


def fit_on_cluster(
    client,
    items: Sequence[Samples | str | os.PathLike],
    model: Model,
    loss: str,
    *,
    read_options: dict[str, Any] | None = None,
    start: dict[str, Any] | Sequence[dict[str, Any] | None] | None = None,
    progress: bool | None = None,
    **options: Any,
) -> list[FitResult]:
    """The results of :func:`fit_here` for ``items`` (datasets, or paths that the workers read with
    :func:`brdffit.load_samples` and ``read_options``), computed on ``client``'s cluster, in the order of ``items``.

    ``model``: a built model. ``start``: one parameter dictionary for all, one per item, or None. ``options``:
    those of :func:`fit_here` but ``progress``, which is the client's bar here.
    """
    items = list(items)
    starts = starts_per_dataset(start, len(items))
    options = one_thread_each(options)
    chunks = _chunks(items, starts, model, loss, options, worker_count(client))
    tasks = [
        ([items[i] for i in chunk], [starts[i] for i in chunk], model, loss, read_options or {}, options)
        for chunk in chunks
    ]
    results: list[FitResult | None] = [None] * len(items)
    bar = progress_bar(len(items), "fit", progress)
    try:
        with closing(on_workers(client, _fit_chunk, tasks)) as done:
            for number, fitted in done:
                for index, result in zip(chunks[number], fitted, strict=True):
                    results[index] = result
                bar.update(len(chunks[number]))
    finally:
        bar.close()
    return every_fitted(results)


#: How many tasks each worker gets where there is work enough: one that ends early takes another, so that the last
#: task to end holds the others up less.
TASKS_PER_WORKER = 4


def task_size(n_items: int, workers: int, most: int) -> int:
    """How many of ``n_items`` one task takes: at most ``most``, and few enough that each of ``workers`` gets
    :data:`TASKS_PER_WORKER` tasks where there are enough items (at least 1)."""
    return max(1, min(most, -(-n_items // (TASKS_PER_WORKER * workers))))


def worker_count(client) -> int:
    """How many workers ``client``'s cluster has (at least 1)."""
    return max(1, len(client.scheduler_info(n_workers=-1)["workers"]))


def one_thread_each(options: dict[str, Any]) -> dict[str, Any]:
    """A fit's ``options`` for a worker: one thread, unless they say how many (the workers are the parallelism)."""
    return options if options.get("threads") is not None else {**options, "threads": 1}


def on_workers(client, function: Callable, tasks: Sequence[tuple]) -> Generator[tuple[int, Any]]:
    """``function(*arguments)`` for each argument tuple of ``tasks``, each one task on a worker of ``client`` (its
    compiled programs kept on its disk, :func:`_on_worker`), yielded as ``(index of the task, its result)`` as each
    ends. Bad input met on a worker is raised here as its one-line error; the tasks not yet done are cancelled when
    the generator is closed (use it in ``contextlib.closing``, so that an error or Ctrl-C in the caller's loop
    cancels them at once)."""
    from distributed import as_completed

    futures = {
        client.submit(_on_worker, function, *arguments, pure=False, key=f"brdffit-{index}-{os.urandom(4).hex()}"): index
        for index, arguments in enumerate(tasks)
    }
    try:
        for future in as_completed(list(futures)):
            result, index = future.result(), futures.pop(future)  # a result fetched is let go on its worker
            if isinstance(result, _BadInput):
                raise BrdfInputError(result.message)
            yield index, result
    finally:
        client.cancel(list(futures))


def _on_worker(function: Callable, *arguments):
    """One task, on a worker: ``function(*arguments)`` with the worker's compiled programs kept on disk. Bad input comes
    back as its one-line message (:class:`_BadInput`), for the client to raise: a task that raised would have the
    worker log a traceback."""
    from ..._programs.cache import enable_compilation_cache

    enable_compilation_cache()
    try:
        return function(*arguments)
    except BrdfInputError as error:
        return _BadInput(str(error))


def _chunks(items: list, starts: list, model: Model, loss: str, options: dict, workers: int) -> list[list[int]]:
    """The indices of ``items`` each task fits, in runs of at most :data:`PER_TASK` and small enough that every
    worker gets four tasks where there are enough items: datasets in memory cut within ``fit_many``'s own work
    units (one bucket's batch, whose programs stack the datasets and treat each alone), paths in runs of
    consecutive ones."""
    in_memory = [index for index, item in enumerate(items) if isinstance(item, Samples)]
    held = options.get("holding", Holding())
    kept = [checked(items[index], model, loss, options.get("max_theta"), holding=held).samples for index in in_memory]
    units = [
        [in_memory[position] for position in unit.indices]
        for unit in work_units(model, kept, [starts[index] is not None for index in in_memory])
    ]
    paths = [index for index, item in enumerate(items) if not isinstance(item, Samples)]
    size = task_size(len(items), workers, PER_TASK)
    return [run[i : i + size] for run in [*units, paths] for i in range(0, len(run), size)]


def _fit_chunk(items: list, starts: list, model, loss: str, read_options: dict, options: dict) -> list[FitResult]:
    """One task's work, on a worker: read what is a path, fit everything (warnings are the results' own; the client
    raises them)."""
    samples = [item if isinstance(item, Samples) else load_samples(item, **read_options) for item in items]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_here(samples, model, loss, start=starts, progress=False, **options)


class _BadInput(NamedTuple):
    message: str
