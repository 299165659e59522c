"""Differentiating through a fit: the implicit function theorem at the optimum, not the solver's iterations.

The solver's inputs enter ``stop_gradient``-ed, so nothing differentiates its loop (or the stand-in
residual function optimistix is given for shapes, ``fit.py``). Instead, at the optimum ``θ*(d)`` of
``½|r(θ, d)|²`` the gradient ``g(θ, d) = Jᵀr`` vanishes, so for a change ``δd`` of the data::

    δθ* = -H⁻¹ (∂g/∂d) δd,        H = ∂g/∂θ

with ``H`` the full Hessian of ``½|r|²`` (its Gauss-Newton part plus ``Σ r ∇²r``), as optimistix's
``ImplicitAdjoint`` does for its own solvers (Blondel et al., "Efficient and modular implicit
differentiation", NeurIPS 2022). ``g`` is the one-pass normal equations' ``Jᵀr``, so the derivative costs
``k + 1`` forward passes over the data and no more memory than a fit. A parameter the data do not
determine (a singular direction of ``H``, e.g. an albedo at 0) gets no derivative: the pseudo-inverse.
Quantities computed beside the optimum (the cost, the rmse) are differentiated as the functions of
``θ`` and the data they are (:func:`computed_as`).
"""

from collections.abc import Callable
from functools import partial

import jax
import jax.numpy as jnp


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def at_optimum(gradient: Callable, theta, data):
    """``theta``, an optimum of the fit of ``data`` whose ``gradient(theta, data) = 0``, with the derivatives of
    the optimum with respect to ``data`` (the implicit function theorem)."""
    return theta


@at_optimum.defjvp
def _at_optimum_jvp(gradient, primals, tangents):
    theta, data = primals
    _, data_tangent = tangents
    hessian = jax.jacfwd(gradient)(theta, data)
    _, mixed = jax.jvp(lambda changed: gradient(theta, changed), (data,), (data_tangent,))
    return theta, -jnp.linalg.pinv(hessian, hermitian=True) @ mixed


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def computed_as(function: Callable, value, theta, data):
    """``value``, which the solver computed as ``function(theta, data)``, with that function's derivatives."""
    return value


@computed_as.defjvp
def _computed_as_jvp(function, primals, tangents):
    value, theta, data = primals
    _, theta_tangent, data_tangent = tangents
    _, tangent = jax.jvp(function, (theta, data), (theta_tangent, data_tangent))
    return value, tangent
