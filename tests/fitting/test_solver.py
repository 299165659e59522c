"""The Levenberg-Marquardt parts: the trust-region descent and step counts against MINPACK."""

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
import pytest
import scipy.optimize

from brdffit import data_synth, fit, get_model
from brdffit.data.samples import Samples
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.objective.problem import build_problem, residuals
from brdffit.fitting.solver.compiled import MAX_COORDINATE_STEP, fit_descent
from brdffit.fitting.starts.grid import starting_points

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
    descent = fit_descent()
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


@pytest.mark.slow
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


@pytest.mark.slow
@pytest.mark.parametrize("budget", [1, 2, 5, 50])
def test_a_step_budget_stops_the_solve_as_max_steps_does(budget):
    """A budget (an argument of the compiled program, which lets one program run the starts' race and the full
    solve) stops after that many steps with the result max_steps gives: the same parameters, cost, step count and
    outcome as a solve compiled with max_steps = budget; a budget the solve does not reach (50) changes nothing.
    The same steps on the same numbers; 1e-12 only allows two programs to order a sum differently."""
    from brdffit.fitting.solver.compiled import solved_from

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


# ---------------------------------------------------------------------------------------------- the contract
def test_the_one_pass_normal_equations_are_those_of_the_residuals_the_solver_is_given():
    """The fit hands optimistix its true residuals (``fit_residuals``) and takes each step from the one-pass sums
    (``problem.normal_equations``): both must be the same function's. Checked against ``rᵀr``, ``Jᵀr``, ``JᵀJ``
    of the residuals' own forward-mode Jacobian (``solver.normal_equations_of``), with sigma and weights and
    padding, free and with a hold (a fixed entry, a bounded one). The residuals are the problem's; the sums agree
    to 1e-12 relative (the same 4,000 × 3 terms summed in another order and grouping: ~1e-14)."""
    from brdffit.fitting.objective.problem import normal_equations, prepared
    from brdffit.fitting.solver.compiled import _held_equations, _held_residuals, fit_residuals
    from brdffit.fitting.solver.hold import Hold, z_of
    from brdffit.fitting.solver.levenberg_marquardt import normal_equations_of

    model = get_model("cook-torrance", fresnel="schlick")
    wi, wo = data_synth.uniform_random(4000, seed=5)
    truth = {"kd": [0.2, 0.1, 0.05], "ks": [0.3, 0.3, 0.4], "m": 0.15, "f0": 0.6}
    synthetic = data_synth.synthesize("cook-torrance", truth, wi, wo, noise=0.02, seed=5, with_sigma=True)
    weight = np.random.default_rng(5).uniform(0.5, 2.0, synthetic.n_samples)
    samples = Samples.from_arrays(wi, wo, synthetic.values, synthetic.channels, synthetic.sigma, weight)
    problem = prepared(LOG, build_problem(samples))
    assert problem.wi.shape[0] > samples.n_samples  # padded
    theta = model.unconstrained.from_params(model.dictionary.to_params(truth)) + 0.1
    k = theta.size
    hold = Hold(
        free=np.r_[np.ones(k - 2), 0.0, 1.0],
        bounded=np.r_[np.zeros(k - 1), 1.0],
        value=np.r_[np.zeros(k - 2), theta[-2], 0.0],
        low=np.r_[np.zeros(k - 1), theta[-1] - 1.0],
        high=np.r_[np.zeros(k - 1), theta[-1] + 2.0],
    )
    residual_fn = lambda t, p: fit_residuals(model, LOG, t, p)
    equations = lambda t, p: normal_equations(model, LOG, t, p)
    r, squared_error = residual_fn(jnp.asarray(theta), problem)
    # The same arithmetic compiled per chunk: T(f) and T(y) may round differently, by a few ε of them (|T| = |log f|
    # is below 10 here), before each sample's residual scale (1/(σ T'), up to ~10⁸ where a value is near 0) multiplies
    # their difference, a few % of them (the noise): ~1e-14 of a typical residual, and up to 16 ε · 10 · scale where
    # the noise makes a residual near 0 (9e-13 seen with the lowest versions allowed, where rtol 1e-12 alone failed).
    expected = np.asarray(residuals(model, LOG, jnp.asarray(theta), problem))
    bound = 1e-12 * np.abs(expected) + 16 * np.finfo(float).eps * 10.0 * np.asarray(problem.scale)
    assert np.all(np.abs(np.asarray(r) - expected) <= bound)
    cases = [
        (residual_fn, equations, jnp.asarray(theta), problem),
        (
            lambda z, data: _held_residuals(residual_fn, z, data),
            lambda z, data: _held_equations(equations, z, data),
            z_of(jnp.asarray(theta), hold),
            (problem, hold),
        ),
    ]
    for fn, one_pass, y, args in cases:
        expected = normal_equations_of(jax.jit(fn), y, args)
        sums = jax.jit(one_pass)(y, args)
        for name, ours, theirs in zip(("rᵀr", "Jᵀr", "JᵀJ", "Σ(f−y)²"), sums, expected, strict=True):
            np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12 * np.max(np.abs(theirs)), err_msg=name)
    assert float(squared_error) == pytest.approx(float(expected[3]), rel=1e-12)


def _quadratic_info(rng, k=3):
    """½|r|² of a random linear residual and its exact quadratic model: actual reduction = predicted reduction."""
    jacobian = rng.standard_normal((20, k))
    residual = rng.standard_normal(20)
    gram, gradient = jacobian.T @ jacobian, jacobian.T @ residual
    info = optx.FunctionInfo.EvalGradHessian(
        0.5 * residual @ residual, jnp.asarray(gradient), lx.MatrixLinearOperator(jnp.asarray(gram))
    )
    return info, gram, gradient


@pytest.mark.parametrize("ratio", [1.0, 0.8, 0.7, 0.5, 1e-3, 1.1e-4, 0.9e-4, -1.0])
@pytest.mark.parametrize("step_size", [1.0, 0.25, 2.0**-10])
def test_the_trust_region_decides_as_optimistix_classical_one_and_stops_at_gauss_newton(rng, ratio, step_size):
    """CappedTrustRegion takes optimistix's ClassicalTrustRegion's decisions with MINPACK's thresholds (accept at
    ρ ≥ 1e-4, ×4 at ρ > 0.75, ×0.25 on rejection), the same arithmetic, and never a step size above 1 (the Gauss-Newton
    step): the actual reduction of each case is ``ratio`` times the predicted one."""
    from brdffit.fitting.solver.levenberg_marquardt import CappedTrustRegion

    info, gram, gradient = _quadratic_info(rng)
    y = jnp.zeros(3)
    y_eval = jnp.asarray(-0.1 * np.linalg.solve(gram, gradient))
    delta = np.asarray(y_eval)
    predicted = delta @ gradient + 0.5 * delta @ gram @ delta
    tried = optx.FunctionInfo.EvalGradHessian(info.f + ratio * predicted, info.grad, info.hessian)
    ours = CappedTrustRegion()
    theirs = optx.ClassicalTrustRegion(high_cutoff=0.75, low_cutoff=1e-4, high_constant=4.0, low_constant=0.25)
    first = jnp.array(False)
    mine = ours.step(first, y, y_eval, info, tried, _state_at(ours, y, info, step_size))
    their_size, their_accept, _, _ = theirs.step(first, y, y_eval, info, tried, _state_at(theirs, y, info, step_size))
    assert bool(mine[1]) is bool(their_accept) is (ratio >= 1e-4)
    assert float(mine[0]) == min(float(their_size), 1.0)
    assert float(mine[0]) == min(step_size * (4.0 if ratio > 0.75 else 1.0 if ratio >= 1e-4 else 0.25), 1.0)
    assert float(ours.predict_reduction(y_eval - y, info)) == float(theirs.predict_reduction(y_eval - y, info))


def _state_at(search, y, info, step_size):
    """A trust region's state at ``step_size``, built through its public ``init`` and the pytree it is (one leaf)."""
    state = search.init(y, info)
    return jax.tree.unflatten(jax.tree.structure(state), [jnp.asarray(step_size)])


# ------------------------------------------------------------------------- MINPACK's radius (the generic solver's)
def _linear_problem(rng, k=3):
    """A random linear residual ``r + J δ`` with columns of different scales: its Jacobian, residual and
    ``FunctionInfo`` at ``δ = 0``."""
    jacobian = rng.standard_normal((20, k)) * np.logspace(-2, 1, k)
    residual = rng.standard_normal(20)
    info = optx.FunctionInfo.EvalGradHessian(
        0.5 * residual @ residual,
        jnp.asarray(jacobian.T @ residual),
        lx.MatrixLinearOperator(jnp.asarray(jacobian.T @ jacobian)),
    )
    return jacobian, residual, info


def _levenberg_marquardt_step(jacobian, residual, scale, par):
    """``p = −(JᵀJ + par D²)⁻¹ Jᵀr``, by numpy."""
    gram = jacobian.T @ jacobian
    return -np.linalg.solve(gram + par * np.diag(scale**2), jacobian.T @ residual)


@pytest.mark.parametrize("fraction", [2.0, 1.0 + 1e-9, 0.5, 0.1, 1e-3])
def test_an_absolute_radius_is_the_scaled_length_of_the_step(rng, fraction):
    """MINPACK's descent takes ``Δ`` as a length in the scaled variables: Gauss-Newton's step when ``|D p| ≤ Δ``,
    else the Levenberg-Marquardt step with ``|D p| = Δ`` (bisection to 60 halvings of a 46-wide log interval:
    ~1e-12; rel 1e-6), which numpy's solve with the same ``λ`` found by root-finding reproduces."""
    from brdffit.fitting.solver.levenberg_marquardt import MINPACK_DESCENT

    jacobian, residual, info = _linear_problem(rng)
    scale = np.linalg.norm(jacobian, axis=0)  # MINPACK's D at a first point
    newton = _levenberg_marquardt_step(jacobian, residual, scale, 0.0)
    radius = fraction * np.linalg.norm(scale * newton)
    state = MINPACK_DESCENT.query(None, info, MINPACK_DESCENT.init(jnp.zeros(3), info))
    delta, result = MINPACK_DESCENT.step(jnp.asarray(radius), state)
    assert result == optx.RESULTS.successful
    if fraction >= 1.0:
        np.testing.assert_allclose(delta, newton, rtol=1e-8)
        return
    par = scipy.optimize.brentq(
        lambda p: np.linalg.norm(scale * _levenberg_marquardt_step(jacobian, residual, scale, p)) - radius, 0.0, 1e12
    )
    np.testing.assert_allclose(delta, _levenberg_marquardt_step(jacobian, residual, scale, par), rtol=1e-6)
    assert np.linalg.norm(scale * np.asarray(delta)) == pytest.approx(radius, rel=1e-6)


def _lmder_radius(jacobian, residual, scale, step, par, cost_tried, radius, first):
    """MINPACK's ``lmder`` after trying ``step`` (its Fortran, statements 230 to 260, transcribed in its own
    variables): whether the step is accepted and the new ``delta``."""
    fnorm, fnorm1 = np.linalg.norm(residual), np.sqrt(2.0 * cost_tried)
    pnorm = np.linalg.norm(scale * step)
    if first:
        radius = min(radius, pnorm)
    actred = 1.0 - (fnorm1 / fnorm) ** 2 if 0.1 * fnorm1 < fnorm else -1.0
    temp1 = np.linalg.norm(jacobian @ step) / fnorm
    temp2 = np.sqrt(par) * pnorm / fnorm
    prered = temp1**2 + temp2**2 / 0.5
    dirder = -(temp1**2 + temp2**2)
    ratio = actred / prered if prered != 0 else 0.0
    if ratio <= 0.25:
        temp = 0.5 if actred >= 0 else 0.5 * dirder / (dirder + 0.5 * actred)
        if 0.1 * fnorm1 >= fnorm or temp < 0.1:
            temp = 0.1
        radius = temp * min(radius, pnorm / 0.1)
    elif par == 0 or ratio >= 0.75:
        radius = pnorm / 0.5
    return bool(ratio >= 1e-4), float(radius)


@pytest.mark.parametrize("first", [False, True])
@pytest.mark.parametrize("bound", [True, False], ids=["radius-binds", "gauss-newton"])
@pytest.mark.parametrize("ratio", [1.0, 0.8, 0.6, 0.3, 0.1, 1e-3, 0.5e-4, -0.5, -3.0, "tenfold"])
def test_the_minpack_radius_is_updated_as_lmder_updates_delta(rng, first, bound, ratio):
    """MinpackTrustRegion accepts and sets ``Δ`` as ``lmder`` does (:func:`_lmder_radius`, in MINPACK's own
    variables ``fnorm``, ``prered``, ``dirder``, ``par``): for a step the radius bound (``par > 0``) and a
    Gauss-Newton step inside it (``par = 0``), on MINPACK's first iteration (``Δ`` clipped to the step's length)
    and later ones, for ratios in each of its bands and a residual grown tenfold. The ratios stay clear of the
    band edges, where rounding may decide; the two computations of the same ``Δ`` agree to 1e-10 (``prered``
    formed as ``|Jp|² + 2 par |Dp|²`` against ``gᵀp + ½ pᵀJᵀJp``, and ``par`` found by root-finding to 1e-12)."""
    from brdffit.fitting.solver.levenberg_marquardt import MinpackTrustRegion

    jacobian, residual, info = _linear_problem(rng)
    scale = np.linalg.norm(jacobian, axis=0)
    newton = _levenberg_marquardt_step(jacobian, residual, scale, 0.0)
    newton_length = np.linalg.norm(scale * newton)
    if bound:
        radius = 0.3 * newton_length
        par = scipy.optimize.brentq(
            lambda p: np.linalg.norm(scale * _levenberg_marquardt_step(jacobian, residual, scale, p)) - radius,
            0.0,
            1e12,
            xtol=1e-300,
            rtol=1e-14,
        )
        step = _levenberg_marquardt_step(jacobian, residual, scale, par)
    else:
        radius, par, step = 3.0 * newton_length, 0.0, newton
    predicted = step @ (jacobian.T @ residual) + 0.5 * step @ jacobian.T @ jacobian @ step
    cost = 0.5 * residual @ residual
    cost_tried = 150.0 * cost if ratio == "tenfold" else cost + ratio * predicted
    tried = optx.FunctionInfo.EvalGradHessian(jnp.asarray(cost_tried), info.grad, info.hessian)

    search = MinpackTrustRegion()
    y = jnp.zeros(3)
    state = search.init(y, info)
    state = jax.tree.unflatten(
        jax.tree.structure(state),
        [jnp.asarray(radius), jnp.asarray(scale), jnp.asarray(scale), jnp.asarray(not first)],
    )
    new_radius, accept, _, _ = search.step(jnp.array(False), y, jnp.asarray(step), info, tried, state)
    expected_accept, expected_radius = _lmder_radius(jacobian, residual, scale, step, par, cost_tried, radius, first)
    assert bool(accept) is expected_accept
    assert float(new_radius) == pytest.approx(expected_radius, rel=1e-10)


def test_the_minpack_radius_starts_at_factor_times_the_scaled_start():
    """``Δ₀ = factor·|D y0|`` with MINPACK's ``D`` (the column norms, 1 for a zero column), ``factor`` where
    ``D y0 = 0`` (``lmder``, statements 40 to 80): exact arithmetic on small integers."""
    from brdffit.fitting.solver.levenberg_marquardt import MinpackTrustRegion

    jacobian = np.array([[3.0, 0.0, 0.0], [4.0, 2.0, 0.0]])  # column norms 5, 2 and 0
    info = optx.FunctionInfo.EvalGradHessian(
        jnp.asarray(1.0), jnp.zeros(3), lx.MatrixLinearOperator(jnp.asarray(jacobian.T @ jacobian))
    )
    search = MinpackTrustRegion(factor=2.0)
    for y0, expected in ((np.array([1.0, 6.0, 7.0]), 2.0 * np.sqrt(5.0**2 + 12.0**2 + 7.0**2)), (np.zeros(3), 2.0)):
        y = jnp.asarray(y0)
        radius, accept, _, _ = search.step(jnp.array(True), y, y, info, info, search.init(y, info))
        assert bool(accept)
        assert float(radius) == pytest.approx(expected, rel=1e-15)


def test_a_residual_that_is_not_finite_is_rejected_and_shrinks_the_radius_tenfold(rng):
    """A trial whose ``|r|²`` is NaN (a model evaluated at a pole) is rejected and ``Δ ← min(Δ, 10|Dp|)/10``, as
    for a residual grown tenfold, where MINPACK's comparisons with NaN would be undefined."""
    from brdffit.fitting.solver.levenberg_marquardt import MinpackTrustRegion

    jacobian, residual, info = _linear_problem(rng)
    scale = np.linalg.norm(jacobian, axis=0)
    step = 0.1 * _levenberg_marquardt_step(jacobian, residual, scale, 0.0)
    search = MinpackTrustRegion()
    y = jnp.zeros(3)
    state = jax.tree.unflatten(
        jax.tree.structure(search.init(y, info)), [jnp.asarray(1e3), jnp.asarray(scale), jnp.asarray(scale), True]
    )
    tried = optx.FunctionInfo.EvalGradHessian(jnp.asarray(np.nan), info.grad, info.hessian)
    radius, accept, _, _ = search.step(jnp.array(False), y, jnp.asarray(step), info, tried, state)
    assert not bool(accept)
    assert float(radius) == pytest.approx(np.linalg.norm(scale * step), rel=1e-12)


def test_a_descent_and_a_search_that_disagree_on_the_radius_are_refused():
    """The step size means a fraction of Gauss-Newton's step to one pair and a scaled length to the other: a
    solver mixing them is refused, and so is MINPACK's radius with a scale that is not MINPACK's."""
    from brdffit.fitting.solver.levenberg_marquardt import (
        CappedTrustRegion,
        MinpackTrustRegion,
        ScaledLevenbergMarquardt,
        ScaledTrustRegionDescent,
    )

    tolerances = {"rtol": 1e-10, "atol": 0.0, "gtol": 1e-8}
    ScaledLevenbergMarquardt(**tolerances)  # the defaults agree
    ScaledLevenbergMarquardt(**tolerances, descent=ScaledTrustRegionDescent(), search=CappedTrustRegion())
    for descent, search in (
        (ScaledTrustRegionDescent(), MinpackTrustRegion()),
        (ScaledTrustRegionDescent(absolute_radius=True), CappedTrustRegion()),
        (ScaledTrustRegionDescent(absolute_radius=True, running_scale=False), MinpackTrustRegion()),
    ):
        with pytest.raises(ValueError, match=r"radius|running_scale"):
            ScaledLevenbergMarquardt(**tolerances, descent=descent, search=search)
