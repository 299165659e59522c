"""Fit a model to samples: Levenberg-Marquardt (optimistix) from data-driven starts.

The parameters move in unconstrained coordinates (``domains.py``), so every
step is physically valid; the solver is ``optimistix.LevenbergMarquardt``
(Moré 1978's trust-region form), jit-compiled once per model, loss and data
shape and reused for every start and every dataset of that shape.
"""

from functools import cache
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from ._checks import whole_number
from .errors import BrdfInputError
from .losses import Loss, get_loss
from .models import Model, get_model
from .problem import Problem, build_problem, residuals
from .results import FitResult
from .samples import Samples
from .solver import LevenbergMarquardt
from .starts import starting_points

#: Relative and absolute tolerances of the solver's Cauchy termination (``optimistix.cauchy_termination``):
#: it stops when both the step and the change of every residual are below ``atol + rtol·|value|``.
RTOL = 1e-8
ATOL = 1e-8
#: MINPACK's ``ftol`` (``solver.py``): it also stops when a step lowers the cost by a relative 1e-10 or less and
#: the linear model predicts no more. At the optimum of N residuals, that leaves each parameter within
#: ~sqrt(1e-10·N) standard errors of it: 0.002 σ for 10⁴ samples × 3 channels.
FTOL = 1e-10
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
    **model_options: Any,
) -> FitResult:
    """Fit ``model`` to ``samples`` by minimising ``loss`` (SPEC section 3).

    ``max_theta``: drop samples with θi or θo above this many degrees.
    ``start``: parameters (SPEC section 5 dictionary) to start from instead of
    the data-driven starts. ``n_starts``: how many of the best grid starts to
    run Levenberg-Marquardt from; the lowest cost wins. ``model_options``:
    ``fresnel=`` for cook-torrance, ``lobes=`` for lafortune.
    """
    model = get_model(model, **model_options)
    loss = get_loss(loss)
    if not isinstance(samples, Samples):
        raise BrdfInputError(f"fit takes Samples (from brdffit.load_samples), got {type(samples).__name__}")
    n_starts = whole_number("--starts", n_starts)
    max_steps = whole_number("--max-steps", max_steps)
    samples = samples.within(max_theta)
    n_parameters = model.n_parameters(samples.n_channels)
    if samples.values.size < n_parameters:
        raise BrdfInputError(
            f"{samples.source}: {samples.n_samples} sample(s) × {samples.n_channels} channel(s) cannot determine"
            f" the {n_parameters} parameters of {model.name}; give at least {n_parameters} values"
        )
    problem = build_problem(loss, samples)
    if start is not None:
        params = model.params_from_dict(start)
        if params.diffuse.size != samples.n_channels:
            raise BrdfInputError(
                f"start parameters have {params.diffuse.size} channel(s) but the samples have {samples.n_channels}"
            )
        starts = [model.to_unconstrained(params)]
    else:
        starts = starting_points(model, loss, problem, n_starts)

    solve = _compiled_solver(model, loss, max_steps)
    runs = [solve(jnp.asarray(theta), problem) for theta in starts]
    theta, cost, n_steps, result = min(runs, key=lambda run: float(run[1]))
    params = model.from_unconstrained(theta, samples.n_channels)
    predicted = np.asarray(model.evaluate(params, problem.wi, problem.wo))
    converged = bool(result == optx.RESULTS.successful)
    return FitResult(
        model=model.name,
        model_options=model.model_options,
        channels=samples.channels,
        params=model.params_to_dict(jax.tree.map(np.asarray, params)),
        loss=loss.name,
        cost=float(cost),
        rmse=float(np.sqrt(np.mean((predicted - samples.values) ** 2))),
        n_samples=samples.n_samples,
        n_steps=int(n_steps),
        converged=converged,
        message="" if converged else _failure_message(result, max_steps),
    )


def _failure_message(result, max_steps: int) -> str:
    if result == optx.RESULTS.nonlinear_max_steps_reached:
        return (
            f"the maximum number of solver steps ({max_steps}) was reached before the tolerances were met;"
            " raise --max-steps"
        )
    return optx.RESULTS[result]


@cache
def _compiled_solver(model: Model, loss: Loss, max_steps: int):
    """``solve(theta0, problem) -> (theta, cost, n_steps, result)``, compiled once per data shape."""
    solver = LevenbergMarquardt(rtol=RTOL, atol=ATOL, ftol=FTOL)

    def residual_vector(theta, problem: Problem):
        return residuals(model, loss, theta, problem)

    @jax.jit
    def solve(theta0, problem: Problem):
        solution = optx.least_squares(residual_vector, solver, theta0, args=problem, max_steps=max_steps, throw=False)
        cost = jnp.sum(residual_vector(solution.value, problem) ** 2)
        return solution.value, cost, solution.stats["num_steps"], solution.result

    return solve
