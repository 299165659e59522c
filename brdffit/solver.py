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
* **Scaled damping.** optimistix damps with ``λ I`` (Levenberg 1944), which is
  not invariant to the scale of a parameter: a log-albedo whose albedo tends
  to 0 has a vanishing Jacobian column, gets a vanishing step and crawls for
  hundreds of steps. :class:`ScaledDampedNewtonDescent` solves
  ``(JᵀJ + λ D²) δ = -Jᵀr`` with ``D² = diag(JᵀJ)`` (Marquardt 1963).
* **MINPACK's stopping tests**, in place of optimistix's Cauchy test (every
  parameter step and every residual change below ``atol + rtol·|value|``),
  which a parameter heading to a bound never passes and which needs the
  residual vector: stop when the last accepted step lowered the sum of squares
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

from . import _jax  # noqa: F401  (float64 before any array)


class _DescentState(eqx.Module):
    gram: Any  # JᵀJ, (k, k)
    gradient: Any  # Jᵀr, (k,)


class ScaledDampedNewtonDescent(optx.AbstractDescent):
    """Damped Newton step ``δ = -(JᵀJ + λ diag(JᵀJ))⁻¹ Jᵀr`` with ``λ = initial_damping / step_size``.

    The trust region starts at step size 1; ``initial_damping = 1e-3`` makes
    the first step nearly a full Gauss-Newton step, as MINPACK's initial radius
    of 100·|Dx| does (optimistix's λ = 1 halves it, and the 3.5× growth per
    good step then costs three or four extra steps). Solved by Cholesky in the
    variables ``z = D δ``, where the matrix has a unit diagonal (Jacobi
    preconditioning of the normal equations).
    """

    initial_damping: float = 1e-3

    def init(self, y, f_info_struct):
        k = y.size
        return _DescentState(jnp.zeros((k, k), y.dtype), jnp.zeros(k, y.dtype))

    def query(self, y, f_info, state):
        return _DescentState(f_info.hessian.as_matrix(), f_info.grad)

    def step(self, step_size, state):
        gram, gradient = state.gram, state.gradient
        eps = jnp.finfo(gram.dtype).eps
        # A column that no residual sees (D = 0) is scaled as if it had the smallest nonzero norm.
        diagonal = jnp.diag(gram)
        diagonal = jnp.maximum(diagonal, eps * jnp.max(diagonal) + jnp.finfo(gram.dtype).tiny)
        scale = 1.0 / jnp.sqrt(diagonal)
        damping = self.initial_damping * jnp.where(
            step_size > eps, 1.0 / jnp.where(step_size > eps, step_size, 1.0), 1.0 / eps
        )
        # eps·I keeps the factorisation defined when J is rank-deficient.
        scaled = gram * scale[:, None] * scale[None, :] + (damping + eps) * jnp.eye(gram.shape[0], dtype=gram.dtype)
        z = jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(scaled), -gradient * scale)
        delta = z * scale
        finite = jnp.all(jnp.isfinite(delta))
        return jnp.where(finite, delta, 0.0), RESULTS.where(finite, RESULTS.successful, RESULTS.singular)


class _State(eqx.Module):
    first_step: Any
    y_eval: Any
    search_state: Any
    f_info: Any  # FunctionInfo.EvalGradHessian at the last accepted point: ½rᵀr, Jᵀr, JᵀJ
    descent_state: Any
    terminate: Any
    result: Any


def _function_info(cost, gradient, gram):
    hessian = lx.MatrixLinearOperator(gram, lx.positive_semidefinite_tag)
    return optx.FunctionInfo.EvalGradHessian(0.5 * cost, gradient, hessian)


class LevenbergMarquardt(optx.AbstractLeastSquaresSolver):
    """Levenberg-Marquardt for ``least_squares(fn, solver, y0, args)`` where ``args`` is a :class:`Problem`.

    ``normal_equations(theta, problem) -> (rᵀr, Jᵀr, JᵀJ)`` supplies the sums
    (``problem.normal_equations``); ``fn`` itself is only used by optimistix for shapes. ``rtol`` is
    MINPACK's ``ftol`` (relative reduction of the sum of squares), ``gtol`` its
    cosine test, and ``atol`` the residual norm below which the fit is exact.
    """

    normal_equations: Callable = eqx.field(static=True)
    rtol: float
    atol: float
    gtol: float
    norm: Callable = eqx.field(static=True, default=optx.max_norm)
    descent: ScaledDampedNewtonDescent = ScaledDampedNewtonDescent()
    search: optx.ClassicalTrustRegion = optx.ClassicalTrustRegion()

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        k = y.size
        f_info = _function_info(jnp.zeros((), jnp.float64), jnp.zeros(k, y.dtype), jnp.zeros((k, k), y.dtype))
        return _State(
            first_step=jnp.array(True),
            y_eval=y,
            search_state=self.search.init(y, f_info),
            f_info=f_info,
            descent_state=self.descent.init(y, f_info),
            terminate=jnp.array(False),
            result=RESULTS.successful,
        )

    def step(self, fn, y, args, options, state, tags):
        cost, gradient, gram = self.normal_equations(state.y_eval, args)
        f_eval_info = _function_info(cost, gradient, gram)
        step_size, accept, search_result, search_state = self.search.step(
            state.first_step, y, state.y_eval, state.f_info, f_eval_info, state.search_state
        )
        new_y = jnp.where(accept, state.y_eval, y)
        f_info = jax.tree.map(lambda new, old: jnp.where(accept, new, old), f_eval_info, state.f_info)
        descent_state = self.descent.query(new_y, f_info, state.descent_state)

        cost_before = 2.0 * state.f_info.f
        cost_after = 2.0 * f_info.f
        # predict_reduction is the model's change of ½rᵀr for the step just tried, gᵀδ + ½δᵀGδ.
        predicted = -2.0 * self.search.predict_reduction(state.y_eval - y, state.f_info)
        safe_before = jnp.where(cost_before > 0, cost_before, 1.0)
        actual_relative = (cost_before - cost_after) / safe_before
        predicted_relative = predicted / safe_before
        ftol = (
            accept
            & ~state.first_step
            & (jnp.abs(actual_relative) <= self.rtol)
            & (predicted_relative <= self.rtol)
            & (actual_relative <= 2.0 * predicted_relative)
        )
        # MINPACK's gtol: the largest cosine between a Jacobian column and the residual vector.
        column_norms = jnp.sqrt(jnp.diag(f_info.hessian.as_matrix()))
        cosine = jnp.abs(f_info.grad) / jnp.where(column_norms > 0, column_norms, 1.0)
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
            descent_state=descent_state,
            terminate=terminate,
            result=result,
        )
        return new_y, new_state, None

    def terminate(self, fn, y, args, options, state, tags):
        return state.terminate, state.result

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}
