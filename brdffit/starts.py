"""Data-driven starting points for the fit, by variable projection over a grid of lobe shapes.

Every model is linear in its albedos (``models/base.py``). For a fixed lobe
shape, the albedos that minimise the loss *linearised about the data*,
``Σ w (f - y)²`` with ``w = (scale · T'(y))²`` (``losses.linearised_weight``), are
a small non-negative least-squares problem per channel (Golub & Pereyra 1973,
variable projection; Lawson & Hanson's NNLS via ``scipy.optimize.nnls``). Each
shape of the lobe family's coarse grid gets its best albedos, is scored by the
true loss, and the best few become the Levenberg-Marquardt starts. Models with
several lobes (Lafortune) add their lobes greedily, one at a time.
"""

from dataclasses import replace
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from .losses import Loss, linearised_weight
from .models import Model, Params
from .problem import Problem, residuals

#: No albedo starts more than this factor below the largest one of its solution (the fit moves log-albedos).
ALBEDO_FLOOR = 1e-3


def starting_points(model: Model, loss: Loss, problem: Problem, n_starts: int) -> list[np.ndarray]:
    """Up to ``n_starts`` unconstrained start vectors, best first."""
    measured = np.asarray(problem.measured)
    weight = linearised_weight(loss, measured, np.asarray(problem.wi[:, 2]), np.asarray(problem.scale))
    n_channels = measured.shape[1]
    if not model.n_lobes:
        diffuse = _albedos(np.full((1, measured.shape[0]), 1.0 / np.pi), measured, weight)[0]
        return [model.to_unconstrained(Params(_floored(diffuse), np.zeros((0, n_channels)), {}))]

    chosen: list[dict[str, float]] = []  # shapes of the lobes already placed
    chosen_values: list[np.ndarray] = []
    for placed in range(model.n_lobes):
        partial_model = replace(model, n_lobes=placed + 1)
        scored = []
        for shape in model.lobe.grid:
            lobe = np.asarray(
                _lobe_values(model.lobe, {k: jnp.asarray(v) for k, v in shape.items()}, problem.wi, problem.wo)
            )
            basis = np.vstack([np.full_like(lobe, 1.0 / np.pi), *chosen_values, lobe])
            albedos = _floored(_albedos(basis, measured, weight))
            shapes = [*chosen, shape]
            params = Params(
                albedos[0], albedos[1:], {name: np.array([s[name] for s in shapes]) for name in model.lobe.names}
            )
            theta = partial_model.to_unconstrained(params)
            scored.append((float(_cost(partial_model, loss, jnp.asarray(theta), problem)), theta, shape, lobe))
        scored.sort(key=lambda item: item[0])
        chosen.append(scored[0][2])
        chosen_values.append(scored[0][3])
    return [theta for _, theta, _, _ in scored[:n_starts]]


def _albedos(basis: np.ndarray, measured: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Non-negative albedos (B, C) minimising ``Σ_n w[n,c] (Σ_b x[b,c] basis[b,n] - y[n,c])²`` per channel.

    Solved on the B×B normal equations through their Cholesky factor ``R``:
    ``|R x - R⁻ᵀ Bᵀ W y|²`` equals the weighted sum of squares up to a constant.
    """
    n_basis, n_channels = basis.shape[0], measured.shape[1]
    albedos = np.zeros((n_basis, n_channels))
    for channel in range(n_channels):
        weighted = basis * weight[:, channel]
        gram = weighted @ basis.T
        rhs = weighted @ measured[:, channel]
        # A lobe that no sample sees has a zero row; a relative ridge keeps the factor defined.
        gram = gram + 1e-12 * np.trace(gram) * np.eye(n_basis) + np.finfo(float).tiny * np.eye(n_basis)
        upper = np.linalg.cholesky(gram).T
        albedos[:, channel], _ = scipy.optimize.nnls(upper, np.linalg.solve(upper.T, rhs))
    return albedos


def _floored(albedos: np.ndarray) -> np.ndarray:
    return np.maximum(albedos, ALBEDO_FLOOR * max(float(np.max(albedos)), 1e-6))


@partial(jax.jit, static_argnums=0)
def _lobe_values(lobe, shape, wi, wo):
    return lobe(shape, wi, wo)


@partial(jax.jit, static_argnums=(0, 1))
def _cost(model: Model, loss: Loss, theta, problem: Problem):
    return jnp.sum(residuals(model, loss, theta, problem) ** 2)
