"""The Levenberg-Marquardt parts: the trust-region descent and step counts against MINPACK."""

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
import pytest
import scipy.optimize

import data_synth
from brdffit import fit, get_model
from brdffit.fitting.losses import get_loss
from brdffit.fitting.problem import build_problem, residuals
from brdffit.fitting.solve import MAX_COORDINATE_STEP
from brdffit.fitting.solver import ScaledTrustRegionDescent
from brdffit.fitting.starts import starting_points

LOG = get_loss("log")


def descent_state(rng, k=6, residual_scale=1e-3):
    """A random problem whose columns have very different scales. The residual is small enough that the
    Gauss-Newton step moves no coordinate by more than MAX_COORDINATE_STEP (checked in the tests)."""
    jacobian = rng.standard_normal((200, k)) * np.logspace(-3, 2, k)
    residual = residual_scale * rng.standard_normal(200)
    gram, gradient = jacobian.T @ jacobian, jacobian.T @ residual
    info = optx.FunctionInfo.EvalGradHessian(
        0.5 * residual @ residual, jnp.asarray(gradient), lx.MatrixLinearOperator(jnp.asarray(gram))
    )
    descent = ScaledTrustRegionDescent(max_coordinate_step=MAX_COORDINATE_STEP)  # the BRDF fit's descent
    return descent, descent.query(None, info, descent.init(jnp.zeros(k), info)), gram, gradient


def test_full_step_is_gauss_newton(rng):
    descent, state, gram, gradient = descent_state(rng)
    newton = -np.linalg.solve(gram, gradient)
    assert np.max(np.abs(newton)) < MAX_COORDINATE_STEP
    delta, result = descent.step(jnp.asarray(1.0), state)
    assert result == optx.RESULTS.successful
    np.testing.assert_allclose(delta, newton, rtol=1e-8)


def test_long_steps_are_shortened_along_their_direction(rng):
    """A Gauss-Newton step that would move a coordinate by more than MAX_COORDINATE_STEP is scaled down as a
    whole: same direction, largest coordinate change exactly the cap."""
    descent, state, gram, gradient = descent_state(rng, residual_scale=1.0)
    newton = -np.linalg.solve(gram, gradient)
    assert np.max(np.abs(newton)) > 10 * MAX_COORDINATE_STEP
    delta, result = descent.step(jnp.asarray(1.0), state)
    assert result == optx.RESULTS.successful
    assert np.max(np.abs(delta)) == pytest.approx(MAX_COORDINATE_STEP, rel=1e-12)
    np.testing.assert_allclose(delta, newton * MAX_COORDINATE_STEP / np.max(np.abs(newton)), rtol=1e-8)


@pytest.mark.parametrize("fraction", [0.5, 0.1, 1e-3])
def test_shorter_steps_have_the_asked_scaled_length(rng, fraction):
    """A step size s < 1 gives |D δ| = s·|D δ_GN| (bisection to 60 halvings of a 46-wide log interval: ~1e-12)."""
    descent, state, gram, gradient = descent_state(rng)
    scale = np.sqrt(np.diag(gram))
    newton = np.linalg.solve(gram, gradient)
    delta, _ = descent.step(jnp.asarray(fraction), state)
    assert np.linalg.norm(scale * np.asarray(delta)) == pytest.approx(
        fraction * np.linalg.norm(scale * newton), rel=1e-6
    )
    # and it descends: the damped step makes an acute angle with -gradient
    assert float(np.asarray(delta) @ gradient) < 0


def test_step_counts_match_minpack():
    """From the same data-driven start, brdffit's steps (rejected ones included) are comparable to scipy's lm
    (MINPACK) function evaluations, and its cost is no higher: on eight seeded random Cook-Torrance materials,
    at most 50% more steps plus two. Deterministic (seeds fixed once).

    The start is brdffit's own (the benchmarks' protocol); from an arbitrary generic start either method can
    end in a different local minimum (for example f0 saturated at 1), which says nothing about either."""
    rng = np.random.default_rng(11)
    wi, wo = data_synth.uniform_random(4000, seed=3)
    model = get_model("cook-torrance")
    for index in range(8):
        truth = {
            "kd": rng.uniform(0.01, 0.4, 3).tolist(),
            "ks": rng.uniform(0.05, 0.6, 3).tolist(),
            "m": float(np.exp(rng.uniform(np.log(0.05), np.log(0.5)))),
            "f0": float(rng.uniform(0.02, 0.9)),
        }
        samples = data_synth.synthesize("cook-torrance", truth, wi, wo, noise=0.01, seed=index)
        theta0 = starting_points(model, LOG, build_problem(samples), 1)[0]
        start = model.dictionary.from_params(model.unconstrained.to_params(jnp.asarray(theta0), 3))
        ours = fit(samples, "cook-torrance", start=start, n_starts=1)
        minpack = _minpack(model, samples, theta0)
        assert ours.converged and ours.cost <= 2 * minpack.cost * (1 + 1e-9), index
        assert ours.n_steps <= 1.5 * minpack.nfev + 2, (index, ours.n_steps, minpack.nfev)


def _minpack(model, samples, theta0):
    """scipy.optimize.least_squares (method lm: MINPACK's lmdif) on brdffit's residuals."""
    problem = build_problem(samples)
    residual = jax.jit(lambda theta: residuals(model, LOG, theta, problem)[: samples.n_samples].ravel())
    return scipy.optimize.least_squares(lambda theta: np.asarray(residual(jnp.asarray(theta))), theta0, method="lm")


@pytest.mark.parametrize("budget", [1, 2, 5, 50])
def test_a_step_budget_stops_the_solve_as_max_steps_does(budget):
    """A budget (an argument of the compiled program, which lets one program run the starts' race and the full
    solve) stops after that many steps with the result max_steps gives: the same parameters, cost, step count and
    outcome as a solve compiled with max_steps = budget; a budget the solve does not reach (50) changes nothing.
    The same steps on the same numbers; 1e-12 only allows two programs to order a sum differently."""
    from brdffit.fitting.solve import solved_from

    model = get_model("cook-torrance")
    wi, wo = data_synth.uniform_random(2000, seed=4)
    truth = {"kd": [0.2, 0.1, 0.05], "ks": [0.3, 0.3, 0.4], "m": 0.15, "f0": 0.6}
    samples = data_synth.synthesize("cook-torrance", truth, wi, wo, noise=0.01, seed=4)
    problem = build_problem(samples)
    theta0 = jnp.asarray(starting_points(model, LOG, problem, 1)[0]) + 0.3  # a start that needs > 5 steps
    capped = jax.jit(lambda t: solved_from(model, LOG, budget, "float64", t, problem))(theta0)
    budgeted = jax.jit(lambda t, b: solved_from(model, LOG, 50, "float64", t, problem, budget=b))(
        theta0, np.int32(budget)
    )
    full = jax.jit(lambda t: solved_from(model, LOG, 50, "float64", t, problem))(theta0)
    assert 5 < int(full.n_steps) < 50 and bool(full.converged)
    assert int(budgeted.n_steps) == int(capped.n_steps) == min(budget, int(full.n_steps))
    assert int(budgeted.result) == int(capped.result) and bool(budgeted.converged) is (budget == 50)
    np.testing.assert_allclose(np.asarray(budgeted.theta), np.asarray(capped.theta), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(float(budgeted.cost), float(capped.cost), rtol=1e-12)
