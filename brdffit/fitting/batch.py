"""Fit one model to many datasets: a scanned material library, the texels of a spatially varying BRDF.

Two strategies, chosen by the backend unless asked:

* ``loop`` (CPU): one fit after another. Sizes are bucketed
  (``problem.padded_size``), so every dataset of a bucket reuses one compiled
  solver; a vmapped while-loop would instead run every fit in lockstep until
  the slowest one ends, which on a CPU costs more than it saves.
* ``vmap`` (GPU): datasets of one bucket are stacked and solved together, one
  start search per dataset, then every Levenberg-Marquardt run of the bucket
  at once.
"""

from collections.abc import Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._jax import float64
from ..checks import choice, whole_number
from ..data.samples import Samples
from ..errors import BrdfInputError
from .defaults import MAX_STEPS, N_STARTS
from .fit import checked, compiled_solver, fit_one, result_of, search_problem, start_vector
from .problem import build_problem, padded_size
from .results import FitResult
from .starts import starting_points

STRATEGIES = ("auto", "loop", "vmap")


def default_strategy() -> str:
    """``vmap`` on a GPU, ``loop`` elsewhere."""
    return "vmap" if jax.default_backend() in ("gpu", "cuda", "rocm") else "loop"


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
    **model_options: Any,
) -> list[FitResult]:
    """Fit ``model`` to each of ``samples``; the arguments are those of :func:`brdffit.fit_batch`."""
    choice("strategy", strategy, STRATEGIES)
    samples = list(samples)
    if not samples:
        raise BrdfInputError("fit_batch needs at least one dataset")
    starts = list(start) if isinstance(start, Sequence) else [start] * len(samples)
    if len(starts) != len(samples):
        raise BrdfInputError(f"{len(starts)} starts for {len(samples)} datasets; give one per dataset or one for all")
    options = dict(max_theta=max_theta, n_starts=n_starts, max_steps=max_steps, dtype=dtype, seed=seed)
    strategy = default_strategy() if strategy == "auto" else strategy
    bar = _progress_bar(len(samples), progress)
    try:
        if strategy == "loop":
            results = []
            for one, one_start in zip(samples, starts, strict=True):
                results.append(fit_one(one, model, loss, start=one_start, **options, **model_options))
                bar.update(1)
            return results
        return _fit_vmapped(samples, model, loss, bar, starts=starts, **options, **model_options)
    finally:
        bar.close()


def _progress_bar(total: int, enabled: bool | None):
    from tqdm.auto import tqdm

    # disable=None: tqdm shows the bar only when its stream (stderr) is a terminal.
    return tqdm(total=total, unit="fit", disable=None if enabled is None else not enabled, leave=False)


def _fit_vmapped(samples, model, loss, bar, *, starts, max_theta, n_starts, max_steps, dtype, seed, **model_options):
    """Every dataset of a bucket (same padded size and channel count) solved at once, each start in parallel."""
    kept_by_check = [checked(one, model, loss, max_theta, dtype, **model_options) for one in samples]
    model, loss = kept_by_check[0][0], kept_by_check[0][1]
    kept = [one for _, _, one in kept_by_check]
    n_starts = whole_number("n_starts", n_starts)
    max_steps = whole_number("max_steps", max_steps)
    solve = jax.vmap(compiled_solver(model, loss, max_steps, dtype))
    results: list[FitResult | None] = [None] * len(kept)
    # One bucket per padded size, channel count and optional columns: its problems stack into one pytree.
    buckets: dict[tuple[int, int, bool, bool], list[int]] = {}
    for index, one in enumerate(kept):
        key = (padded_size(one.n_samples), one.n_channels, one.sigma is None, one.weight is None)
        buckets.setdefault(key, []).append(index)
    for indices in buckets.values():
        problems = [build_problem(kept[i], dtype) for i in indices]
        if any(starts[i] is None for i in indices):
            thetas = _best_starts(model, loss, [kept[i] for i in indices], problems, n_starts, solve, dtype, seed)
        else:
            thetas = np.zeros((len(indices), model.unconstrained.size(kept[indices[0]].n_channels)))
        for position, index in enumerate(indices):
            if starts[index] is not None:  # a given start replaces the searched one
                thetas[position] = start_vector(model, starts[index], kept[index].n_channels)
        solved = solve(jnp.asarray(thetas), _stacked(problems))
        if dtype == "float32":
            stacked = _stacked([build_problem(kept[i]) for i in indices])
            refined = jax.vmap(compiled_solver(model, loss, max_steps))(solved.theta, stacked)
            solved = refined._replace(n_steps=solved.n_steps + refined.n_steps)
        for position, index in enumerate(indices):
            one = jax.tree.map(lambda leaf, p=position: leaf[p], solved)
            results[index] = result_of(model, loss, kept[index], one, max_steps, dtype, max_theta=max_theta)
        bar.update(len(indices))
    return results


def _best_starts(model, loss, samples, problems, n_starts, solve, dtype, seed):
    """For each dataset, the best of its ``n_starts`` grid starts after a solve on its search subsample."""
    searches = [search_problem(one, problem, dtype, seed) for one, problem in zip(samples, problems, strict=True)]
    starts = [starting_points(model, loss, search, n_starts) for search in searches]
    if all(len(s) == 1 for s in starts):
        return np.stack([s[0] for s in starts])
    # Every start of every dataset in one vmapped solve (datasets repeated once per start).
    width = max(len(s) for s in starts)
    padded = [s + [s[0]] * (width - len(s)) for s in starts]
    thetas = jnp.asarray(np.stack([theta for s in padded for theta in s]))
    repeated = jax.tree.map(lambda leaf: jnp.repeat(leaf, width, axis=0), _stacked(searches))
    solved = solve(thetas, repeated)
    best = np.argmin(np.asarray(solved.cost).reshape(len(starts), width), axis=1)
    return np.asarray(solved.theta).reshape(len(starts), width, -1)[np.arange(len(starts)), best]


def _stacked(problems):
    """Problems of one bucket as one problem with a leading batch axis."""
    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *problems)
