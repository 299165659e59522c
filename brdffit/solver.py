"""Levenberg-Marquardt assembled from optimistix's parts, with Marquardt scaling and MINPACK's ftol test.

optimistix builds its ``LevenbergMarquardt`` from a Gauss-Newton loop
(``AbstractGaussNewton``), a damped-Newton *descent* and a classical trust
region (``ClassicalTrustRegion``). This module keeps the loop and the trust
region and changes two things, both as in MINPACK's ``lmder`` (Moré, "The
Levenberg-Marquardt algorithm: implementation and theory", 1978):

* **Scaled damping.** optimistix damps with ``λ I`` (Levenberg 1944), which is not
  invariant to the scale of a parameter: a parameter whose Jacobian column is
  small (a log-albedo whose albedo tends to 0) gets a tiny step and crawls for
  hundreds of steps. :class:`ScaledDampedNewtonDescent` solves
  ``(JᵀJ + λ D²) δ = -Jᵀr`` with ``D² = diag(JᵀJ)`` (Marquardt 1963), on the
  k×k normal equations (k is at most a few tens), Jacobi-preconditioned so the
  Cholesky factorisation sees a unit diagonal.
* **Relative-reduction stop.** optimistix stops on a Cauchy test (every step
  component and every residual change below ``atol + rtol·|value|``), which a
  parameter running to the boundary of its domain never passes. MINPACK also
  stops when the last accepted step lowered the sum of squares by a relative
  ``actred ≤ ftol`` that the linear model predicted (``prered ≤ ftol``,
  ``actred ≤ 2·prered``): no step can still lower the cost by more than ``ftol``.
* **Zero-residual stop.** When the data are fitted exactly at the boundary (all
  values 0, say) the cost falls by a constant fraction per step towards 0 and no
  relative test fires; the solver also stops once the sum of squares is below
  ``atol²``, the residuals being at rounding level.
"""

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx


class _DescentState(eqx.Module):
    gram: Any  # JᵀJ, (k, k)
    gradient: Any  # Jᵀr, (k,)


class ScaledDampedNewtonDescent(optx.AbstractDescent):
    """Damped Newton step ``δ = -(JᵀJ + λ diag(JᵀJ))⁻¹ Jᵀr`` with ``λ = 1/step_size``."""

    def init(self, y, f_info_struct):
        k = y.size
        return _DescentState(jnp.zeros((k, k), y.dtype), jnp.zeros(k, y.dtype))

    def query(self, y, f_info, state):
        jacobian = f_info.jac.as_matrix()
        residual = jnp.ravel(f_info.residual)
        return _DescentState(jacobian.T @ jacobian, jacobian.T @ residual)

    def step(self, step_size, state):
        gram, gradient = state.gram, state.gradient
        eps = jnp.finfo(gram.dtype).eps
        # A column that no residual sees (D = 0) is scaled as if it had the smallest nonzero norm.
        diagonal = jnp.diag(gram)
        diagonal = jnp.maximum(diagonal, eps * jnp.max(diagonal) + jnp.finfo(gram.dtype).tiny)
        scale = 1.0 / jnp.sqrt(diagonal)
        damping = jnp.where(step_size > eps, 1.0 / jnp.where(step_size > eps, step_size, 1.0), 1.0 / eps)
        # In the variables z = D δ the matrix has a unit diagonal; eps·I keeps a rank-deficient J factorisable.
        scaled = gram * scale[:, None] * scale[None, :] + (damping + eps) * jnp.eye(gram.shape[0], dtype=gram.dtype)
        factor = jax.scipy.linalg.cho_factor(scaled)
        z = jax.scipy.linalg.cho_solve(factor, -gradient * scale)
        delta = z * scale
        result = optx.RESULTS.where(jnp.all(jnp.isfinite(delta)), optx.RESULTS.successful, optx.RESULTS.singular)
        return jnp.where(jnp.isfinite(delta), delta, 0.0), result


class LevenbergMarquardt(optx.AbstractGaussNewton):
    """Levenberg-Marquardt: optimistix's Gauss-Newton loop and trust region, a Marquardt-scaled descent, MINPACK's ftol.

    ``rtol``, ``atol``: optimistix's Cauchy termination; ``ftol``: MINPACK's relative-reduction test.
    """

    rtol: float
    atol: float
    ftol: float
    norm: Callable = optx.max_norm
    descent: ScaledDampedNewtonDescent = ScaledDampedNewtonDescent()
    search: optx.ClassicalTrustRegion = optx.ClassicalTrustRegion()
    verbose: Callable = eqx.field(static=True, default=lambda **kwargs: None)

    def step(self, fn, y, args, options, state, tags):
        new_y, new_state, aux = super().step(fn, y, args, options, state, tags)
        accepted = (new_state.num_accepted_steps > state.num_accepted_steps) & ~state.first_step
        cost_before = jnp.sum(jnp.square(state.f_info.residual))
        cost_after = jnp.sum(jnp.square(new_state.f_info.residual))
        # The step just tried went from the last accepted point y to state.y_eval;
        # predict_reduction returns ½(|r + Jδ|² - |r|²), negative for a decrease.
        predicted = -2.0 * self.search.predict_reduction(state.y_eval - y, state.f_info)
        safe_before = jnp.where(cost_before > 0, cost_before, 1.0)
        actual_relative = (cost_before - cost_after) / safe_before
        predicted_relative = predicted / safe_before
        small = (
            accepted
            & (jnp.abs(actual_relative) <= self.ftol)
            & (predicted_relative <= self.ftol)
            & (actual_relative <= 2.0 * predicted_relative)
        )
        exact = accepted & (cost_after <= self.atol**2)
        new_state = eqx.tree_at(lambda s: s.terminate, new_state, new_state.terminate | small | exact)
        return new_y, new_state, aux
