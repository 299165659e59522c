"""The compiled programs every fit of a lobe model runs, over datasets stacked as arrays (D, …): one dataset, or a
batch of a bucket of many (``fitting/many/buckets.py``: datasets whose problems stack). A material library or the
texels of a capture pay no Python per dataset and per solver step; a single fit runs the same computation:

1. start (:meth:`StackedFit.starts`): the grid start search of every dataset (``starts/grid.py``), on its search
   subset when it has one, then a race of each dataset's ``n_starts`` starts: on the subset, Levenberg-Marquardt to
   convergence; without one, :data:`RACE_STEPS` steps on every sample, run by the program of step 2 with a smaller
   step budget;
2. solve (:meth:`StackedFit.solve`): Levenberg-Marquardt from the winner on every sample (float32 fits: refined in
   float64 after; a parameter pulled beyond its bound: solved again on it);
3. caveats and results (:meth:`StackedFit.results`): the caveats' screens of every dataset in one program (and, for
   the fits its albedo screen leaves open, a finer grid in another, ``caveats._refined``).

Inside a program the datasets are solved one after another (``lax.map``) on a CPU, where a vectorised
while-loop would run every fit until the slowest ends; on a GPU all at once (``vmap``), which fills the device.
"""

import threading
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from ..._jax import float64, jax
from ..._programs import built_once, jit
from ...data.reciprocity import ReciprocityAhead
from ...data.samples import Samples
from ...physics.models.model import LobeModel, Model
from ..objective.losses import Loss
from ..objective.problem import Problem, build_problems, padded_size
from ..options import Solving
from ..solver.compiled import SAME_COST, best_index, solved_from
from ..solver.hold import Hold, at_bounds, prior_cost
from ..starts.grid import grid_channels, grid_starts, search_subset
from .caveats import Screened, screen_bucket, screen_program
from .constraints import Constraints
from .outcome import final_params, result_of
from .result import FitResult

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


class StackedFit:
    """The fit of datasets of one bucket (one dataset, or a batch of many) in the compiled programs every fit shares:
    built from the data, then :meth:`starts` → :meth:`solve` → :meth:`results`.

    ``hold``: what every dataset's fit holds (``hold.py``), or None. ``solving``: the starts, steps, dtype and seed
    (``fitting/options.py``). ``strategy``: ``loop`` or ``vmap`` (:func:`default_strategy`). ``stack``: how many
    datasets the programs stack them to (:func:`stack_size` of the bucket's batches; by default that of these).
    ``on_stage``: called with ``"searched"`` once the grid starts are searched and ``"compiled"`` once the programs
    of the search and of the solve are compiled (with given starts, before anything has run; a float32 fit's
    refinement and a bounded fit's second solve compile later): ``many/threads.py`` starts its other threads then.
    The caveats' screen program compiles in the background meanwhile (``caveats.screen_program``; a single fit's from
    a given start once its solve is lowered, :meth:`_compile_screens`).
    """

    @float64
    def __init__(
        self,
        model: LobeModel,
        loss: Loss,
        samples: Sequence[Samples],
        hold: Hold | None = None,
        *,
        solving: Solving,
        strategy: str,
        stack: int | None = None,
        on_stage: Callable[[str], None] | None = None,
        caveats: bool = True,
    ):
        self.model, self.loss, self.samples, self.hold = model, loss, list(samples), hold
        max_steps, dtype = solving.max_steps, solving.dtype
        self.n_starts, self.max_steps, self.dtype, self.seed = solving.n_starts, max_steps, dtype, solving.seed
        self.strategy = strategy
        self.on_stage = on_stage or (lambda stage: None)
        self.count = stack_size([len(samples)]) if stack is None else stack  # few distinct counts, few programs
        self.problems = build_problems(samples, dtype, self.count)
        self.holds = None if hold is None else jax.tree.map(partial(_stacked_leaf, count=self.count), hold)
        self.solver = bucket_solver(model, loss, max_steps, dtype, strategy == "vmap")
        self.budget = step_budget(max_steps)
        self.caveats = caveats
        self._screen_program = screen_program(model, samples, self.count) if caveats else None
        self._screen_compiling: threading.Thread | None = None  # started by _compile_screens
        # One dataset's reciprocity is checked while its programs trace and compile (a MERL-size file's directions take
        # ~0.3 s to pair); a batch's datasets mostly share their directions, whose pairs the first check keeps for the
        # others. The solve runs once it is done (:meth:`solve`): its k-d trees (~20 MB at MERL size) and the solve's
        # run never meet, and a MERL-size fit's peak memory stays under 600 MB.
        self._reciprocal = ReciprocityAhead(self.samples[0]) if caveats and len(self.samples) == 1 else None

    @float64
    def starts(self, given: np.ndarray | None = None) -> np.ndarray:
        """Each dataset's start (D, 1, k): ``given`` (D, k) as it is; else the best of the grid (``starts/grid.py``),
        its ``n_starts`` best shapes raced: to convergence on the search subset of large datasets, a few steps
        (:data:`RACE_STEPS`) on every sample of small ones."""
        model, count, holds = self.model, self.count, self.holds
        if given is None or self._reciprocal is None:  # a single fit from a given start: once its solve is lowered
            self._compile_screens()
        if given is not None:
            self.on_stage("compiled")
            return padded_rows(given, count)[:, None]
        # The program that solves the winners compiles in the background, during the grid search; but when the
        # starts race on a subset, only after it (the race's program compiles then, and three compilations at
        # once on 2 cores cost 20 × 100k Ward ~1 s).
        one_start = jax.ShapeDtypeStruct((count, 1, model.unconstrained.size(self.samples[0].n_channels)), np.float64)
        winners = lambda: compile_in_background(self.solver, one_start, self.problems, holds, self.budget)
        subsets = [search_subset(one, self.seed) for one in self.samples]
        search = None
        if subsets[0] is not None:
            # a bucket's datasets have one size: a subset for each, or none
            chosen = [
                one if subset is None else one.select(subset) for one, subset in zip(self.samples, subsets, strict=True)
            ]
            search = build_problems(chosen, self.dtype, count)
        subset_race = search is not None and self.n_starts > 1
        compiling = None if subset_race else winners()
        channels = grid_channels(model, self.samples[0].channels)  # a bucket's datasets share their channels
        thetas = np.asarray(
            grid_starts(model, self.loss, self.n_starts, self.problems if search is None else search, holds, channels)
        )
        self.on_stage("searched")
        if subset_race:
            # Compiled before (a later batch, a second call): said now, so that other threads start beside the race.
            said = self.solver.is_compiled(thetas, search, holds, self.budget) and self.solver.is_compiled(
                one_start, self.problems, holds, self.budget
            )
            if said:
                self.on_stage("compiled")
            compiling = winners()
            if thetas.shape[1] > 1:  # the starts race to convergence on the subset
                thetas = _best(self.solver(thetas, search, holds, self.budget)).theta[:, None]
        assert compiling is not None  # started before the search, or after the race
        compiling.join()
        if not (subset_race and said):
            self.on_stage("compiled")
        if thetas.shape[1] > 1:  # the starts race a few steps on every sample, one start at a time
            budget = step_budget(min(RACE_STEPS, self.max_steps))
            raced = [self.solver(thetas[:, [s]], self.problems, holds, budget) for s in range(thetas.shape[1])]
            thetas = _best(jax.tree.map(lambda *leaves: np.concatenate(leaves, axis=1), *raced)).theta[:, None]
        return thetas

    @float64
    def solve(self, thetas: np.ndarray):
        """The best solve (``solver.compiled.Solved`` of numpy arrays with a leading axis D) of each dataset from its
        start (:meth:`starts`): Levenberg-Marquardt on every sample, then a float32 fit refined in float64, and a
        bounded parameter that ended near its bound solved again on it (:func:`onto_bounds`)."""
        samples, count, holds = self.samples, self.count, self.holds
        if self._reciprocal is not None:  # compiled beside the check (nothing to do if compiled already), run after it
            self.solver.precompile_with(self._compile_screens, thetas, self.problems, holds, self.budget)
            self._compile_screens()
            self._reciprocity_checked()
        solved = _best(self.solver(thetas, self.problems, holds, self.budget))
        solver64, problems64 = self.solver, self.problems
        if self.dtype == "float32":
            solver64 = bucket_solver(self.model, self.loss, self.max_steps, "float64", self.strategy == "vmap")
            problems64 = build_problems(samples, "float64", count)
            refined = solver64(solved.theta[:, None], problems64, holds, self.budget)
            solved = _best(refined)._replace(n_steps=solved.n_steps + np.asarray(refined.n_steps)[:, 0])
        if holds is not None and self.hold is not None and np.any(self.hold.bounded):
            again = lambda theta, held: solver64(theta[:, None], problems64, held, self.budget)
            solved = onto_bounds(again, solved, holds)
        self.problems = None  # the results need none of it: its memory (~110 MB at MERL size) back before the caveats
        return jax.tree.map(lambda leaf: leaf[: len(samples)], solved)

    def _compile_screens(self) -> None:
        """Start compiling the caveats' screen program in the background (``caveats.screen_program``), once. A fit
        from grid starts starts it before its search; a single fit from a given start once its solve is lowered
        (:meth:`solve`): its tracing and lowering (~0.2 s of Python for a MERL-size Cook-Torrance fit) then run while
        XLA compiles the solve, and no longer slow the solve's own tracing by as much (the GIL is one), and its
        compilation overlaps that one's and the solve's run."""
        if self._screen_program is not None and self._screen_compiling is None:
            self._screen_compiling = compile_in_background(*self._screen_program)

    def _reciprocity_checked(self) -> None:
        """Wait for the reciprocity check started with the fit, if it is still under way."""
        if self._reciprocal is not None:
            self._reciprocal.wait()

    def results(
        self, solved, *, max_theta: float | None = None, constraints: Constraints | None = None
    ) -> list[FitResult]:
        """The :class:`FitResult` of each dataset's ``solved`` (:meth:`solve`), with its caveats: the screens of all
        of them in one program, compiled while they were solved (and the albedo screen's finer grid for the fits its
        first grid leaves open, ``caveats.screen_bucket``)."""
        leaves, structure = jax.tree.flatten(solved)  # flattened once, not once a dataset: a tile has thousands
        each = [structure.unflatten([leaf[p] for leaf in leaves]) for p in range(len(self.samples))]
        n_channels = self.samples[0].n_channels
        params = [final_params(self.model, one, n_channels) for one in each]
        screens: Sequence[Screened | None] = [None] * len(params)
        reciprocals = [self._reciprocal] * len(params)  # a check started with the fit: of its one dataset
        if self._screen_program is not None:  # with caveats
            self._compile_screens()
            assert self._screen_compiling is not None  # started now, if not before
            self._screen_compiling.join()
            screens = screen_bucket(self.model, params, self.samples, self.count)
        return [
            result_of(
                self.model,
                self.loss,
                samples,
                one,
                self.max_steps,
                self.dtype,
                max_theta=max_theta,
                screened=screened,
                constraints=constraints,
                params=fitted,
                with_caveats=self.caveats,
                reciprocal=reciprocal,
            )
            for samples, one, fitted, screened, reciprocal in zip(
                self.samples, each, params, screens, reciprocals, strict=True
            )
        ]


def onto_bounds(solve, solved, holds):
    """``solved`` (numpy, leading axis D), each dataset solved again from its optimum with the bounded parameters
    that ended near a bound held on it (``hold.at_bounds``), where that is no worse: the optimum of a fit whose
    data pull a parameter beyond its bound is on the bound, which the logistic map reaches only in the limit.
    ``solve(thetas (D, k), holds) -> Solved (D, 1, …)``."""
    again = _best(solve(solved.theta, at_bounds(solved.theta, holds)))
    # Compared as the solver minimised them: a prior's part (hold.py) too, which the reported costs leave out.
    objective = lambda run: run.cost + prior_cost(run.theta, holds)
    better = objective(again) <= objective(solved) * (1.0 + SAME_COST)
    again = again._replace(n_steps=solved.n_steps + again.n_steps)
    return jax.tree.map(
        lambda new, old: np.where(better.reshape(-1, *[1] * (np.ndim(old) - 1)), new, old), again, solved
    )


def padded_rows(rows: np.ndarray, count: int) -> np.ndarray:
    """``rows`` (D, …), one per dataset, then for the stack's rows beyond D (copies of the first dataset,
    ``problem.build_problems``) its first row: (count, …)."""
    return np.concatenate([rows, np.repeat(rows[:1], count - len(rows), axis=0)])


def _stacked_leaf(leaf, count: int) -> np.ndarray:
    """A hold's array for ``count`` stacked datasets: one (k,) for every dataset, or one row per dataset (D, k)
    (:func:`padded_rows`)."""
    leaf = np.asarray(leaf, dtype=float)
    return np.broadcast_to(leaf, (count, leaf.size)) if leaf.ndim == 1 else padded_rows(leaf, count)


def _best(solved):
    """The best run (``solver/compiled.best_index``) of each dataset: Solved (D, S, …) → (D, …), on the host."""
    solved = jax.tree.map(np.asarray, solved)
    chosen = best_index(solved.cost)
    rows = np.arange(len(chosen))
    return jax.tree.map(lambda leaf: leaf[rows, chosen], solved)


def _is_static(leaf) -> bool:
    """Whether a program's argument is static (a model, a loss): passed on as it is, not by its shape."""
    return isinstance(leaf, (Model, Loss))


def compile_in_background(solve, *arguments) -> threading.Thread:
    """Compile ``solve`` (a :func:`~brdffit._programs.jit` function) for ``arguments`` (``jax.ShapeDtypeStruct``s,
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
        except (Exception, KeyboardInterrupt):  # the call that follows raises it properly; an interrupt (the stop of
            pass  # every write, ``_files.stop_writing``, met storing the program) is the main thread's to report

    thread = threading.Thread(target=compile_quietly, name="brdffit-compile", daemon=True)
    thread.start()
    return thread


def step_budget(steps: int) -> np.ndarray:
    """The most steps a solve of :func:`bucket_solver` takes, as the array its program takes."""
    return np.asarray(steps, np.int32)


@built_once
def bucket_solver(model: LobeModel, loss: Loss, max_steps: int, dtype: str, vectorise: bool):
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

    return jit(solve, name=f"{__name__}.bucket_solver", closes_over=(model, loss, max_steps, dtype, vectorise))
