"""Differentiating a fit with respect to its data: the implicit function theorem against finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from catalogue import CASES

from brdffit import data_synth, get_model
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.objective.problem import build_problem, cost, normal_equations, prepared, residuals
from brdffit.fitting.options import MAX_STEPS
from brdffit.fitting.solver.compiled import compiled_solver

pytestmark = pytest.mark.slow  # refits under perturbed data, to finite-difference the optimum: ~70 s

MODEL, OPTIONS, PARAMS = CASES[1]  # Ward, pickled oak (Ngan et al. 2005)


@pytest.fixture(scope="module")
def setting():
    wi, wo = data_synth.uniform_random(600, seed=11)
    samples = data_synth.synthesize(MODEL, PARAMS, wi, wo, noise=0.02, seed=12, **OPTIONS)
    model, loss = get_model(MODEL, **OPTIONS), get_loss("log")
    problem = build_problem(samples)
    theta0 = model.unconstrained.from_params(model.dictionary.to_params(PARAMS)) + 0.05
    return model, loss, problem, jnp.asarray(theta0)


def polished(model, loss, problem, theta):
    """The optimum to machine precision: Newton steps on the exact gradient of ½|r|² from the solver's answer
    (the solver stops at ftol 1e-10, which would leave finite differences of 1e-4 with 1e-3 relative error)."""
    gradient = lambda t: normal_equations(model, loss, t, prepared(loss, problem)).gradient
    for _ in range(4):
        theta = theta - jnp.linalg.solve(jax.jacfwd(gradient)(theta), gradient(theta))
    return theta


def test_optimum_derivatives_match_finite_differences_of_refits(setting):
    model, loss, problem, theta0 = setting
    solve = compiled_solver(model, loss, MAX_STEPS)
    theta_of = lambda measured: solve(theta0, problem._replace(measured=measured)).theta
    direction = jnp.asarray(np.random.default_rng(13).standard_normal(problem.measured.shape)) * problem.measured
    step = 1e-4
    refit = lambda measured: polished(model, loss, problem._replace(measured=measured), theta_of(measured))
    numeric = (refit(problem.measured + step * direction) - refit(problem.measured - step * direction)) / (2 * step)
    _, forward = jax.jvp(theta_of, (problem.measured,), (direction,))
    # Central differences err by O(step²) relative (1e-8 here) plus rounding of 1e-16/step: 1e-6 is ample.
    np.testing.assert_allclose(forward, numeric, rtol=1e-6, atol=1e-9 * float(jnp.max(jnp.abs(numeric))))
    # Reverse mode transposes the same linear map.
    _, pullback = jax.vjp(theta_of, problem.measured)
    cotangent = jnp.arange(1.0, forward.size + 1.0)
    (reverse,) = pullback(cotangent)
    np.testing.assert_allclose(jnp.sum(reverse * direction), cotangent @ forward, rtol=1e-10)


def test_the_start_has_no_derivative_and_the_cost_and_rmse_have_theirs(setting):
    model, loss, problem, theta0 = setting
    solve = compiled_solver(model, loss, MAX_STEPS)
    assert np.all(jax.grad(lambda t: solve(t, problem).theta[-1])(theta0) == 0)  # the optimum ignores the start
    measured = problem.measured
    direction = jnp.asarray(np.random.default_rng(14).standard_normal(measured.shape)) * measured
    # The rmse is a root of squared residuals that are only 2% of the values: its central difference errs by
    # ~(step/0.02)², so the step is 1e-6 (2.5e-9 relative; rounding: 1e-16 · rmse / step, negligible).
    step = 1e-6

    def reference(values):  # cost and rmse at the polished optimum, computed afresh
        changed = problem._replace(measured=values)
        theta = polished(model, loss, changed, solve(theta0, changed).theta)
        total = cost(lambda t, chunk: residuals(model, loss, t, prepared(loss, chunk)), theta, changed)
        predicted = model.brdf(model.unconstrained.to_params(theta, 3), changed.wi, changed.wo)
        error = jnp.where(changed.real[:, None], predicted - values, 0.0)
        return jnp.stack([total, jnp.sqrt(jnp.sum(error**2) / (jnp.sum(changed.real) * 3))])

    numeric = (reference(measured + step * direction) - reference(measured - step * direction)) / (2 * step)
    solved = lambda values: (lambda s: jnp.stack([s.cost, s.rmse]))(solve(theta0, problem._replace(measured=values)))
    _, forward = jax.jvp(solved, (measured,), (direction,))
    np.testing.assert_allclose(forward, numeric, rtol=1e-6)
