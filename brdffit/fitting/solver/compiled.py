"""One Levenberg-Marquardt solve of one problem from one start, as a compiled program, and the best of several.

The parameters move in unconstrained coordinates (``Model.unconstrained``), so every step is physically
valid. The solver (``solver.py``) is compiled once per model, loss and bucketed data size
(``problem.padded_size``) and reused for every start and every dataset of that size.

The compiled solve is differentiable with respect to the data: its derivatives are those of the optimum
(the implicit function theorem, ``implicit.py``), never of the solver's iterations.
"""

from functools import partial
from typing import Any, NamedTuple

import numpy as np

from ..._jax import jax, jnp
from ..._programs import built_once, jit
from ...physics.models.model import Model
from ...physics.models.params import Params
from ..objective.losses import Loss
from ..objective.problem import Problem, Sums, cost, normal_equations, prepared, residuals
from .hold import Hold, slopes, theta_of, z_of
from .implicit import at_optimum, computed_as

#: Stopping tolerances (``solver.py``) per dtype: MINPACK's ftol (relative cost reduction), gtol (largest cosine
#: between a Jacobian column and the residuals) and the residual norm of an exact fit. In float64, ftol 1e-10
#: leaves each parameter within ~sqrt(1e-10·N) standard errors of the optimum (0.002 σ for 10⁴ samples × 3
#: channels, 0.02 σ at MERL's 4.4·10⁶) and gtol 1e-8 within ~1e-8·sqrt(N) σ. A float32 model makes residuals
#: that differ by 1% carry ~1e-4 relative rounding error, so its cost jitters at ~1e-5 and only loose tests can
#: pass; the float32 stage merely has to land near the optimum, which float64 then refines.
TOLERANCES = {"float64": (1e-10, 1e-8, 1e-8), "float32": (1e-5, 1e-4, 1e-5)}


class Solved(NamedTuple):
    """What a compiled solve returns: the optimum in both forms and how the solve went."""

    theta: Any  # the unconstrained optimum
    cost: Any  # Σr² there (not ½Σr² as scipy and optimistix report it)
    n_steps: Any
    result: Any  # how the solve ended: an index into OUTCOMES
    converged: Any  # result == RESULTS.successful, decided in the compiled solve, not by a host program
    params: Params  # the optimum as physical parameters
    rmse: Any  # sqrt(mean((f - y)²)) over the real samples, 1/sr


#: How a solve ends, by the names of optimistix's ``RESULTS``; a compiled solve returns the index (a program
#: stored by ``_programs.py`` returns arrays, and reading the message back needs no optimistix).
OUTCOMES = (
    "successful",
    "nonlinear_max_steps_reached",
    "nonlinear_divergence",
    "nonfinite",
    "singular",
    "max_steps_reached",
    "breakdown",
    "stagnation",
    "conlim",
    "nonfinite_input",
)

#: Costs of two runs within this relative difference are the same optimum reached twice, equal up to rounding.
SAME_COST = 1e-12


def best_index(costs) -> np.ndarray:
    """Index of the run of lowest cost along the last axis of ``costs``; runs within :data:`SAME_COST` of it tie,
    and the first (the better start) wins.

    Without the tie rule, rounding picked the winner among starts that found the same optimum, so the
    reported step count changed with how XLA happened to order a sum (the example: 4 or 7 steps).
    """
    costs = np.asarray(costs, float)
    lowest = np.min(costs, axis=-1, keepdims=True)
    return np.argmax(costs <= lowest + SAME_COST * np.abs(lowest), axis=-1)


def best(runs: list[Solved]) -> Solved:
    """The run of lowest cost (:func:`best_index`)."""
    return runs[int(best_index([float(run.cost) for run in runs]))]


@built_once
def compiled_solver(model: Model, loss: Loss, max_steps: int, dtype: str = "float64"):
    """``solve(theta0, problem, hold=None) -> Solved`` (:func:`solved_from`), compiled once per problem size and
    once for fits that hold parameters (``hold.py``): the held values and bounds are data, so changing them
    compiles nothing.

    Differentiable with respect to ``problem`` (its measurements, sigma, weights, directions) and the hold's
    values: ``theta``, ``params``, ``cost`` and ``rmse`` carry the derivatives of the optimum (``implicit.py``);
    the start ``theta0`` has none, the optimum does not depend on it.
    """
    return jit(
        partial(solved_from, model, loss, max_steps, dtype),
        name=f"fitting.solve.solved_from[{model!r}, {loss!r}, {max_steps}, {dtype!r}]",
    )


def solved_from(
    model: Model,
    loss: Loss,
    max_steps: int,
    dtype: str,
    theta0,
    problem: Problem,
    hold: Hold | None = None,
    budget=None,
) -> Solved:
    """The Levenberg-Marquardt solve (``solver.py``) of ``problem`` from ``theta0`` (JAX, to be traced), of at
    most ``max_steps`` steps, or ``budget`` (an integer array ≤ ``max_steps``: an argument of the program, not a
    constant of it) when given.

    With a ``hold`` the solver moves the coordinates ``z`` of ``hold.py`` (fixed entries stay at their values,
    bounded ones inside their ranges), and ``theta0`` is first moved onto what the hold allows."""
    import optimistix as optx

    from .levenberg_marquardt import OnePassLevenbergMarquardt

    ftol, gtol, atol = TOLERANCES[dtype]
    if hold is None:
        equations = partial(normal_equations, model, loss)
        to_theta = lambda y, data: y
        start = jnp.asarray(theta0, jnp.float64)  # the optimum is float64's whatever the start's dtype
    else:
        equations = partial(_held_equations, partial(normal_equations, model, loss))
        to_theta = lambda y, data: theta_of(y, data[1])
        hold = jax.tree.map(lambda leaf: jnp.asarray(leaf, jnp.float64), hold)
        start = z_of(jnp.asarray(theta0, jnp.float64), hold)
    solver = OnePassLevenbergMarquardt(normal_equations=equations, rtol=ftol, atol=atol, gtol=gtol)

    def gradient(y, data):
        return equations(y, data).gradient

    def squared_error(theta, problem: Problem):
        n_channels = problem.measured.shape[1]

        def error(t, chunk):
            predicted = model.brdf(model.unconstrained.to_params(t, n_channels), chunk.wi, chunk.wo)
            return jnp.where(chunk.real[:, None], predicted - chunk.measured, 0.0)

        return cost(error, theta, problem)

    problem = prepared(loss, problem)
    data = problem if hold is None else (problem, hold)
    frozen_start, frozen_data = jax.lax.stop_gradient((start, data))
    solution = optx.least_squares(
        _residual_shape,
        solver,
        frozen_start,
        args=frozen_data,
        options=None if budget is None else {"budget": budget},
        max_steps=max_steps,
        throw=False,
    )
    theta = to_theta(at_optimum(gradient, solution.value, data), data)
    n_channels = problem.measured.shape[1]
    params = model.unconstrained.to_params(theta, n_channels)
    sum_of_squares = partial(cost, partial(residuals, model, loss))
    total = computed_as(sum_of_squares, 2.0 * solution.state.f_info.f, theta, problem)
    # rmse: sqrt(mean((f - y)²)) over the real samples, from the pass at the point returned.
    n_values = jnp.sum(problem.real) * n_channels
    rmse = jnp.sqrt(computed_as(squared_error, solution.state.squared_error, theta, problem) / n_values)
    ended = [solution.result == getattr(optx.RESULTS, name) for name in OUTCOMES]
    outcome = jnp.select(ended, list(range(len(OUTCOMES))), len(OUTCOMES))
    converged = solution.result == optx.RESULTS.successful
    return Solved(theta, total, solution.stats["num_steps"], outcome, converged, params, rmse)


def _held_equations(equations, z, data) -> Sums:
    """The normal equations in the coordinates ``z`` of a hold: those of ``θ`` by the chain rule, ``θ`` mapping
    elementwise (``Jz = Jθ · diag(dθ/dz)``); a fixed entry's row and column are 0."""
    problem, hold = data
    sums = equations(theta_of(z, hold), problem)
    slope = slopes(z, hold)
    return sums._replace(gradient=slope * sums.gradient, gram=slope[:, None] * sums.gram * slope[None, :])


def _residual_shape(theta, data):
    """The residuals' shape and dtype, which is all optimistix's interface needs of them here.

    The solver only calls ``normal_equations``; handing optimistix the real
    residual function would make it trace the model once more for nothing
    (0.13 s of the first fit of a Cook-Torrance model). Nothing differentiates
    it either: the solve's derivatives come from ``implicit.py``.
    """
    problem = data if isinstance(data, Problem) else data[0]
    return jnp.zeros(problem.measured.shape, theta.dtype)


def failure_message(outcome: int, max_steps: int) -> str:
    """Why a solve that ended with ``outcome`` (an index into :data:`OUTCOMES`) did not converge."""
    import optimistix as optx

    if outcome >= len(OUTCOMES):
        return "the solver stopped for a reason brdffit does not know (optimistix's result is new)"
    name = OUTCOMES[outcome]
    if name == "nonlinear_max_steps_reached":
        return (
            f"the maximum number of solver steps ({max_steps}) was reached before the tolerances were met;"
            " allow more steps"
        )
    return optx.RESULTS[getattr(optx.RESULTS, name)]
