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

A lobe with P parameters of one value per channel (``Lobe.channel_names``: a conductor's ``eta``, ``k``) is one
lobe per channel, ``lobe_k[n, c]``, so the basis is per channel, (N, C, M) with ``M = 1 + K + K·(S + P)``:
``[d, lobe_k[·, c], ∂lobe_k[·, c]/∂u_ks, ∂lobe_k[·, c]/∂u_kpc]``. Channel ``c``'s lobe depends on channel ``c``'s
parameters alone, so one forward-mode tangent per parameter, set in every channel at once, gives all channels'
derivatives: S + P tangents, as many as a lobe of shared parameters would take. A separable lobe
(``Lobe.separable``: a conductor's ``F(cos β; eta, k)`` (N, C) times ``D·G/(4 ci co)`` (N,)) takes its S tangents
through the second factor alone and its P through the first alone, not S + P through both: an anisotropic GGX
conductor's 19 steps on 155,520 pairs (an anisotropic export's refit, on its fine grid before 2026-11-28) took 2.25 s
whole, 1.16 s so (2-core x86-64).

A whole-lobe model (a renderer's own, ``LobeModel.whole``) has the same basis with no albedos in θ: its diffuse albedo
is 0 and its lobe's 1, so its diffuse and lobe rows carry nothing and its derivative rows carry 1. A lobe whose channels
depend on each other's parameters (``Lobe.channels_coupled``: principled's tints, through the colour's luminance) has
the whole Jacobian as its basis, ``basis[n, c, p] = ∂f[n, c]/∂θ_p`` (M = k, one tangent per entry of θ), with identity
coefficients.
"""

from __future__ import annotations  # Directions is a type checker's name (physics/geometry.py)

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ...physics.domains import ALBEDO
from ...physics.geometry import above_horizon
from ...physics.models.model import LobeModel
from ...physics.models.params import albedo_size, lobe_family, whole_albedos

if TYPE_CHECKING:
    from ...physics.geometry import Directions


def value_and_basis(
    model: LobeModel,
    theta: Float[Array, " k"],
    wi: Directions,
    wo: Directions,
    n_channels: int,
    dtype=None,
) -> tuple[Float[Array, "n C"], Float[Array, "n M"] | Float[Array, "n C M"]]:
    """BRDF values (N, C) and the basis (N, M) at the unconstrained ``theta``, in ``dtype`` (default: ``wi``'s); a
    basis (N, C, M) for a lobe with per-channel parameters (module docstring)."""
    dtype = dtype or wi.dtype
    if model.lobe is not None and model.lobe.channels_coupled:  # a lobe exactly when n_lobes > 0
        return _whole_jacobian(model, theta, wi, wo, n_channels, dtype)
    if model.lobe is not None and model.lobe.channel_names:
        return _per_channel_value_and_basis(model, theta, wi, wo, n_channels, dtype)
    visible, wi, wo = above_horizon(wi, wo)
    n, c = wi.shape[0], n_channels
    diffuse = ALBEDO.to_physical(theta[:c]).astype(dtype)
    diffuse_term = model.diffuse({}, wi, wo).astype(dtype)[:, None]  # (N, 1): the diffuse term of unit albedo
    values = diffuse_term * diffuse
    columns = [diffuse_term]
    if model.n_lobes:
        k = model.n_lobes
        shape_coordinates = lobe_family(model).unconstrained
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


def _whole_jacobian(model: LobeModel, theta, wi, wo, n_channels: int, dtype):
    """Values (N, C) and the whole Jacobian (N, C, k) as the basis, for a lobe whose channels are coupled."""

    def values_at(t):
        values = model.brdf(model.unconstrained.to_params(t, n_channels), wi, wo).astype(dtype)
        return values, values

    jacobian, values = jax.jacfwd(values_at, has_aux=True)(theta)
    return values, jacobian.astype(dtype)


def _per_channel_value_and_basis(model: LobeModel, theta, wi, wo, n_channels: int, dtype):
    """:func:`value_and_basis` of a lobe with per-channel parameters: the basis (N, C, M)."""
    visible, wi, wo = above_horizon(wi, wo)
    c, k = n_channels, model.n_lobes
    shared, per_channel = model.unconstrained.shared, model.unconstrained.per_channel
    assert per_channel is not None  # a lobe with per-channel parameters
    s, p = len(shared.names), len(per_channel.names)
    diffuse, specular = _albedos(model, theta, c, dtype)
    diffuse_term = model.diffuse({}, wi, wo).astype(dtype)  # (N,): the diffuse term of unit albedo
    a = albedo_size(model, c)
    u_shared = theta[a : a + k * s].reshape(k, s)
    u_channel = theta[a + k * s :].reshape(k, p, c)
    # The tangents: each shared coordinate, then each per-channel parameter in every channel at once.
    tangents = (
        jnp.concatenate([jnp.eye(s, dtype=theta.dtype), jnp.zeros((p, s), theta.dtype)]),
        jnp.concatenate(
            [jnp.zeros((s, p, c), theta.dtype), jnp.broadcast_to(jnp.eye(p, dtype=theta.dtype)[:, :, None], (p, p, c))]
        ),
    )

    cast = lambda shape: jax.tree.map(lambda x: x.astype(dtype), shape)
    family = model.lobe
    assert family is not None

    def lobe(v_shared, v_channel):
        return family(cast(shared.from_vector(v_shared) | per_channel.from_vector(v_channel)), wi, wo)  # (N, C)

    def lobe_and_derivatives(v_shared, v_channel):
        push = lambda d_shared, d_channel: jax.jvp(lobe, (v_shared, v_channel), (d_shared, d_channel))[1]
        return lobe(v_shared, v_channel), jax.vmap(push)(*tangents).astype(dtype)  # (N, C), (S + P, N, C)

    def separated_lobe_and_derivatives(v_shared, v_channel):
        # lobe = F (N, C) · U (N,), each of its own parameters: S tangents through U alone, P through F alone
        unit_of = lambda v: family.shared_factor(cast(shared.from_vector(v)), wi, wo)
        factor_of = lambda v: family.channel_factor(cast(per_channel.from_vector(v)), wi, wo)
        unit, d_unit = jax.vmap(lambda d: jax.jvp(unit_of, (v_shared,), (d,)))(tangents[0][:s])  # (S, N) each
        factor, d_factor = jax.vmap(lambda d: jax.jvp(factor_of, (v_channel,), (d,)))(tangents[1][s:])  # (P, N, C)
        unit, factor = unit[0], factor[0]
        derivatives = jnp.concatenate([factor[None] * d_unit[:, :, None], d_factor * unit[None, :, None]])
        return factor * unit[:, None], derivatives.astype(dtype)

    if family.separable:
        # A lobe at a time, the basis written column by column: XLA then fuses each product F·∂U, ∂F·U into the
        # column it writes. Batched over the lobes (a vmap, even of one) and transposed into place as below, a pass of
        # an anisotropic GGX conductor on 155,520 pairs took 61 ms, a Beckmann one 116 ms; so, 32 ms each. The
        # whole lobes' vmapped tangents (glTF's) run faster as below: 56 ms against 80 (2-core x86-64).
        lobes, derivatives = _each_lobe(separated_lobe_and_derivatives, u_shared, u_channel)
        columns = [jnp.broadcast_to(diffuse_term[:, None], lobes.shape[1:]), *lobes]
        basis = jnp.stack(columns + [derivatives[index, t] for index in range(k) for t in range(s + p)], axis=2)
    else:
        lobes, derivatives = jax.vmap(lobe_and_derivatives)(u_shared, u_channel)  # (K, N, C), (K, S + P, N, C)
        n = wi.shape[0]
        columns = [
            jnp.broadcast_to(diffuse_term[:, None, None], (n, c, 1)),
            jnp.transpose(lobes, (1, 2, 0)),
            jnp.transpose(derivatives, (2, 3, 0, 1)).reshape(n, c, k * (s + p)),
        ]
        basis = jnp.concatenate(columns, axis=2)
    values = diffuse_term[:, None] * diffuse + jnp.einsum("knc,kc->nc", lobes, specular)
    return jnp.where(visible[:, None], values, 0.0), jnp.where(visible[:, None, None], basis, 0.0)


def _each_lobe(function, *per_lobe):
    """``jax.vmap(function)(*per_lobe)`` (arguments with the lobes on axis 0) as a loop over the lobes, the results
    stacked: code XLA compiles per lobe, not for a batch of them."""
    results = [function(*(argument[lobe] for argument in per_lobe)) for lobe in range(per_lobe[0].shape[0])]
    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *results)


def _albedos(model: LobeModel, theta, c: int, dtype):
    """The diffuse (C,) and lobe (K, C) albedos at ``theta``: 0 and 1 for a whole-lobe model, which has none in θ."""
    k = model.n_lobes
    if model.whole:  # one lobe (LobeModel.whole)
        return whole_albedos(c, jnp, dtype)
    diffuse = ALBEDO.to_physical(theta[:c]).astype(dtype)
    return diffuse, ALBEDO.to_physical(theta[c : (1 + k) * c].reshape(k, c)).astype(dtype)


def jacobian_coefficients(model: LobeModel, theta: Float[Array, " k"], n_channels: int) -> Float[Array, "C M k"]:
    """``A`` (C, M, k) with ``∂f[n, c]/∂θ = Σ_m basis[n, m] · A[c, m]`` (see :func:`value_and_basis`; ``basis[n, c,
    m]`` for a lobe with per-channel parameters).

    Row 0 (the diffuse basis) carries ``d rho_d/du``; the lobe rows carry ``d rho_s/du``; the
    shape-derivative rows carry the specular albedos.
    """
    c, k = n_channels, model.n_lobes
    if model.lobe is not None and model.lobe.channels_coupled:  # the basis is the Jacobian itself
        return jnp.broadcast_to(jnp.eye(theta.shape[0], dtype=theta.dtype), (c, theta.shape[0], theta.shape[0]))
    if model.lobe is not None and model.lobe.channel_names:
        return _per_channel_coefficients(model, theta, c)
    eye_c = jnp.eye(c, dtype=theta.dtype)
    _, diffuse_slope = jax.jvp(ALBEDO.to_physical, (theta[:c],), (jnp.ones(c, theta.dtype),))
    if not k:
        return (eye_c * diffuse_slope)[:, None, :]
    s = len(lobe_family(model).unconstrained.names)
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


def _per_channel_coefficients(model: LobeModel, theta, n_channels: int):
    """:func:`jacobian_coefficients` for the per-channel basis: a derivative row ``(k, t)`` of channel ``c`` carries
    ``specular[k, c]`` at the entry of θ it differentiates: shared coordinate ``t`` of lobe ``k``, or per-channel
    parameter ``t - S`` of lobe ``k`` in channel ``c``."""
    c, k = n_channels, model.n_lobes
    shared, per_channel = model.unconstrained.shared, model.unconstrained.per_channel
    assert per_channel is not None  # a lobe with per-channel parameters
    s, p = len(shared.names), len(per_channel.names)
    size, a = model.unconstrained.size(c), albedo_size(model, c)
    channel = np.arange(c)
    lobe, tangent = np.meshgrid(np.arange(k), np.arange(s + p), indexing="ij")  # (K, S + P)
    shared_entry = a + lobe * s + tangent  # (K, S + P); used where tangent < s
    channel_entry = a + k * s + (lobe * p + tangent - s)[..., None] * c + channel  # (K, S + P, C)
    entry = np.where((tangent < s)[..., None], shared_entry[..., None], channel_entry)  # (K, S + P, C)
    rows = 1 + k + lobe * (s + p) + tangent  # (K, S + P)
    coefficients = jnp.zeros((c, 1 + k + k * (s + p), size), theta.dtype)
    if model.whole:  # no albedos: the derivative rows carry the lobe's albedo, 1
        specular = jnp.ones((k, c), theta.dtype)
    else:
        _, diffuse_slope = jax.jvp(ALBEDO.to_physical, (theta[:c],), (jnp.ones(c, theta.dtype),))
        u_specular = theta[c : (1 + k) * c].reshape(k, c)
        specular, specular_slope = jax.jvp(ALBEDO.to_physical, (u_specular,), (jnp.ones_like(u_specular),))
        coefficients = coefficients.at[channel, 0, channel].set(diffuse_slope)
        lobe_rows = np.broadcast_to(1 + np.arange(k)[:, None], (k, c))
        coefficients = coefficients.at[channel[None, :], lobe_rows, c + np.arange(k)[:, None] * c + channel].set(
            specular_slope
        )
    on_channel = np.broadcast_to(channel, entry.shape)
    return coefficients.at[on_channel, np.broadcast_to(rows[..., None], entry.shape), entry].set(
        jnp.broadcast_to(specular[:, None, :], entry.shape)
    )
