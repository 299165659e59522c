"""Data-driven starting points for the fit, by variable projection over a grid of lobe shapes.

Every model is linear in its albedos (``physics/models/model.py``). For a fixed lobe
shape, the albedos that minimise the loss *linearised about the data*,
``Σ w (f - y)²`` with ``w = (scale · T'(y))²`` (``losses.linearised_weight``), are
a small non-negative least-squares problem per channel (Golub & Pereyra 1973,
variable projection; Lawson & Hanson's NNLS via ``scipy.optimize.nnls``). Every
shape of the lobe family's coarse grid gets its best albedos and is scored by
the true loss, all shapes at once; the best few become the Levenberg-Marquardt
starts. Models with several lobes (Lafortune) place their lobes one at a time
(:class:`LobeSearch`; ``lobes.py`` fits them lobe by lobe).
"""

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from .._jax import float64, jit
from ..data.samples import Samples
from ..physics.models import Model, Params
from .losses import Loss, linearised_weight
from .problem import Problem, prepared, residuals, target_and_scale

#: No albedo starts more than this factor below the largest one of its solution (the fit moves log-albedos).
ALBEDO_FLOOR = 1e-3
#: Starts are searched on at most this many samples; the winner is then refined on all of them.
SEARCH_SAMPLES = 2**14
#: The part of the search subset taken as the brightest samples (the rest at random), so that a narrow lobe
#: that a few samples see is still seen.
BRIGHT_SHARE = 0.25


def search_subset(samples: Samples, seed: int) -> np.ndarray | None:
    """Indices of the samples the starts are searched on, or None for all of them.

    Above :data:`SEARCH_SAMPLES` samples: the brightest quarter of the subset
    (by each sample's largest value relative to its channel's median, so a
    specular peak is kept) and the rest drawn at random with ``seed``. An
    all-zero channel would overflow the ratio; each channel's scale is at
    least a thousandth of its largest value.
    """
    n = samples.n_samples
    if n <= SEARCH_SAMPLES:
        return None
    # A channel that is 0 almost everywhere (an albedo of 0) is scaled by a thousandth of its largest value.
    values = samples.values
    scale = np.maximum(np.median(values, axis=0), 1e-3 * np.max(values, axis=0))
    brightness = np.max(values / np.maximum(scale, np.finfo(float).tiny), axis=1)
    n_bright = int(SEARCH_SAMPLES * BRIGHT_SHARE)
    bright = np.argpartition(-brightness, n_bright)[:n_bright]
    others = np.setdiff1d(np.arange(n), bright, assume_unique=True)
    rest = np.random.default_rng(seed).choice(others, SEARCH_SAMPLES - n_bright, replace=False)
    return np.sort(np.concatenate([bright, rest]))


@float64
def starting_points(model: Model, loss: Loss, problem: Problem, n_starts: int) -> list[np.ndarray]:
    """Up to ``n_starts`` unconstrained start vectors, best first: lobes placed greedily on the grid."""
    if not model.n_lobes:
        weight = _weights(loss, problem)
        diffuse_basis = jnp.full((1, problem.wi.shape[0]), 1.0 / np.pi, problem.wi.dtype)
        diffuse = _albedos(*(np.asarray(x) for x in _gram(diffuse_basis, weight, problem.measured)))[0]
        return [
            model.unconstrained.from_params(Params(_floored(diffuse), np.zeros((0, problem.measured.shape[1])), {}))
        ]
    search = LobeSearch(model, loss, problem)
    chosen: list[dict[str, float]] = []
    for _ in range(model.n_lobes):
        costs, thetas = search.candidates(chosen)
        order = np.argsort(costs, kind="stable")
        chosen.append(search.grid[order[0]])
    return [thetas[index] for index in order[:n_starts]]


class LobeSearch:
    """The grid of a model's lobe shapes on one problem, for placing its lobes one at a time.

    :meth:`candidates` places the next lobe beside lobes whose shapes are fixed (grid shapes or fitted ones):
    for every grid shape, the best albedos of all lobes so far (variable projection), scored by the true loss
    of the whole model with the lobes not yet placed switched off (albedo 0, which the solver's dead-column rule
    then leaves alone: the fit of fewer lobes runs in the compiled solver of all of them).
    """

    @float64
    def __init__(self, model: Model, loss: Loss, problem: Problem):
        self.model, self.loss, self.problem = model, loss, problem
        self.grid = model.lobe.grid
        self.weight = _weights(loss, problem)
        stacked = {name: jnp.asarray([shape[name] for shape in self.grid]) for name in model.lobe.names}
        self.lobes = _grid_lobes(model.lobe, stacked, problem.wi, problem.wo)  # (G, N)
        self.diffuse_basis = jnp.full((1, problem.wi.shape[0]), 1.0 / np.pi, problem.wi.dtype)

    @float64
    def candidates(self, chosen: list[dict[str, float]]) -> tuple[np.ndarray, list[np.ndarray]]:
        """Costs (G,) and unconstrained vectors of the whole model with lobe ``len(chosen) + 1`` at each grid shape."""
        model, n_channels = self.model, self.problem.measured.shape[1]
        fixed = self.diffuse_basis
        if chosen:
            shapes = {name: jnp.asarray([shape[name] for shape in chosen]) for name in model.lobe.names}
            fixed = jnp.concatenate([fixed, _grid_lobes(model.lobe, shapes, self.problem.wi, self.problem.wo)])
        grams, rhs = (np.asarray(x) for x in _grid_grams(fixed, self.lobes, self.weight, self.problem.measured))
        off = [self.grid[0]] * (model.n_lobes - len(chosen) - 1)  # any valid shape: their albedos are 0
        thetas = []
        for index, shape in enumerate(self.grid):
            albedos = _floored(_albedos(grams[index], rhs[index]))
            specular = np.concatenate([albedos[1:], np.zeros((len(off), n_channels))])
            every = [*chosen, shape, *off]
            shape_arrays = {name: np.array([s[name] for s in every]) for name in model.lobe.names}
            thetas.append(model.unconstrained.from_params(Params(albedos[0], specular, shape_arrays)))
        costs = np.asarray(_grid_costs(model, self.loss, jnp.asarray(np.stack(thetas)), self.problem))
        return costs, thetas


def _albedos(gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Non-negative albedos (B, C) from per-channel normal equations ``gram`` (C, B, B) and ``rhs`` (C, B).

    NNLS on the B×B system through its Cholesky factor ``R``: ``|R x - R⁻ᵀ rhs|²``
    equals the weighted sum of squares up to a constant.
    """
    n_channels, n_basis = rhs.shape
    albedos = np.zeros((n_basis, n_channels))
    for channel in range(n_channels):
        # A lobe that no sample sees has a zero row; a relative ridge keeps the factor defined.
        matrix = gram[channel]
        matrix = matrix + (1e-12 * np.trace(matrix) + np.finfo(float).tiny) * np.eye(n_basis)
        upper = np.linalg.cholesky(matrix).T
        albedos[:, channel], _ = scipy.optimize.nnls(upper, np.linalg.solve(upper.T, rhs[channel]))
    return albedos


def _floored(albedos: np.ndarray) -> np.ndarray:
    return np.maximum(albedos, ALBEDO_FLOOR * max(float(np.max(albedos)), 1e-6))


@jit(static_argnums=0)
def _weights(loss: Loss, problem: Problem):
    return linearised_weight(loss, problem.measured, problem.wi[:, 2:3], target_and_scale(loss, problem)[1])


@jit
def _gram(basis, weight, measured):
    """Per-channel normal equations (C, B, B), (C, B) of ``Σ_n w[n,c] (Σ_b x[b,c] basis[b,n] - y[n,c])²``."""
    weighted = basis[None, :, :] * weight.T[:, None, :]  # (C, B, N)
    return jnp.einsum("cbn,dn->cbd", weighted, basis), jnp.einsum("cbn,nc->cb", weighted, measured)


@jit
def _grid_grams(fixed, lobes, weight, measured):
    """:func:`_gram` for the basis ``fixed`` plus each grid lobe: (G, C, B, B), (G, C, B)."""
    return jax.vmap(lambda lobe: _gram(jnp.concatenate([fixed, lobe[None]]), weight, measured))(lobes)


@jit(static_argnums=0)
def _grid_lobes(lobe, shapes, wi, wo):
    return jax.vmap(lambda shape: lobe(shape, wi, wo))(shapes)


@jit(static_argnums=(0, 1))
def _grid_costs(model: Model, loss: Loss, thetas, problem: Problem):
    problem = prepared(loss, problem)
    return jax.vmap(lambda theta: jnp.sum(residuals(model, loss, theta, problem) ** 2))(thetas)
