"""Levenberg-Marquardt as an optimistix least-squares solver, on normal equations accumulated in one pass.

optimistix builds its ``LevenbergMarquardt`` from parts: a Gauss-Newton loop
(``AbstractGaussNewton``), a damped-Newton *descent* and a classical trust
region (``ClassicalTrustRegion``). This solver runs in optimistix's
``least_squares`` loop with optimistix's trust region and result codes, and
changes the parts that cost time, memory or convergence on BRDF data; each
follows MINPACK's ``lmder`` (Moré, "The Levenberg-Marquardt algorithm:
implementation and theory", 1978):

* **Normal equations in one pass.** optimistix linearises the whole residual at
  every trial point (keeping every intermediate of the N·C-long evaluation
  alive) and materialises the Jacobian; here ``rᵀr``, ``Jᵀr`` and ``JᵀJ`` come
  from one chunked forward-mode pass (``problem.normal_equations``) and the
  trust region sees them as ``FunctionInfo.EvalGradHessian(½rᵀr, Jᵀr, JᵀJ)``,
  whose predicted reduction is exactly the Gauss-Newton model's. A step costs
  one fused Jacobian evaluation and memory does not grow with the data.
* **A trust region on the scaled step.** optimistix damps with ``λ I``
  (Levenberg 1944), which is not invariant to the scale of a parameter: a
  log-albedo whose albedo tends to 0 has a vanishing Jacobian column, gets a
  vanishing step and crawls for hundreds of steps. Here the step lives in
  Marquardt's scaled variables ``z = D δ`` (``D² = diag JᵀJ``) and its length is
  a fraction of the Gauss-Newton step (:class:`ScaledTrustRegionDescent`), so
  that a rejected step is followed by one four times shorter; with the trust
  region's thresholds set to MINPACK's (grow at ρ ≥ 0.75), step counts match
  MINPACK's (7.5 against 7.1 on 30 random Cook-Torrance materials; with ``λ``
  damping it took 8.4, and up to 35 where MINPACK took 17).
* **MINPACK's stopping tests**, in place of optimistix's Cauchy test (every
  parameter step and every residual change below ``atol + rtol·|value|``),
  which a parameter heading to a bound never passes and which needs the
  residual vector: stop when the step just tried changed the sum of squares
  by a relative ``≤ rtol`` that the linear model predicted (``ftol``); when
  every Jacobian column is orthogonal to the residuals to within ``gtol``
  (the cosine test); or when the sum of squares is below ``atol²`` (an exact fit).
"""

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from optimistix import RESULTS

#: The largest change of any unconstrained coordinate in one step (a log-albedo or log-roughness by a factor e² ≈ 7.4).
MAX_COORDINATE_STEP = 2.0


class _DescentState(eqx.Module):
    live: Any  # (k,) bool: columns of J that can change the residuals
    scale: Any  # D, (k,): the running scale on live columns, 1 on dead ones
    largest_norms: Any  # the largest sqrt(diag JᵀJ) of each column so far, (k,)
    eigenvalues: Any  # σ of D⁻¹JᵀJD⁻¹, (k,)
    eigenvectors: Any  # V, (k, k)
    projected: Any  # c = Vᵀ D⁻¹ Jᵀr, (k,)
    newton_norm: Any  # |z_GN| = |c / σ|


class ScaledTrustRegionDescent(optx.AbstractDescent):
    """Levenberg-Marquardt step in Marquardt's scaled variables with a trust radius relative to Gauss-Newton.

    In ``z = D δ`` (``D² = diag JᵀJ``, Marquardt 1963) the step is
    ``z(λ) = -(D⁻¹JᵀJD⁻¹ + λ I)⁻¹ D⁻¹Jᵀr``. A step size ``s ≥ 1`` takes the
    Gauss-Newton step ``z(0)``; ``s < 1`` takes the ``λ`` with
    ``|z(λ)| = s·|z(0)|`` (Moré 1978's trust-region form; optimistix's
    ``IndirectDampedNewtonDescent`` makes the same choice of scale), found
    from the eigen-decomposition of the k×k scaled matrix, where
    ``|z(λ)|² = Σ cᵢ² / (σᵢ + λ)²`` is monotone in ``λ``, by bisection in
    ``log λ``. So each rejection shortens the step by the trust region's
    factor, where damping ``λ I`` from a small ``λ`` barely shortens it.

    A column whose squared norm is below ``ε·max`` (an albedo that has gone to
    0 in log space) cannot change the residuals at float precision; it is left
    out of the step, whose length would otherwise be all its own and leave the
    other parameters a vanishing radius.

    Two guards against a fit that runs off into a flat region, both on by default:

    * ``running_scale``: MINPACK's scale (``lmder``, mode 1), each column's largest norm so far rather than its
      norm now, so that a column that shrinks on the way (an albedo heading to 0) keeps a step of the size it
      had instead of a step that grows as it shrinks;
    * ``max_coordinate_step``: no unconstrained coordinate moves by more than this in one step (the whole step
      is shortened along its direction). A log-albedo that Gauss-Newton would send from 0.2 to 3e-10 in one
      step, where its column vanishes and the step test freezes it, goes by a factor e² at most.

    Without them, brdffit's grid starts ended in a false optimum on 2 of 300 small Ward fits and 3 of 200
    Cook-Torrance ones (an albedo collapsed to 3e-10, a Fresnel f0 saturated at 1) that MINPACK from the same
    starts did not; with them, none. The glTF fit (``export/gltf.py``), whose logistic coordinates must
    travel far to saturate a colour at 0 or 1, turns both off.
    """

    max_coordinate_step: float | None = MAX_COORDINATE_STEP
    running_scale: bool = True

    def init(self, y, f_info_struct):
        k = y.size
        zeros = jnp.zeros(k, y.dtype)
        live = jnp.ones(k, bool)
        return _DescentState(live, zeros, zeros, zeros, jnp.zeros((k, k), y.dtype), zeros, jnp.zeros((), y.dtype))

    def query(self, y, f_info, state):
        gram, gradient = f_info.hessian.as_matrix(), f_info.grad
        tiny = jnp.finfo(gram.dtype).tiny
        eps = jnp.finfo(gram.dtype).eps
        diagonal = jnp.diag(gram)
        live = diagonal > eps * jnp.max(diagonal)
        norms = jnp.sqrt(diagonal)
        running = jnp.maximum(state.largest_norms, norms) if self.running_scale else norms
        scale = jnp.where(live, running, 1.0)
        # Dead columns become an identity block with no gradient: no step and no length there.
        live_pair = live[:, None] & live[None, :]
        scaled = jnp.where(live_pair, gram / scale[:, None] / scale[None, :], jnp.eye(gram.shape[0], dtype=gram.dtype))
        eigenvalues, eigenvectors = jnp.linalg.eigh(scaled)
        # Directions J cannot see get the curvature eps·σ_max: finite, and long enough that the radius decides.
        eigenvalues = jnp.maximum(eigenvalues, eps * jnp.max(eigenvalues) + tiny)
        projected = eigenvectors.T @ jnp.where(live, gradient / scale, 0.0)
        newton_norm = jnp.sqrt(jnp.sum((projected / eigenvalues) ** 2))
        return _DescentState(live, scale, running, eigenvalues, eigenvectors, projected, newton_norm)

    def step(self, step_size, state):
        sigma, c = state.eigenvalues, state.projected
        radius = jnp.minimum(step_size, 1.0) * state.newton_norm

        def length(log_lambda):
            return jnp.sqrt(jnp.sum((c / (sigma + jnp.exp(log_lambda))) ** 2))

        # |z(λ)| ≤ |c|/λ, so at λ_hi = |c|/radius the step is inside the radius; at λ_hi·1e-20 it is not.
        high = jnp.log(jnp.sqrt(jnp.sum(c * c)) / jnp.maximum(radius, jnp.finfo(c.dtype).tiny))
        low = high - 46.0

        def bisect(_, bounds):
            lo, hi = bounds
            middle = 0.5 * (lo + hi)
            outside = length(middle) > radius
            return jnp.where(outside, middle, lo), jnp.where(outside, hi, middle)

        _, log_lambda = jax.lax.fori_loop(0, 60, bisect, (low, high))
        damping = jnp.where(step_size >= 1.0, 0.0, jnp.exp(log_lambda))
        z = -state.eigenvectors @ (c / (sigma + damping))
        delta = jnp.where(state.live, z / state.scale, 0.0)
        if self.max_coordinate_step is not None:
            largest = jnp.max(jnp.abs(delta))
            delta = delta * jnp.minimum(1.0, self.max_coordinate_step / jnp.where(largest > 0, largest, 1.0))
        finite = jnp.all(jnp.isfinite(delta))
        return jnp.where(finite, delta, 0.0), RESULTS.where(finite, RESULTS.successful, RESULTS.singular)


class _State(eqx.Module):
    first_step: Any
    y_eval: Any
    search_state: Any
    f_info: Any  # FunctionInfo.EvalGradHessian at the last accepted point: ½rᵀr, Jᵀr, JᵀJ
    squared_error: Any  # Σ (f - y)² at the last accepted point (problem.Sums), for the result's rmse
    descent_state: Any
    terminate: Any
    result: Any
    steps: Any  # steps taken, for ``options["budget"]``


def _function_info(cost, gradient, gram):
    hessian = lx.MatrixLinearOperator(gram, lx.positive_semidefinite_tag)
    return optx.FunctionInfo.EvalGradHessian(0.5 * cost, gradient, hessian)


class OnePassLevenbergMarquardt(optx.AbstractLeastSquaresSolver):
    """Levenberg-Marquardt on normal equations, for ``least_squares(fn, solver, y0, args)`` with ``args`` a
    :class:`~brdffit.fitting.problem.Problem`.

    Not optimistix's ``LevenbergMarquardt``: its contract differs (it never evaluates ``fn``).

    ``normal_equations(theta, problem) -> problem.Sums`` supplies ``rᵀr``, ``Jᵀr``, ``JᵀJ`` and ``Σ (f - y)²``
    (``problem.normal_equations``); ``fn`` itself is only used by optimistix for shapes. The state's
    ``squared_error`` is that of the point returned. ``rtol`` is
    MINPACK's ``ftol`` (relative reduction of the sum of squares), ``gtol`` its
    cosine test, and ``atol`` the residual norm below which the fit is exact.
    """

    normal_equations: Callable = eqx.field(static=True)
    rtol: float
    atol: float
    gtol: float
    descent: ScaledTrustRegionDescent = ScaledTrustRegionDescent()
    #: MINPACK's thresholds: accept when the actual reduction is ≥ 1e-4 of the predicted one, enlarge the
    #: trust region when ≥ 0.75 (optimistix's defaults, 0.01 and 0.99, rarely enlarge it and the fit crawls).
    search: optx.ClassicalTrustRegion = optx.ClassicalTrustRegion(
        high_cutoff=0.75, low_cutoff=1e-4, high_constant=4.0, low_constant=0.25
    )

    @property
    def norm(self) -> Callable:
        """Required by optimistix's solver interface; the stopping tests here need no norm."""
        return optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        k = y.size
        f_info = _function_info(jnp.zeros((), jnp.float64), jnp.zeros(k, y.dtype), jnp.zeros((k, k), y.dtype))
        return _State(
            first_step=jnp.array(True),
            y_eval=y,
            search_state=self.search.init(y, f_info),
            f_info=f_info,
            squared_error=jnp.zeros((), jnp.float64),
            descent_state=self.descent.init(y, f_info),
            terminate=jnp.array(False),
            result=RESULTS.successful,
            steps=jnp.zeros((), jnp.int32),
        )

    def step(self, fn, y, args, options, state, tags):
        sums = self.normal_equations(state.y_eval, args)
        f_eval_info = _function_info(sums.cost, sums.gradient, sums.gram)
        step_size, accept, search_result, search_state = self.search.step(
            state.first_step, y, state.y_eval, state.f_info, f_eval_info, state.search_state
        )
        # A step size of 1 is the Gauss-Newton step; beyond it the trust region would only need extra
        # rejections to come back, so it stops there (MINPACK bounds its radius by the step taken).
        step_size = jnp.minimum(step_size, 1.0)
        search_state = eqx.tree_at(lambda s: s.step_size, search_state, step_size)
        new_y = jnp.where(accept, state.y_eval, y)
        f_info = jax.tree.map(lambda new, old: jnp.where(accept, new, old), f_eval_info, state.f_info)
        descent_state = self.descent.query(new_y, f_info, state.descent_state)

        # MINPACK's ftol, judged on the step just tried whether accepted or not (lmder does the same): at the
        # optimum a step predicted to gain ~1e-16 is rejected or accepted by rounding alone, and waiting for an
        # acceptance would shrink the region pass after pass for nothing.
        cost_before = 2.0 * state.f_info.f
        cost_tried = 2.0 * f_eval_info.f
        cost_after = 2.0 * f_info.f
        # predict_reduction is the model's change of ½rᵀr for the step just tried, gᵀδ + ½δᵀGδ.
        predicted = -2.0 * self.search.predict_reduction(state.y_eval - y, state.f_info)
        safe_before = jnp.where(cost_before > 0, cost_before, 1.0)
        actual_relative = (cost_before - cost_tried) / safe_before
        predicted_relative = predicted / safe_before
        ftol = (
            ~state.first_step
            & (jnp.abs(actual_relative) <= self.rtol)
            & (predicted_relative <= self.rtol)
            & (actual_relative <= 2.0 * predicted_relative)
        )
        # MINPACK's gtol: the largest cosine between a Jacobian column and the residual vector.
        # Columns the descent leaves out as dead (below ε·max) are left out here too.
        squared_norms = jnp.diag(f_info.hessian.as_matrix())
        live = squared_norms > jnp.finfo(squared_norms.dtype).eps * jnp.max(squared_norms)
        cosine = jnp.where(live, jnp.abs(f_info.grad) / jnp.sqrt(jnp.where(live, squared_norms, 1.0)), 0.0)
        gtol = jnp.max(cosine) <= self.gtol * jnp.sqrt(cost_after)
        exact = cost_after <= self.atol**2
        terminate = ftol | gtol | exact

        y_descent, descent_result = self.descent.step(step_size, descent_state)
        result = RESULTS.where(search_result == RESULTS.successful, descent_result, search_result)
        new_state = _State(
            first_step=jnp.array(False),
            y_eval=new_y + y_descent,
            search_state=search_state,
            f_info=f_info,
            squared_error=jnp.where(accept, sums.squared_error, state.squared_error),
            descent_state=descent_state,
            terminate=terminate,
            result=result,
            steps=state.steps + 1,
        )
        return new_y, new_state, None

    def terminate(self, fn, y, args, options, state, tags):
        """The stopping tests of :meth:`step`; with ``options={"budget": b}`` (an integer, possibly traced) also a
        stop after ``b`` steps, reported as ``max_steps`` would report it: a budget is a ``max_steps`` that a
        program takes as an argument, so that one compiled solve serves a short race and the full solve."""
        if not options or "budget" not in options:
            return state.terminate, state.result
        spent = ~state.terminate & (state.steps >= options["budget"])
        result = RESULTS.where(
            spent & (state.result == RESULTS.successful), RESULTS.nonlinear_max_steps_reached, state.result
        )
        return state.terminate | spent, result

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}
