"""Fit a model to samples: Levenberg-Marquardt (optimistix) from data-driven starts.

The parameters move in unconstrained coordinates (``domains.py``), so every
step is physically valid. The solver (``solver.py``) is compiled once per
model, loss and bucketed data size (``problem.padded_size``) and reused for
every start and every dataset of that size. On large data the starts are
searched on a subset (``starts.search_subset``) and only the winner is refined
on all of them.
"""

import threading
from functools import cache, partial
from typing import TYPE_CHECKING, Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._jax import jit  # float64 before any array; jax.jit with brdffit's compiler options
from ..checks import whole_number
from ..data.samples import Samples
from ..errors import BrdfInputError
from ..physics.models import Model, Params, get_model
from .losses import Loss, get_loss
from .problem import DTYPES, Problem, build_problem, normal_equations, prepared
from .results import FitResult
from .solver import LevenbergMarquardt
from .starts import search_subset, starting_points

if TYPE_CHECKING:
    from ..uncertainty.mcmc import MCMC

#: Stopping tolerances (``solver.py``) per dtype: MINPACK's ftol (relative cost reduction), gtol (largest cosine
#: between a Jacobian column and the residuals) and the residual norm of an exact fit. In float64, ftol 1e-10
#: leaves each parameter within ~sqrt(1e-10·N) standard errors of the optimum (0.002 σ for 10⁴ samples × 3
#: channels, 0.02 σ at MERL's 4.4·10⁶) and gtol 1e-8 within ~1e-8·sqrt(N) σ. A float32 model makes residuals
#: that differ by 1% carry ~1e-4 relative rounding error, so its cost jitters at ~1e-5 and only loose tests can
#: pass; the float32 stage merely has to land near the optimum, which float64 then refines.
TOLERANCES = {"float64": (1e-10, 1e-8, 1e-8), "float32": (1e-5, 1e-4, 1e-5)}
MAX_STEPS = 256
N_STARTS = 3


def fit(
    samples: Samples,
    model: str | Model = "ward",
    loss: str = "log",
    *,
    max_theta: float | None = None,
    start: dict[str, Any] | None = None,
    n_starts: int = N_STARTS,
    max_steps: int = MAX_STEPS,
    dtype: str = "float64",
    seed: int = 0,
    uncertainty: str | None = None,
    mcmc: "MCMC | None" = None,
    chain: str | None = None,
    progress: bool = False,
    **model_options: Any,
) -> FitResult:
    """Fit ``model`` to ``samples`` by minimising ``loss`` (SPEC section 3).

    ``max_theta``: drop samples with θi or θo above this many degrees.
    ``start``: parameters (SPEC section 5 dictionary) to start from instead of
    the data-driven starts. ``n_starts``: how many of the best grid starts to
    run Levenberg-Marquardt from; the lowest cost wins. ``dtype``: ``float32``
    runs the solve with the model in single precision (sums stay float64) and
    then refines the optimum in float64 (mixed-precision iterative refinement,
    usually one or two steps), so the result is float64's.
    ``seed``: the random part of the subset the starts are searched on (for
    more than ``starts.SEARCH_SAMPLES`` samples). ``uncertainty``: ``"laplace"``
    or ``"mcmc"`` adds the result's ``uncertainty`` block (``laplace.py``,
    ``mcmc.py``); ``mcmc`` (:class:`brdffit.MCMC`: walkers, steps, burn, thin,
    seed), ``chain`` (a ``.npz`` or ``.h5`` file for the chain) and ``progress``
    (a progress bar) apply to ``"mcmc"``. ``model_options``: ``fresnel=`` for
    cook-torrance, ``lobes=`` for lafortune.
    """
    if uncertainty is not None or mcmc is not None or chain is not None:  # imported only when asked for
        from ..uncertainty.mcmc import MCMC, check_walkers
        from ..uncertainty.methods import check_options, with_uncertainty

        check_options(uncertainty, mcmc, chain)
    model, loss, samples = _checked(samples, model, loss, max_theta, dtype, **model_options)
    if uncertainty == "mcmc":
        check_walkers(mcmc or MCMC(), model, samples)
    n_starts = whole_number("--starts", n_starts)
    max_steps = whole_number("--max-steps", max_steps)
    full = build_problem(samples, dtype)
    solve = compiled_solver(model, loss, max_steps, dtype)
    if start is not None:
        starts = [start_vector(model, start, samples.n_channels)]
    else:
        search = search_problem(samples, full, dtype, seed)
        compiling = None if search is full else _compile_in_background(solve, model, full)
        starts = starting_points(model, loss, search, n_starts)
        if search is not full and len(starts) > 1:
            starts = [_best([solve(theta, search) for theta in starts]).theta]
        if compiling is not None:
            compiling.join()
    solved = _best([solve(theta, full) for theta in starts])
    if dtype == "float32":
        refined = compiled_solver(model, loss, max_steps)(solved.theta, build_problem(samples))
        solved = refined._replace(n_steps=solved.n_steps + refined.n_steps)
    result = result_of(model, loss, samples, solved, max_steps, dtype)
    if uncertainty is None:
        return result
    return with_uncertainty(result, samples, uncertainty, mcmc=mcmc, chain=chain, progress=progress)


def _compile_in_background(solve, model: Model, problem: Problem) -> threading.Thread:
    """Compile ``solve`` for the full ``problem`` in a thread while the starts are searched on a subset.

    XLA compiles with the GIL released, so on two or more cores the full-size
    solver's compilation (~1 s for a MERL-size Cook-Torrance problem) overlaps
    the search instead of following it. A failure there is left for the real
    call to report.
    """
    shapes = jax.tree.map(lambda leaf: jax.ShapeDtypeStruct(leaf.shape, leaf.dtype), problem)
    theta = jax.ShapeDtypeStruct((model.n_parameters(problem.measured.shape[1]),), jnp.float64)

    def compile_quietly():
        try:
            solve.precompile(theta, shapes)
        except Exception:  # the call that follows raises it properly
            pass

    thread = threading.Thread(target=compile_quietly, name="brdffit-compile", daemon=True)
    thread.start()
    return thread


def search_problem(samples: Samples, full: Problem, dtype: str, seed: int) -> Problem:
    """The problem the starts are searched on: ``full``, or that of the subset ``starts.search_subset`` picks."""
    subset = search_subset(samples, seed)
    return full if subset is None else build_problem(samples.select(subset), dtype)


def _checked(samples, model, loss, max_theta, dtype, **model_options) -> tuple[Model, Loss, Samples]:
    """The model, the loss and the samples kept by ``max_theta``, after every check of the arguments."""
    model = get_model(model, **model_options)
    loss = get_loss(loss)
    if not isinstance(samples, Samples):
        raise BrdfInputError(f"fit takes Samples (from brdffit.load_samples), got {type(samples).__name__}")
    if dtype not in DTYPES:
        raise BrdfInputError(f"--dtype {dtype!r} is not allowed; choose one of: {', '.join(DTYPES)}")
    samples = samples.within(max_theta)
    n_parameters = model.n_parameters(samples.n_channels)
    if samples.values.size < n_parameters:
        raise BrdfInputError(
            f"{samples.source}: {samples.n_samples} sample(s) × {samples.n_channels} channel(s) cannot determine"
            f" the {n_parameters} parameters of {model.name}; give at least {n_parameters} values"
        )
    return model, loss, samples


def start_vector(model: Model, start: dict[str, Any], n_channels: int) -> np.ndarray:
    params = model.params_from_dict(start)
    if params.diffuse.size != n_channels:
        raise BrdfInputError(
            f"start parameters have {params.diffuse.size} channel(s) but the samples have {n_channels}"
        )
    return model.to_unconstrained(params)


class Solved(NamedTuple):
    """What a compiled solve returns: the optimum in both forms and how the solve went."""

    theta: Any  # the unconstrained optimum
    cost: Any  # rᵀr there
    n_steps: Any
    result: Any  # optimistix.RESULTS
    converged: Any  # result == RESULTS.successful, decided in the compiled solve, not by a host program
    params: Params  # the optimum as physical parameters
    rmse: Any  # sqrt(mean((f - y)²)) over the real samples, 1/sr


#: Costs of two runs within this relative difference are the same optimum reached twice, equal up to rounding.
SAME_COST = 1e-12


def _best(runs: list[Solved]) -> Solved:
    """The run of lowest cost; runs within :data:`SAME_COST` of it tie, and the first (the better start) wins.

    Without the tie rule, rounding picked the winner among starts that found the same optimum, so the
    reported step count changed with how XLA happened to order a sum (the example: 4 or 7 steps).
    """
    costs = [float(run.cost) for run in runs]
    lowest = min(costs)
    return next(run for run, cost in zip(runs, costs, strict=True) if cost <= lowest + SAME_COST * abs(lowest))


def result_of(model: Model, loss: Loss, samples: Samples, solved: Solved, max_steps: int, dtype: str) -> FitResult:
    """The :class:`FitResult` of a solve."""
    converged = bool(solved.converged)
    return FitResult(
        model=model.name,
        model_options=model.model_options,
        channels=samples.channels,
        params=model.params_to_dict(jax.tree.map(np.asarray, solved.params)),
        loss=loss.name,
        cost=float(solved.cost),
        rmse=float(solved.rmse),
        n_samples=samples.n_samples,
        n_steps=int(solved.n_steps),
        converged=converged,
        message="" if converged else _failure_message(solved.result, max_steps),
        dtype=dtype,
    )


def _residual_shape(theta, problem: Problem):
    """The residuals' shape and dtype, which is all optimistix's interface needs of them here.

    The solver only calls ``normal_equations``; handing optimistix the real
    residual function would make it trace the model once more for nothing
    (0.13 s of the first fit of a Cook-Torrance model).
    """
    return jnp.zeros(problem.measured.shape, theta.dtype)


def _failure_message(result, max_steps: int) -> str:
    if result == optx.RESULTS.nonlinear_max_steps_reached:
        return (
            f"the maximum number of solver steps ({max_steps}) was reached before the tolerances were met;"
            " raise --max-steps"
        )
    return optx.RESULTS[result]


@cache
def compiled_solver(model: Model, loss: Loss, max_steps: int, dtype: str = "float64"):
    """``solve(theta0, problem) -> Solved``, compiled once per problem size."""
    ftol, gtol, atol = TOLERANCES[dtype]
    solver = LevenbergMarquardt(
        normal_equations=partial(normal_equations, model, loss), rtol=ftol, atol=atol, gtol=gtol
    )

    @jit
    def solve(theta0, problem: Problem):
        problem = prepared(loss, problem)
        solution = optx.least_squares(_residual_shape, solver, theta0, args=problem, max_steps=max_steps, throw=False)
        theta = solution.value
        params = model.from_unconstrained(theta, problem.measured.shape[1])
        cost = 2.0 * solution.state.f_info.f
        # rmse: sqrt(mean((f - y)²)) over the real samples, from the pass at the point returned.
        n_values = jnp.sum(problem.real) * problem.measured.shape[1]
        rmse = jnp.sqrt(solution.state.squared_error / n_values)
        converged = solution.result == optx.RESULTS.successful
        return Solved(theta, cost, solution.stats["num_steps"], solution.result, converged, params, rmse)

    return solve
