"""Many datasets of one shape fitted at once: the start search and every solve of a bucket in compiled programs.

A *bucket* is a list of datasets whose problems stack: the same padded size (``problem.padded_size``), channel
count and optional columns, all searched on a subset or none (:func:`bucket_key`). A bucket goes through the
fit's steps as arrays (D, …) in a few compiled programs, so a material library or the texels of a capture pay
no Python per dataset and per solver step:

1. the grid start search of every dataset (``starts.grid_starts``), on its search subset when it has one;
2. a race of each dataset's ``n_starts`` starts: on the subset, Levenberg-Marquardt to convergence; without one,
   :data:`RACE_STEPS` steps on every sample, run by the program of step 3 with a smaller step budget;
3. Levenberg-Marquardt from the winner on every sample (float32 fits: refined in float64 after).

Inside a program the datasets are solved one after another (``lax.map``) on a CPU, where a vectorised
while-loop would run every fit until the slowest ends; on a GPU all at once (``vmap``), which fills the device.
A single fit is a bucket of one (``fit.py``), so both paths are the same computation.
"""

import threading
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from ..._jax import float64, jax
from ..._programs import built_once, jit
from ...data.samples import Samples
from ...physics.models.model import Model
from ..objective.losses import Loss
from ..objective.problem import Problem, build_problems, padded_size
from ..solver.compiled import SAME_COST, best_index, solved_from
from ..solver.hold import Hold, at_bounds
from ..starts.grid import grid_starts, search_subset

#: Steps of the race between the starts of a dataset searched on all its samples: the one of lowest cost after
#: them goes on. Measured on 1,000 Ward and 300 Cook-Torrance fits of 500 samples: after 2 steps the race picked a
#: start that ends at the best cost of the three in every one (after 1, 3 Cook-Torrance fits ended worse).
RACE_STEPS = 2


def stack_size(batch_lengths: Sequence[int]) -> int:
    """How many datasets the batches of one bucket are stacked to (``problem.build_problems``' ``count``): one
    value for them all, so that they run one compiled program; the rows after a batch's last are copies."""
    return padded_size(max(batch_lengths))


def default_strategy() -> str:
    """How a program goes through a bucket's datasets: all at once on a GPU (``vmap``), else one after another
    (``loop``)."""
    return "vmap" if jax.default_backend() in ("gpu", "cuda", "rocm") else "loop"


@float64
def solve_bucket(
    model: Model,
    loss: Loss,
    samples: Sequence[Samples],
    starts: np.ndarray | None,
    *,
    n_starts: int,
    max_steps: int,
    dtype: str,
    seed: int,
    strategy: str,
    hold: Hold | None = None,
    stack: int | None = None,
    on_stage: Callable[[str], None] | None = None,
):
    """The best solve (a ``fit.Solved`` of numpy arrays with a leading axis D) of each dataset of one bucket.

    ``starts`` (D, k): the unconstrained start of each dataset, or None to search the grid for them. ``hold``:
    what every dataset's fit holds (``hold.py``), or None. ``stack``: how many datasets to stack them to
    (:func:`stack_size` of the bucket's batches; by default that of this one). ``on_stage``: called with
    ``"searched"`` once the starts are searched, and ``"compiled"`` right before the final solve, when the programs
    of the search and the race have run and that of the solve is compiled (with given starts, nothing has run yet;
    a float32 fit's refinement and a bounded fit's second solve compile after it).
    """
    on_stage = on_stage or (lambda stage: None)
    count = stack_size([len(samples)]) if stack is None else stack  # few distinct counts, few compiled programs
    full = build_problems(samples, dtype, count)
    holds = None if hold is None else jax.tree.map(lambda leaf: np.broadcast_to(leaf, (count, leaf.size)), hold)
    solver = bucket_solver(model, loss, max_steps, dtype, strategy == "vmap")
    full_budget = step_budget(max_steps)
    solve = lambda thetas, problems: solver(thetas, problems, holds, full_budget)
    if starts is not None:
        thetas = np.concatenate([starts, np.repeat(starts[:1], count - len(samples), axis=0)])[:, None]
    else:
        # The program that solves the winners compiles in the background, during the grid search; but when the
        # starts race on a subset, only after it (the race's program compiles then, and three compilations at
        # once on 2 cores cost 20 × 100k Ward ~1 s).
        one_start = jax.ShapeDtypeStruct((count, 1, model.unconstrained.size(samples[0].n_channels)), np.float64)
        winners = lambda: compile_in_background(solver, one_start, full, holds, full_budget)
        subsets = [search_subset(one, seed) for one in samples]
        search = None
        if subsets[0] is not None:
            chosen = [one.select(subset) for one, subset in zip(samples, subsets, strict=True)]
            search = build_problems(chosen, dtype, count)
        subset_race = search is not None and n_starts > 1
        compiling = None if subset_race else winners()
        thetas = np.asarray(grid_starts(model, loss, n_starts, full if search is None else search, holds))
        on_stage("searched")
        if subset_race:
            compiling = winners()
            if thetas.shape[1] > 1:  # the starts race to convergence on the subset
                thetas = _best(solve(thetas, search)).theta[:, None]
        compiling.join()
        if thetas.shape[1] > 1:  # the starts race a few steps on every sample, one start at a time
            budget = step_budget(min(RACE_STEPS, max_steps))
            raced = [solver(thetas[:, [s]], full, holds, budget) for s in range(thetas.shape[1])]
            thetas = _best(jax.tree.map(lambda *leaves: np.concatenate(leaves, axis=1), *raced)).theta[:, None]
    on_stage("compiled")
    solved = _best(solve(thetas, full))
    if dtype == "float32":
        refined = bucket_solver(model, loss, max_steps, "float64", strategy == "vmap")(
            solved.theta[:, None], build_problems(samples, "float64", count), holds, full_budget
        )
        solved = _best(refined)._replace(n_steps=solved.n_steps + np.asarray(refined.n_steps)[:, 0])
    if holds is not None and np.any(hold.bounded):
        solver64 = (
            solver if dtype == "float64" else bucket_solver(model, loss, max_steps, "float64", strategy == "vmap")
        )
        problems64 = full if dtype == "float64" else build_problems(samples, "float64", count)
        solved = onto_bounds(lambda theta, held: solver64(theta[:, None], problems64, held, full_budget), solved, holds)
    return jax.tree.map(lambda leaf: leaf[: len(samples)], solved)


def onto_bounds(solve, solved, holds):
    """``solved`` (numpy, leading axis D), each dataset solved again from its optimum with the bounded parameters
    that ended near a bound held on it (``hold.at_bounds``), where that is no worse: the optimum of a fit whose
    data pull a parameter beyond its bound is on the bound, which the logistic map reaches only in the limit.
    ``solve(thetas (D, k), holds) -> Solved (D, 1, …)``."""
    again = _best(solve(solved.theta, at_bounds(solved.theta, holds)))
    better = again.cost <= solved.cost * (1.0 + SAME_COST)
    again = again._replace(n_steps=solved.n_steps + again.n_steps)
    return jax.tree.map(
        lambda new, old: np.where(better.reshape(-1, *[1] * (np.ndim(old) - 1)), new, old), again, solved
    )


def _best(solved):
    """The best run (``solve.best_index``) of each dataset: Solved (D, S, …) → (D, …), on the host."""
    solved = jax.tree.map(np.asarray, solved)
    chosen = best_index(solved.cost)
    rows = np.arange(len(chosen))
    return jax.tree.map(lambda leaf: leaf[rows, chosen], solved)


def _is_static(leaf) -> bool:
    """Whether a program's argument is static (a model, a loss): passed on as it is, not by its shape."""
    return isinstance(leaf, (Model, Loss))


def compile_in_background(solve, *arguments) -> threading.Thread:
    """Compile ``solve`` (a :func:`~brdffit._jax.jit` function) for ``arguments`` (``jax.ShapeDtypeStruct``s,
    arrays whose shapes are taken, or static models and losses) in a thread, while the caller does other work (the
    start search, the solves before a caveat screen): XLA compiles with the GIL released, so on two or more cores a
    program's compilation (~1 s for a MERL-size Cook-Torrance solve) overlaps that work instead of following it. A
    failure there is left for the real call to report."""
    shapes = jax.tree.map(
        lambda leaf: leaf if _is_static(leaf) else jax.ShapeDtypeStruct(leaf.shape, leaf.dtype),
        arguments,
        is_leaf=_is_static,
    )

    def compile_quietly():
        try:
            solve.precompile(*shapes)
        except Exception:  # the call that follows raises it properly
            pass

    thread = threading.Thread(target=compile_quietly, name="brdffit-compile", daemon=True)
    thread.start()
    return thread


def step_budget(steps: int) -> np.ndarray:
    """The most steps a solve of :func:`bucket_solver` takes, as the array its program takes."""
    return np.asarray(steps, np.int32)


@built_once
def bucket_solver(model: Model, loss: Loss, max_steps: int, dtype: str, vectorise: bool):
    """``solve(thetas (D, S, k), problems (D, N, …), holds (D, k) or None, budget) -> Solved (D, S, …)``: every
    start of every dataset, each solve stopping after ``budget`` steps (:func:`step_budget`, at most
    ``max_steps``): one compiled program runs both the race of the starts and the winner's solve."""
    one = partial(solved_from, model, loss, max_steps, dtype)

    def solve(thetas, problems: Problem, holds: Hold | None, budget):
        if vectorise:
            return jax.vmap(
                lambda starts, problem, hold: jax.vmap(lambda theta: one(theta, problem, hold, budget))(starts)
            )(thetas, problems, holds)

        def each_dataset(triple):
            starts, problem, hold = triple
            return jax.lax.map(lambda theta: one(theta, problem, hold, budget), starts)

        return jax.lax.map(each_dataset, (thetas, problems, holds))

    return jit(solve, name=f"fitting.buckets.solve[{model!r}, {loss!r}, {max_steps}, {dtype!r}, {vectorise}]")
