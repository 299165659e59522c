"""Fit a model to one set of samples: Levenberg-Marquardt (optimistix) from data-driven starts.

The parameters move in unconstrained coordinates (``Model.unconstrained``), so every step is physically
valid. The solver (``solver.py``) is compiled once per model, loss and bucketed data size
(``problem.padded_size``) and reused for every start and every dataset of that size. On large data the
starts are searched on a subset (``starts.search_subset``) and only the winner is refined on all of them.

The compiled solve is differentiable with respect to the data: its derivatives are those of the optimum
(the implicit function theorem, ``implicit.py``), never of the solver's iterations.
"""

import threading
from functools import cache, partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._jax import float64, jit
from ..checks import choice, whole_number
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..physics.domains import START_FACTOR
from ..physics.models import MODELS, Model, Params, get_model, model_option_names
from .caveats import caveats
from .defaults import MAX_STEPS, N_STARTS
from .implicit import at_optimum, computed_as
from .lobes import lobe_by_lobe
from .losses import Loss, get_loss
from .problem import DTYPES, Problem, build_problem, cost, normal_equations, prepared, residuals
from .results import FitResult
from .solver import OnePassLevenbergMarquardt
from .starts import search_subset, starting_points

#: Stopping tolerances (``solver.py``) per dtype: MINPACK's ftol (relative cost reduction), gtol (largest cosine
#: between a Jacobian column and the residuals) and the residual norm of an exact fit. In float64, ftol 1e-10
#: leaves each parameter within ~sqrt(1e-10·N) standard errors of the optimum (0.002 σ for 10⁴ samples × 3
#: channels, 0.02 σ at MERL's 4.4·10⁶) and gtol 1e-8 within ~1e-8·sqrt(N) σ. A float32 model makes residuals
#: that differ by 1% carry ~1e-4 relative rounding error, so its cost jitters at ~1e-5 and only loose tests can
#: pass; the float32 stage merely has to land near the optimum, which float64 then refines.
TOLERANCES = {"float64": (1e-10, 1e-8, 1e-8), "float32": (1e-5, 1e-4, 1e-5)}


@float64
def fit_one(
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
    **model_options: Any,
) -> FitResult:
    """Fit ``model`` to ``samples`` by minimising ``loss``; the arguments are those of :func:`brdffit.fit`."""
    model, loss, samples = checked(samples, model, loss, max_theta, dtype, **model_options)
    n_starts = whole_number("n_starts", n_starts)
    max_steps = whole_number("max_steps", max_steps)
    full = build_problem(samples, dtype)
    solve = compiled_solver(model, loss, max_steps, dtype)
    fewer_lobes_cost = None
    if start is not None:
        starts = [start_vector(model, start, samples.n_channels)]
    else:
        search = search_problem(samples, full, dtype, seed)
        compiling = None if search is full else _compile_in_background(solve, model, full)
        if model.n_lobes > 1:
            by_lobe = lobe_by_lobe(model, loss, search, solve, n_starts, best)
            starts = [by_lobe.best.theta]
            fewer_lobes_cost = by_lobe.fewer_lobes_cost if search is full else None
            if search is full:  # already solved on every sample
                return result_of(model, loss, samples, by_lobe.best, max_steps, dtype, fewer_lobes_cost, max_theta)
        else:
            starts = starting_points(model, loss, search, n_starts)
            if search is not full and len(starts) > 1:
                starts = [best([solve(theta, search) for theta in starts]).theta]
        if compiling is not None:
            compiling.join()
    solved = best([solve(theta, full) for theta in starts])
    if dtype == "float32":
        refined = compiled_solver(model, loss, max_steps)(solved.theta, build_problem(samples))
        solved = refined._replace(n_steps=solved.n_steps + refined.n_steps)
    return result_of(model, loss, samples, solved, max_steps, dtype, fewer_lobes_cost, max_theta)


def _compile_in_background(solve, model: Model, problem: Problem) -> threading.Thread:
    """Compile ``solve`` for the full ``problem`` in a thread while the starts are searched on a subset.

    XLA compiles with the GIL released, so on two or more cores the full-size
    solver's compilation (~1 s for a MERL-size Cook-Torrance problem) overlaps
    the search instead of following it. A failure there is left for the real
    call to report.
    """
    shapes = jax.tree.map(lambda leaf: jax.ShapeDtypeStruct(leaf.shape, leaf.dtype), problem)
    theta = jax.ShapeDtypeStruct((model.unconstrained.size(problem.measured.shape[1]),), jnp.float64)

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


def checked(samples, model, loss, max_theta, dtype, **model_options) -> tuple[Model, Loss, Samples]:
    """The model, the loss and the samples kept by ``max_theta``, after every check of the arguments."""
    _check_option_names(model_options)
    model = get_model(model, **model_options)
    loss = get_loss(loss)
    if not isinstance(samples, Samples):
        raise BrdfInputError(f"fit takes Samples (from brdffit.load_samples), got {type(samples).__name__}")
    choice("dtype", dtype, DTYPES)
    samples = samples.within(max_theta)
    n_parameters = model.unconstrained.size(samples.n_channels)
    if samples.values.size < n_parameters:
        raise BrdfInputError(
            f"{samples.source}: {samples.n_samples} sample(s) × {samples.n_channels} channel(s) cannot determine"
            f" the {n_parameters} parameters of {model.name}; give at least {n_parameters} values"
        )
    return model, loss, samples


def _check_option_names(options: dict[str, Any]) -> None:
    """A keyword no model takes is a misspelt argument, not a model option (``max_step`` for ``max_steps``)."""
    known = {name for each in MODELS for name in model_option_names(each)}
    for key in options:
        if key not in known:
            raise BrdfInputError(
                Argument(key),
                f" is not an argument of the fit, nor an option of any model ({', '.join(sorted(known))})",
            )


def start_vector(model: Model, start: dict[str, Any], n_channels: int) -> np.ndarray:
    """The unconstrained vector of the parameter dictionary ``start``, checked against the samples' channels and
    each lobe-shape parameter's plausible range: beyond :data:`~brdffit.physics.domains.START_FACTOR` times its
    upper end a fit cannot move (a Phong exponent of 10⁹ is a delta function, flat to every step) and would report
    a converged fit that never moved. An albedo can start anywhere: the fit moves its logarithm."""
    params = model.dictionary.to_params(start)
    if params.diffuse.size != n_channels:
        raise BrdfInputError(
            Argument("start"), f" parameters have {params.diffuse.size} channel(s) but the samples have {n_channels}"
        )
    if model.n_lobes:
        for k in range(model.n_lobes):
            for name, domain in model.lobe.parameters:
                value, limit = float(params.shape[name][k]), START_FACTOR * domain.plausible[1]
                if value > limit:
                    where = f"lobes[{k}].{name}" if model.lobes_as_list else name
                    raise BrdfInputError(
                        Argument("start"),
                        f": {where} = {value:g} is far beyond its plausible range"
                        f" (≤ {domain.plausible[1]:g}), where a fit cannot move; give at most {limit:g}",
                    )
    return model.unconstrained.from_params(params)


class Solved(NamedTuple):
    """What a compiled solve returns: the optimum in both forms and how the solve went."""

    theta: Any  # the unconstrained optimum
    cost: Any  # Σr² there (not ½Σr² as scipy and optimistix report it)
    n_steps: Any
    result: Any  # optimistix.RESULTS
    converged: Any  # result == RESULTS.successful, decided in the compiled solve, not by a host program
    params: Params  # the optimum as physical parameters
    rmse: Any  # sqrt(mean((f - y)²)) over the real samples, 1/sr


#: Costs of two runs within this relative difference are the same optimum reached twice, equal up to rounding.
SAME_COST = 1e-12


def best(runs: list[Solved]) -> Solved:
    """The run of lowest cost; runs within :data:`SAME_COST` of it tie, and the first (the better start) wins.

    Without the tie rule, rounding picked the winner among starts that found the same optimum, so the
    reported step count changed with how XLA happened to order a sum (the example: 4 or 7 steps).
    """
    costs = [float(run.cost) for run in runs]
    lowest = min(costs)
    return next(run for run, cost in zip(runs, costs, strict=True) if cost <= lowest + SAME_COST * abs(lowest))


def result_of(
    model: Model,
    loss: Loss,
    samples: Samples,
    solved: Solved,
    max_steps: int,
    dtype: str,
    fewer_lobes_cost: float | None = None,
    max_theta: float | None = None,
) -> FitResult:
    """The :class:`FitResult` of a solve, with its caveats (``caveats.py``); ``samples`` are those fitted, selected
    by ``max_theta``."""
    converged = bool(solved.converged)
    physical = np.asarray(model.physical.from_params(jax.tree.map(np.asarray, solved.params)))
    domains = model.physical.domains(samples.n_channels)
    inside = np.array([domain.nearest_inside(value) for value, domain in zip(physical, domains, strict=True)])
    params = model.physical.to_params(inside, samples.n_channels)
    return FitResult(
        model=model.name,
        model_options=model.model_options,
        channels=samples.channels,
        params=model.dictionary.from_params(params),
        loss=loss.name,
        cost=float(solved.cost),
        rmse=float(solved.rmse),
        n_samples=samples.n_samples,
        n_steps=int(solved.n_steps),
        converged=converged,
        message="" if converged else _failure_message(solved.result, max_steps),
        dtype=dtype,
        warnings=caveats(model, samples, params, float(solved.cost), fewer_lobes_cost),
        quantity=samples.provenance.quantity if samples.provenance else None,
        max_theta=max_theta,
    )


def _residual_shape(theta, problem: Problem):
    """The residuals' shape and dtype, which is all optimistix's interface needs of them here.

    The solver only calls ``normal_equations``; handing optimistix the real
    residual function would make it trace the model once more for nothing
    (0.13 s of the first fit of a Cook-Torrance model). Nothing differentiates
    it either: the solve's derivatives come from ``implicit.py``.
    """
    return jnp.zeros(problem.measured.shape, theta.dtype)


def _failure_message(result, max_steps: int) -> str:
    if result == optx.RESULTS.nonlinear_max_steps_reached:
        return (
            f"the maximum number of solver steps ({max_steps}) was reached before the tolerances were met;"
            " allow more steps"
        )
    return optx.RESULTS[result]


@cache
def compiled_solver(model: Model, loss: Loss, max_steps: int, dtype: str = "float64"):
    """``solve(theta0, problem) -> Solved``, compiled once per problem size.

    Differentiable with respect to ``problem`` (its measurements, sigma, weights, directions): ``theta``,
    ``params``, ``cost`` and ``rmse`` carry the derivatives of the optimum (``implicit.py``); the start
    ``theta0`` has none, the optimum does not depend on it.
    """
    ftol, gtol, atol = TOLERANCES[dtype]
    equations = partial(normal_equations, model, loss)
    solver = OnePassLevenbergMarquardt(normal_equations=equations, rtol=ftol, atol=atol, gtol=gtol)

    def gradient(theta, problem: Problem):
        return equations(theta, problem).gradient

    def squared_error(theta, problem: Problem):
        n_channels = problem.measured.shape[1]

        def error(t, chunk):
            predicted = model.brdf(model.unconstrained.to_params(t, n_channels), chunk.wi, chunk.wo)
            return jnp.where(chunk.real[:, None], predicted - chunk.measured, 0.0)

        return cost(error, theta, problem)

    @jit
    def solve(theta0, problem: Problem):
        theta0 = jnp.asarray(theta0, jnp.float64)  # the optimum is float64's whatever the start's dtype
        problem = prepared(loss, problem)
        frozen_theta0, frozen_problem = jax.lax.stop_gradient((theta0, problem))
        solution = optx.least_squares(
            _residual_shape, solver, frozen_theta0, args=frozen_problem, max_steps=max_steps, throw=False
        )
        theta = at_optimum(gradient, solution.value, problem)
        n_channels = problem.measured.shape[1]
        params = model.unconstrained.to_params(theta, n_channels)
        sum_of_squares = partial(cost, partial(residuals, model, loss))
        total = computed_as(sum_of_squares, 2.0 * solution.state.f_info.f, theta, problem)
        # rmse: sqrt(mean((f - y)²)) over the real samples, from the pass at the point returned.
        n_values = jnp.sum(problem.real) * n_channels
        rmse = jnp.sqrt(computed_as(squared_error, solution.state.squared_error, theta, problem) / n_values)
        converged = solution.result == optx.RESULTS.successful
        return Solved(theta, total, solution.stats["num_steps"], solution.result, converged, params, rmse)

    return solve
