"""The derivatives of a model in the solver's coordinates, factored as a per-sample basis times coefficients.

A lobe model is linear in its albedos (``physics/models/model.py``)::

    f[n, c] = diffuse[c] · d[n] + Σ_k specular[k, c] · lobe_k[n]

with ``d`` the diffuse term of unit albedo (Lambert's ``1/π``), so the derivative of every channel with respect to
every unconstrained parameter ``θ`` (``ln`` of the albedos, the lobes' shape coordinates) is a combination of
``M = 1 + K + K·S`` functions per sample, the *basis* ``[d, lobe_k, ∂lobe_k/∂u_ks]``, with coefficients that do not
depend on the sample::

    ∂f[n, c]/∂θ_p = Σ_m basis[n, m] · A[c, m, p]

Only the S shape coordinates of each lobe are differentiated (forward mode), once per sample, not per
channel; the one-pass normal equations (``problem.normal_equations``) accumulate over the basis and never
form the (N·C × k) Jacobian.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ...physics.domains import ALBEDO
from ...physics.geometry import above_horizon
from ...physics.models.model import LobeModel


def value_and_basis(
    model: LobeModel,
    theta: Float[Array, " k"],
    wi: Float[Array, "n 3"],
    wo: Float[Array, "n 3"],
    n_channels: int,
    dtype=None,
) -> tuple[Float[Array, "n C"], Float[Array, "n M"]]:
    """BRDF values (N, C) and the basis (N, M) at the unconstrained ``theta``, in ``dtype`` (default: ``wi``'s)."""
    dtype = dtype or wi.dtype
    visible, wi, wo = above_horizon(wi, wo)
    n, c = wi.shape[0], n_channels
    diffuse = ALBEDO.to_physical(theta[:c]).astype(dtype)
    diffuse_term = model.diffuse({}, wi, wo).astype(dtype)[:, None]  # (N, 1): the diffuse term of unit albedo
    values = diffuse_term * diffuse
    columns = [diffuse_term]
    if model.n_lobes:
        k = model.n_lobes
        shape_coordinates = model.lobe.unconstrained
        s = len(shape_coordinates.names)
        specular = ALBEDO.to_physical(theta[c : (1 + k) * c].reshape(k, c)).astype(dtype)

        def lobe_and_derivatives(u):
            def lobe(v):
                shape = jax.tree.map(lambda x: x.astype(dtype), shape_coordinates.from_vector(v))
                value = model.lobe(shape, wi, wo)
                return value, value

            derivatives, value = jax.jacfwd(lobe, has_aux=True)(u)
            return value, derivatives.astype(dtype)

        lobes, lobe_derivatives = jax.vmap(lobe_and_derivatives)(theta[(1 + k) * c :].reshape(k, s))
        values = values + lobes.T @ specular
        columns += [lobes.T, jnp.transpose(lobe_derivatives, (1, 0, 2)).reshape(n, k * s)]
    basis = jnp.concatenate(columns, axis=1)
    return jnp.where(visible[:, None], values, 0.0), jnp.where(visible[:, None], basis, 0.0)


def jacobian_coefficients(model: LobeModel, theta: Float[Array, " k"], n_channels: int) -> Float[Array, "C M k"]:
    """``A`` (C, M, k) with ``∂f[n, c]/∂θ = Σ_m basis[n, m] · A[c, m]`` (see :func:`value_and_basis`).

    Row 0 (the diffuse basis) carries ``d rho_d/du``; the lobe rows carry ``d rho_s/du``; the
    shape-derivative rows carry the specular albedos.
    """
    c, k = n_channels, model.n_lobes
    eye_c = jnp.eye(c, dtype=theta.dtype)
    _, diffuse_slope = jax.jvp(ALBEDO.to_physical, (theta[:c],), (jnp.ones(c, theta.dtype),))
    if not k:
        return (eye_c * diffuse_slope)[:, None, :]
    s = len(model.lobe.unconstrained.names)
    u_specular = theta[c : (1 + k) * c].reshape(k, c)
    specular, specular_slope = jax.jvp(ALBEDO.to_physical, (u_specular,), (jnp.ones_like(u_specular),))
    eye_k, eye_s = jnp.eye(k, dtype=theta.dtype), jnp.eye(s, dtype=theta.dtype)
    diffuse_rows = (eye_c * diffuse_slope)[:, None, :]
    lobe_rows = specular_slope.T[:, :, None, None] * eye_k[None, :, :, None] * eye_c[:, None, None, :]
    shape_rows = specular.T[:, :, None, None, None] * eye_k[None, :, None, :, None] * eye_s[None, None, :, None, :]
    zeros = lambda rows, cols: jnp.zeros((c, rows, cols), theta.dtype)
    return jnp.concatenate(
        [
            jnp.concatenate([diffuse_rows, zeros(1, k * c), zeros(1, k * s)], axis=2),
            jnp.concatenate([zeros(k, c), lobe_rows.reshape(c, k, k * c), zeros(k, k * s)], axis=2),
            jnp.concatenate([zeros(k * s, c), zeros(k * s, k * c), shape_rows.reshape(c, k * s, k * s)], axis=2),
        ],
        axis=1,
    )
