"""How many datasets are cut into units of work: buckets of datasets whose problems stack, and batches of a bucket.

A *bucket* is a list of datasets whose problems stack: the same padded size (``problem.padded_size``), channels
(their names too: a conductor's measured starts are in the data's channels) and optional columns, all searched on
a subset or none (:func:`bucket_key`). Each bucket is cut into batches
(:func:`batches`) that the threads fit one at a time, each in the compiled programs of ``single/stacked.py``.
"""

from collections.abc import Sequence
from itertools import pairwise
from typing import NamedTuple

from ...data.samples import Samples
from ...physics.models.model import LobeModel, Model
from ..objective.problem import padded_size
from ..single.stacked import stack_size
from ..starts.grid import SEARCH_SAMPLES

#: The most samples (datasets × padded size) in one batch of a bucket: its arrays take ~100 bytes a sample.
BATCH_SAMPLES = 2**21


class BucketKey(NamedTuple):
    """What datasets must share to be stacked into one batch."""

    padded_size: int
    n_channels: int
    channels: tuple[str, ...]
    has_sigma: bool
    has_weight: bool
    searched_on_subset: bool


def bucket_key(samples: Samples) -> BucketKey:
    return BucketKey(
        padded_size(samples.n_samples),
        samples.n_channels,
        samples.channels,
        samples.sigma is not None,
        samples.weight is not None,
        samples.n_samples > SEARCH_SAMPLES,
    )


def batches(indices: Sequence[int], size: int, threads: int = 1) -> list[list[int]]:
    """``indices`` (one bucket's datasets of ``size`` padded samples) cut into batches for ``threads`` threads that
    run one batch each at a time: together at most :data:`BATCH_SAMPLES` samples, a multiple of ``threads`` batches
    (unless there are fewer datasets), as few as that allows and of sizes that differ by one at most: 20 datasets
    that need two batches go as 10 + 10, which stack into one compiled program, not as 19 + 1, which need two."""
    per_batch = max(1, BATCH_SAMPLES // threads // size)
    count = min(-(-len(indices) // (per_batch * threads)) * threads, len(indices))
    cuts = [len(indices) * k // count for k in range(count + 1)]
    return [list(indices[start:end]) for start, end in pairwise(cuts)]


class WorkUnit(NamedTuple):
    """Datasets fitted together: one batch of one bucket (``buckets.py``), or one dataset fitted lobe by lobe."""

    indices: list[int]
    given: bool  # every one has its start: no search
    stack: int = (
        1  # the datasets are stacked to this many (``single/stacked.stack_size``), as are the others of the bucket
    )
    size: int = 0  # samples of each stacked dataset (``problem.padded_size``)


def fitted_alone(model: Model, given: bool) -> bool:
    """Whether ``model`` fits each dataset alone rather than in a bucket's programs: the data-driven model (its own
    solve, ``datadriven/fit.py``), and a lobe model of several lobes without a given start (lobe by lobe,
    ``starts/lobes.py``)."""
    return not isinstance(model, LobeModel) or (model.n_lobes > 1 and not given)


def work_units(model: Model, samples: Sequence[Samples], given: Sequence[bool], threads: int = 1) -> list[WorkUnit]:
    """How :func:`fit_many` cuts ``samples`` (as kept for the fit) into units: by bucket and by whether the start
    is given (a given start replaces the search), each bucket in batches for ``threads`` threads
    (:func:`batches`: together at most :data:`BATCH_SAMPLES` samples at a time); a model with several
    lobes and no start, one dataset per unit."""
    groups: dict[tuple, list[int]] = {}
    for index, (one, has_start) in enumerate(zip(samples, given, strict=True)):
        groups.setdefault((bucket_key(one), has_start), []).append(index)
    units = []
    for (key, has_start), indices in groups.items():
        if fitted_alone(model, has_start):
            units += [WorkUnit([index], has_start, 1, key.padded_size) for index in indices]
        else:
            cut = batches(indices, key.padded_size, threads)
            stack = stack_size([len(batch) for batch in cut])
            units += [WorkUnit(batch, has_start, stack, key.padded_size) for batch in cut]
    return units
