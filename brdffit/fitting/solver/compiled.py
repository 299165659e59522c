"""One Levenberg-Marquardt solve of one problem from one start, as a compiled program, and the best of several.

The parameters move in unconstrained coordinates (``Model.unconstrained``), so every step is physically
valid. The solver (``levenberg_marquardt.py``) is compiled once per model, loss and bucketed data size
(``problem.padded_size``) and reused for every start and every dataset of that size.

The compiled solve is differentiable with respect to the data: its derivatives are those of the optimum,
never of the solver's iterations. optimistix's ``ImplicitAdjoint`` (``levenberg_marquardt.ADJOINT``) gives them, by the
implicit function theorem on the fit's optimality condition ``∇½|r|² = 0`` differentiated through the fit's
residuals (:func:`fit_residuals`); the start carries none, the optimum does not depend on it. The cost and
the rmse come from the solver's last pass and are differentiated as the functions of the optimum and the data
they are (:func:`computed_as`).
"""

from collections.abc import Callable
from functools import partial
from typing import Any, NamedTuple

import numpy as np

from ..._jax import jax, jnp
from ..._programs import built_once, jit
from ...physics.models.model import LobeModel
from ...physics.models.params import Params
from ..objective.losses import Loss
from ..objective.problem import Problem, Sums, chunks, cost, normal_equations, prepared, residuals
from .hold import Hold, prior_cost, slopes, theta_of, z_of

#: Stopping tolerances (``levenberg_marquardt.py``) per dtype: MINPACK's ftol (relative cost reduction), gtol (largest
#: cosine between a Jacobian column and the residuals) and the residual norm of an exact fit. In float64, ftol 1e-10
#: leaves each parameter within ~sqrt(1e-10·N) standard errors of the optimum (0.002 σ for 10⁴ samples × 3 channels,
#: 0.02 σ at MERL's 4.4·10⁶) and gtol 1e-8 within ~1e-8·sqrt(N) σ. A float32 model makes residuals that differ by 1%
#: carry ~1e-4 relative rounding error, so its cost jitters at ~1e-5 and only loose tests can pass; the float32 stage
#: merely has to land near the optimum, which float64 then refines.
TOLERANCES = {"float64": (1e-10, 1e-8, 1e-8), "float32": (1e-5, 1e-4, 1e-5)}

#: The largest change of any unconstrained coordinate in one step: a log-albedo or log-roughness by a factor e² ≈ 7.4.
MAX_COORDINATE_STEP = 2.0


def fit_descent():
    """The descent of the BRDF fits (``levenberg_marquardt.ScaledTrustRegionDescent``): MINPACK's, with columns below
    ``ε`` of the largest left out (an albedo at 0 in log space, a lobe switched off) and at most
    :data:`MAX_COORDINATE_STEP` per coordinate per step. A log-albedo that Gauss-Newton would send from 0.2 to 3e-10 in
    one step, where its column vanishes and the step test freezes it, goes by e² at most (the descent's docstring says
    what these guards changed on brdffit's starts)."""
    from .levenberg_marquardt import ScaledTrustRegionDescent

    return ScaledTrustRegionDescent(drop_negligible_columns=True, max_coordinate_step=MAX_COORDINATE_STEP)


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
#: stored by ``brdffit/_programs/stored.py`` returns arrays, and reading the message back needs no optimistix).
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
def compiled_solver(model: LobeModel, loss: Loss, max_steps: int, dtype: str = "float64"):
    """``solve(theta0, problem, hold=None) -> Solved`` (:func:`solved_from`), compiled once per problem size and
    once for fits that hold parameters (``hold.py``): the held values and bounds are data, so changing them
    compiles nothing.

    Differentiable with respect to ``problem`` (its measurements, sigma, weights, directions) and the hold's
    values: ``theta``, ``params``, ``cost`` and ``rmse`` carry the derivatives of the optimum (the module
    docstring); the start ``theta0`` has none, the optimum does not depend on it.
    """
    return jit(partial(solved_from, model, loss, max_steps, dtype))  # named by its bound arguments' cache keys


def solved_from(
    model: LobeModel,
    loss: Loss,
    max_steps: int,
    dtype: str,
    theta0,
    problem: Problem,
    hold: Hold | None = None,
    budget=None,
) -> Solved:
    """The Levenberg-Marquardt solve (``levenberg_marquardt.py``) of ``problem`` from ``theta0`` (JAX, to be traced), of
    at most ``max_steps`` steps, or ``budget`` (an integer array ≤ ``max_steps``: an argument of the program, not a
    constant of it) when given.

    The solver sees the fit's residuals (:func:`fit_residuals`) and takes each step from the one-pass normal
    equations (``problem.normal_equations``), which give the same sums without forming the Jacobian. With a
    ``hold`` it moves the coordinates ``z`` of ``hold.py`` (fixed entries stay at their values, bounded ones
    inside their ranges), and ``theta0`` is first moved onto what the hold allows."""
    import optimistix as optx

    from .levenberg_marquardt import least_squares

    ftol, gtol, atol = TOLERANCES[dtype]
    problem = prepared(loss, problem)
    residual_fn = partial(fit_residuals, model, loss)
    equations = partial(normal_equations, model, loss)
    data: Problem | tuple[Problem, Hold]
    if hold is None:
        data = problem
        start = jnp.asarray(theta0, jnp.float64)  # the optimum is float64's whatever the start's dtype
    else:
        hold = jax.tree.map(lambda leaf: jnp.asarray(leaf, jnp.float64), hold)
        residual_fn, equations = partial(_held_residuals, residual_fn), partial(_held_equations, equations)
        data = (problem, hold)
        start = z_of(jnp.asarray(theta0, jnp.float64), hold)
    solution = least_squares(
        residual_fn,
        start,
        data,
        rtol=ftol,
        atol=atol,
        gtol=gtol,
        max_steps=max_steps,
        has_aux=True,
        normal_equations=equations,
        budget=budget,
        descent=fit_descent(),
    )
    theta = solution.value if hold is None else theta_of(solution.value, hold)
    n_channels = problem.measured.shape[1]
    params = model.unconstrained.to_params(theta, n_channels)
    sum_of_squares = partial(cost, partial(residuals, model, loss))
    # The data's rᵀr: the solver's last pass less the prior's part (hold.py), which the reported cost leaves out.
    total = computed_as(sum_of_squares, 2.0 * solution.state.f_info.f - prior_cost(theta, hold), theta, problem)
    # rmse: sqrt(mean((f - y)²)) over the real samples, from the pass at the point returned (the residuals' aux).
    n_values = jnp.sum(problem.real) * n_channels
    squared_error = partial(cost, partial(_brdf_error, model))
    rmse = jnp.sqrt(computed_as(squared_error, solution.aux, theta, problem) / n_values)
    converged = solution.result == optx.RESULTS.successful
    return Solved(theta, total, solution.stats["num_steps"], outcome_of(solution.result), converged, params, rmse)


def fit_residuals(model: LobeModel, loss: Loss, theta, problem: Problem):
    """The fit's residual function as the solver sees it: the residuals (N, C) of ``problem.residuals`` at
    ``theta`` and, as their aux, ``Σ (f - y)²`` over the real samples (float64, the rmse's numerator), computed
    chunk by chunk (``problem.chunks``).

    The solver never evaluates it (``problem.normal_equations`` gives its sums in one pass); optimistix traces it
    for its shape and differentiates it for the derivatives of the optimum. Each chunk is recomputed on the way
    back (``jax.checkpoint``), so that those derivatives hold one chunk's intermediates at a time, as the
    normal equations do, rather than the whole problem's.
    """

    def chunk_residuals(total, chunk):
        error = _brdf_error(model, theta, chunk).astype(jnp.float64)
        return total + jnp.sum(error * error), residuals(model, loss, theta, chunk)

    total, r = jax.lax.scan(jax.checkpoint(chunk_residuals), jnp.zeros((), jnp.float64), chunks(problem))
    return r.reshape(problem.measured.shape[0], -1), total


def _brdf_error(model: LobeModel, theta, problem: Problem):
    """``f - y`` (N, C) at ``theta``, 0 on padding, 1/sr, computed in the problem's dtype as the residuals are."""
    params = model.unconstrained.to_params(theta, problem.measured.shape[1])
    params = jax.tree.map(lambda leaf: leaf.astype(problem.wi.dtype), params)
    predicted = model.brdf(params, problem.wi, problem.wo)
    return jnp.where(problem.real[:, None], predicted - problem.measured, 0.0)


def _held_residuals(residual_fn, z, data):
    """``residual_fn`` in the coordinates ``z`` of a hold, with the prior's residuals ``√w·(θ − mean)`` beside the
    data's where the hold has one (``hold.py``)."""
    problem, hold = data
    theta = theta_of(z, hold)
    residuals, aux = residual_fn(theta, problem)
    if hold.prior_weight is None:
        return residuals, aux
    weight = hold.prior_weight
    root = jnp.where(weight > 0, jnp.sqrt(jnp.where(weight > 0, weight, 1.0)), 0.0)  # √0's slope would be inf
    return (residuals, root * (theta - hold.prior_mean)), aux


def _held_equations(equations, z, data) -> Sums:
    """The normal equations in the coordinates ``z`` of a hold: those of ``θ`` (with the prior's rows, where the
    hold has one: ``w·d²``, ``w·d`` and ``diag(w)`` added, ``d = θ − mean``) by the chain rule, ``θ`` mapping
    elementwise (``Jz = Jθ · diag(dθ/dz)``); a fixed entry's row and column are 0."""
    problem, hold = data
    theta = theta_of(z, hold)
    sums = equations(theta, problem)
    if hold.prior_weight is not None:
        weight = hold.prior_weight
        sums = sums._replace(
            cost=sums.cost + prior_cost(theta, hold),
            gradient=sums.gradient + weight * (theta - hold.prior_mean),
            gram=sums.gram + jnp.diag(weight),
        )
    slope = slopes(z, hold)
    return sums._replace(gradient=slope * sums.gradient, gram=slope[:, None] * sums.gram * slope[None, :])


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def computed_as(function: Callable, value, theta, data):
    """``value``, which the solver computed as ``function(theta, data)``, with that function's derivatives (with
    respect to ``theta`` and ``data``): the cost and the rmse come from the solver's last pass, not from a
    separate evaluation, and differentiate as what they are."""
    return value


@computed_as.defjvp
def _computed_as_jvp(function, primals, tangents):
    value, theta, data = primals
    _, theta_tangent, data_tangent = tangents
    _, tangent = jax.jvp(function, (theta, data), (theta_tangent, data_tangent))
    return value, tangent


def outcome_of(result):
    """The index into :data:`OUTCOMES` of optimistix's ``result`` (JAX), ``len(OUTCOMES)`` for one it does not
    list."""
    known = [(index, item) for index, item in enumerate(map(_result_item, OUTCOMES)) if item is not None]
    return jnp.select([result == item for _, item in known], [index for index, _ in known], len(OUTCOMES))


def _result_item(name: str):
    """optimistix's ``RESULTS.<name>``, or None where this optimistix has none (``nonfinite`` came in 0.1.0)."""
    import optimistix as optx

    try:
        return getattr(optx.RESULTS, name)
    except (AttributeError, KeyError):  # its enumeration's lookup raises KeyError
        return None


def failure_message(outcome: int, max_steps: int) -> str:
    """Why a solve that ended with ``outcome`` (an index into :data:`OUTCOMES`) did not converge."""
    if outcome >= len(OUTCOMES):
        return "the solver stopped for a reason brdffit does not know (optimistix's result is new)"
    name = OUTCOMES[outcome]
    if name == "nonlinear_max_steps_reached":
        return (
            f"the maximum number of solver steps ({max_steps}) was reached before the tolerances were met;"
            " allow more steps"
        )
    import optimistix as optx  # 0.3 s to import: a fit that runs stored programs needs it for this message alone

    return optx.RESULTS[getattr(optx.RESULTS, name)]  # type: ignore[misc]  # equinox's Enumeration is indexable
