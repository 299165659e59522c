"""Data-driven starting points for the fit, by variable projection over a grid of lobe shapes.

Every model is linear in its albedos (``physics/models/model.py``). For a fixed lobe
shape, the albedos that minimise the loss *linearised about the data*,
``Σ w (f - y)²`` with ``w = (scale · T'(y))²`` (``losses.linearised_weight``), are
a small non-negative least-squares problem per channel (Golub & Pereyra 1973,
variable projection), solved exactly by :func:`nonnegative_least_squares`. Every
shape of the lobe family's coarse grid gets its best albedos and is scored by
the true loss, all shapes at once; the best few become the Levenberg-Marquardt
starts. The whole search is one compiled program, over every dataset of a batch
at once (:func:`grid_starts`). Models with several lobes (Lafortune) place their
lobes one at a time (:class:`LobeSearch`; ``lobes.py`` fits them lobe by lobe).
"""

import itertools
from dataclasses import dataclass

import numpy as np

from ..._jax import float64, jax, jnp
from ..._programs import jit
from ...data.samples import Samples
from ...physics.domains import ALBEDO
from ...physics.geometry import above_horizon
from ...physics.models.model import LobeModel
from ...physics.models.params import Params, albedo_size, lobe_family, whole_albedos
from ..objective.losses import Loss, linearised_weight
from ..objective.problem import Problem, prepared, residuals, residuals_of_values
from ..solver.hold import Hold, respected

#: No albedo starts more than this factor below the largest one of its solution (the fit moves log-albedos).
ALBEDO_FLOOR = 1e-3
#: Starts are searched on at most this many samples; the winner is then refined on all of them.
SEARCH_SAMPLES = 2**14
#: A lobe with per-channel parameters (a conductor) is searched this many grid shapes at a time: its grid is larger
#: (352 shapes with the measured metals on RGB data) and its bases C times larger, and all of them at once, (G, B, N,
#: C), made the search memory-bound: on the pickled-oak example (10k samples × 3 channels, 2-core Xeon, loaded) the
#: search took 1,075 ms at once, 383, 354, 342, 416, 567 and 508 ms in batches of 1, 2, 4, 8, 16 and 64.
PER_CHANNEL_BATCH = 4
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
    # Channel by channel, in rows (C, N): numpy reduces a contiguous row ~10× faster than a column of (N, C).
    channels = np.ascontiguousarray(samples.values.T)
    scale = np.maximum(np.median(channels, axis=1), 1e-3 * np.max(channels, axis=1))
    brightness = np.max(channels / np.maximum(scale, np.finfo(float).tiny)[:, None], axis=0)
    n_bright = int(SEARCH_SAMPLES * BRIGHT_SHARE)
    bright = np.argpartition(-brightness, n_bright)[:n_bright]
    others = np.ones(n, bool)
    others[bright] = False
    others = np.flatnonzero(others)
    rest = np.random.default_rng(seed).choice(others, SEARCH_SAMPLES - n_bright, replace=False)
    return np.sort(np.concatenate([bright, rest]))


@float64
def starting_points(
    model: LobeModel,
    loss: Loss,
    problem: Problem,
    n_starts: int,
    hold: Hold | None = None,
    channels: tuple[str, ...] | None = None,
) -> list[np.ndarray]:
    """Up to ``n_starts`` unconstrained start vectors of one problem, best first: lobes placed greedily on the grid;
    every start respects ``hold`` (``hold.py``); ``channels``: the data's channel names (:func:`grid_channels`)."""
    if model.n_lobes <= 1:
        stacked = jax.tree.map(lambda leaf: leaf[None], (problem, hold))
        channels = grid_channels(model, channels)
        n_grid = len(_grid(model, channels))
        return list(np.asarray(grid_starts(model, loss, min(n_starts, n_grid), *stacked, channels))[0])
    search = LobeSearch(model, loss, problem, hold)
    chosen: list[dict[str, float]] = []
    for _ in range(model.n_lobes):
        costs, thetas = search.candidates(chosen)
        order = np.argsort(costs, kind="stable")
        chosen.append(search.grid[order[0]])
    return [thetas[index] for index in order[:n_starts]]


def grid_channels(model: LobeModel, channels: tuple[str, ...] | None) -> tuple[str, ...] | None:
    """The channel names the grid search of ``model`` depends on: the data's, for a lobe with per-channel parameters
    (its measured starts, ``Lobe.channel_grid``, are in the data's channels), else None (every dataset, whatever its
    channels' names, shares one compiled search)."""
    has_channel_starts = model.lobe is not None and model.lobe.channel_names  # a lobe exactly when n_lobes > 0
    return tuple(channels) if has_channel_starts and channels is not None else None


@jit(static_argnums=(0, 1, 2, 5))
def grid_starts(
    model: LobeModel,
    loss: Loss,
    n_starts: int,
    problems: Problem,
    holds: Hold | None = None,
    channels: tuple[str, ...] | None = None,
):
    """The ``n_starts`` best grid starts (D, n_starts, k) of each of the stacked problems (D, N, …), best first
    (ties to the earlier grid shape), for models of at most one lobe: one program for every dataset of a batch.
    ``holds`` (arrays (D, k)): what each dataset's fit holds (``hold.py``), or None. ``channels``: the datasets'
    channel names, for the measured starts of a lobe with per-channel parameters (:func:`grid_channels`).

    The datasets are searched one after another inside the program (``lax.map``): the grid's lobe values are
    (G, N) per dataset, and all of them at once could outgrow memory where one at a time is small.
    """

    def best_of_one(pair):
        costs, thetas = _candidates(model, loss, *pair, {}, channels)
        order = jnp.argsort(costs, stable=True)[:n_starts]
        return thetas[order]

    return jax.lax.map(best_of_one, (problems, holds))


class LobeSearch:
    """The grid of a model's lobe shapes on one problem, for placing its lobes one at a time.

    :meth:`candidates` places the next lobe beside lobes whose shapes are fixed (grid shapes or fitted ones):
    for every grid shape, the best albedos of all lobes so far (variable projection), scored by the true loss
    of the whole model with the lobes not yet placed switched off (albedo 0, which the solver's dead-column rule
    then leaves alone: the fit of fewer lobes runs in the compiled solver of all of them).
    """

    def __init__(self, model: LobeModel, loss: Loss, problem: Problem, hold: Hold | None = None):
        self.model, self.loss, self.problem, self.hold = model, loss, problem, hold
        self.grid = lobe_family(model).grid

    @float64
    def candidates(self, chosen: list[dict[str, float]]) -> tuple[np.ndarray, list[np.ndarray]]:
        """Costs (G,) and unconstrained vectors of the whole model with lobe ``len(chosen) + 1`` at each grid shape."""
        shapes = {name: np.array([shape[name] for shape in chosen], float) for name in lobe_family(self.model).names}
        costs, thetas = _lobe_candidates(self.model, self.loss, self.problem, self.hold, shapes if chosen else {})
        return np.asarray(costs), list(np.asarray(thetas))


def _grid(model: LobeModel, channels: tuple[str, ...] | None = None) -> tuple[dict[str, float], ...]:
    """The lobe family's grid of shapes, and its measured shapes in ``channels`` (``Lobe.channel_grid``) where
    given; one empty shape for a model without lobes (its one start)."""
    if model.lobe is None:  # no lobes
        return ({},)
    return model.lobe.grid + (model.lobe.channel_grid(channels) if channels else ())


@jit(static_argnums=(0, 1))
def _lobe_candidates(model: LobeModel, loss: Loss, problem: Problem, hold: Hold | None, chosen: dict):
    return _candidates(model, loss, problem, hold, chosen)


def _candidates(model: LobeModel, loss: Loss, problem: Problem, hold: Hold | None, chosen: dict, channels=None):
    """Costs (G,) and unconstrained vectors (G, k) of the model with its next lobe at each grid shape (JAX).

    ``chosen``: the shapes (K₀,) of the lobes already placed, {} for none. Each candidate's albedos are the
    non-negative least-squares ones of the linearised loss, floored at :data:`ALBEDO_FLOOR` of their largest
    (the fit moves log-albedos); the lobes after the new one are off (albedo 0, any shape: the grid's first).
    With a ``hold``, the grid's shapes are moved onto what it allows, the albedos it fixes are held in the least
    squares, and every vector respects it. A lobe with per-channel parameters (``Lobe.channel_names``) is one lobe
    per channel: the bases are per channel, (G, B, N, C), and its grid's numbers stand for every channel, beside
    the grid's measured shapes in ``channels`` (:func:`_grid`).
    """
    problem = prepared(loss, problem)
    n_channels = problem.measured.shape[1]
    weight = linearised_weight(loss, problem.measured, problem.wi[:, 2:3], problem.scale)
    grid = _grid(model, channels)
    n_placed = len(next(iter(chosen.values()), ()))
    lobe_of = model.lobe
    per_channel = lobe_of.channel_names if lobe_of is not None else ()
    fixed = model.diffuse({}, problem.wi, problem.wo)[None].astype(problem.wi.dtype)  # the diffuse term's basis
    if per_channel:  # (B₀, N, C)
        fixed = jnp.broadcast_to(fixed[:, :, None], (*fixed.shape, n_channels))
    if chosen:
        fixed = jnp.concatenate([fixed, model.lobe_values(chosen, problem.wi, problem.wo)])
    separated = _Separated.of(model, grid, chosen, problem.measured.shape)  # None for whole lobes too
    if separated is not None:  # each distinct factor of the lobe computed once (_Separated)
        stacked, grams, rhs, cost_at = separated.search(model, loss, problem, hold, fixed, weight)
    elif lobe_of is not None:
        stacked = {
            name: jnp.asarray(
                [np.broadcast_to(shape[name], (n_channels,)) if name in per_channel else shape[name] for shape in grid]
            )
            for name in lobe_of.names
        }
        if hold is not None:
            stacked = _held_shapes(model, stacked, hold, n_placed, n_channels)
    cost_of = lambda theta: jnp.sum(residuals(model, loss, theta, problem) ** 2)
    if model.whole:  # a renderer's own model: no albedos to solve for, each grid shape is scored as it is
        return _whole_candidates(model, stacked, n_channels, hold, cost_of)
    if separated is None and per_channel:  # bases (B, N, C) built and reduced a few shapes at a time (below)

        def normal_equations_of(shape):
            lobe = lobe_family(model)(shape, problem.wi, problem.wo)  # (N, C)
            return _normal_equations(jnp.concatenate([fixed, lobe[None]]), weight, problem.measured)

        grams, rhs = jax.lax.map(normal_equations_of, stacked, batch_size=PER_CHANNEL_BATCH)
    elif separated is None:
        if model.n_lobes:
            lobes = jax.vmap(lambda shape: lobe_family(model)(shape, problem.wi, problem.wo))(stacked)  # (G, N)
            bases = jax.vmap(lambda lobe: jnp.concatenate([fixed, lobe[None]]))(lobes)  # (G, B, N)
        else:
            bases = fixed[None]
        grams, rhs = jax.vmap(lambda basis: _normal_equations(basis, weight, problem.measured))(bases)
    n_basis = rhs.shape[-1]
    held = None if hold is None else _held_albedos(hold, n_basis, n_channels)
    albedos = jnp.swapaxes(nonnegative_least_squares(grams, rhs, held), 1, 2)  # (G, B, C)
    largest = jnp.maximum(jnp.max(albedos, axis=(1, 2), keepdims=True), 1e-6)
    albedos = jnp.maximum(albedos, ALBEDO_FLOOR * largest)
    n_off = model.n_lobes - n_placed - 1 if model.n_lobes else 0

    def theta_of(index, albedo):
        specular = jnp.concatenate([albedo[1:], jnp.zeros((n_off, n_channels))])
        one = lambda name: (n_channels,) if name in per_channel else ()  # one value's shape
        shape = (
            {
                name: jnp.concatenate(
                    [
                        jnp.asarray(chosen.get(name, jnp.zeros((0, *one(name))))),
                        jnp.asarray(stacked[name])[index][None],
                        jnp.full((n_off, *one(name)), grid[0][name]),
                    ]
                )
                for name in model.lobe.names
            }
            if model.n_lobes
            else {}
        )
        return respected(model.unconstrained.from_params(Params(albedo[0], specular, shape)), hold)

    indices = jnp.arange(len(grid))
    thetas = jax.vmap(theta_of)(indices, albedos)
    if separated is not None:
        costs = jax.lax.map(lambda pair: cost_at(*pair), (indices, thetas), batch_size=SEPARATED_BATCH)
    elif per_channel:
        costs = jax.lax.map(cost_of, thetas, batch_size=PER_CHANNEL_BATCH)
    else:
        costs = jax.vmap(cost_of)(thetas)
    return costs, thetas


#: A :class:`_Separated` search holds its factors in memory at once, four arrays (F, N, C) of its indices' Fresnel terms
#: and their products with the weights and data, and one (U, N) of its microfacet terms, where they take at most this
#: many bytes (the 40 indices and 72 shapes of an anisotropic conductor's grid on RGB data: 72 MB at the search's
#: 16,384 samples); else each grid shape's lobe is computed whole, as for any other lobe.
SEPARATED_BYTES = 2**28
#: A :class:`_Separated` search scores this many grid shapes at a time (their values come from its factors).
SEPARATED_BATCH = 16


@dataclass(frozen=True)
class _Separated:
    """The grid of a :attr:`~brdffit.physics.models.lobe.Lobe.separable` lobe (a conductor's microfacet lobe: ``F(cos
    β; eta, k)`` (N, C) times ``D·G/(4 ci co)`` (N,)) as its distinct factors: ``shared`` (U,) shapes of the shared
    parameters, ``channel`` (F, C) values of the per-channel ones, and which of each grid shape ``g`` takes
    (``shared_of[g]``, ``channel_of[g]``). The grid is every roughness with every index (and measured metals at a few
    roughnesses): a conductor's 2,240 anisotropic shapes have 72 distinct microfacet factors and 40 distinct indices,
    so the search evaluates 112 lobes' worth of the costly Fresnel and Smith terms, not 2,240. The normal equations
    of every grid shape come from three contractions of the factors (``Σ_n w F² U²`` etc.), and each shape's values
    for its cost from a product of two of them. The start search (grid and race) of an export's anisotropic stand-ins
    (8,640 pairs, in a warm process) took 1.3–1.7 s whole, 0.29–0.34 s so; the grid alone of an isotropic Beckmann
    one, 0.22 and 0.09 s (2-core x86-64)."""

    shared: dict
    channel: dict
    shared_of: np.ndarray
    channel_of: np.ndarray

    @staticmethod
    def of(model: LobeModel, grid, chosen: dict, measured_shape: tuple[int, ...]) -> "_Separated | None":
        """The factors of ``model``'s one lobe on ``grid``, or None: a lobe that is not separable, a model of several
        lobes, lobes placed already (``chosen``), or factors above :data:`SEPARATED_BYTES` on data of
        ``measured_shape`` (N, C)."""
        lobe = model.lobe
        if lobe is None or not lobe.separable or model.n_lobes != 1 or chosen:
            return None
        n, n_channels = measured_shape
        shared_names = [name for name in lobe.names if name not in lobe.channel_names]
        shared_keys: dict[tuple, int] = {}
        channel_keys: dict[tuple, int] = {}
        shared_of, channel_of = [], []
        for shape in grid:
            shared_key = tuple(float(shape[name]) for name in shared_names)
            channel_key = tuple(
                tuple(np.broadcast_to(np.asarray(shape[name], float), (n_channels,)).tolist())
                for name in lobe.channel_names
            )
            shared_of.append(shared_keys.setdefault(shared_key, len(shared_keys)))
            channel_of.append(channel_keys.setdefault(channel_key, len(channel_keys)))
        if (4 * len(channel_keys) * n_channels + len(shared_keys)) * n * 8 > SEPARATED_BYTES:
            return None
        columns = lambda keys, names: {name: np.array([key[i] for key in keys]) for i, name in enumerate(names)}
        return _Separated(
            columns(shared_keys, shared_names),
            columns(channel_keys, lobe.channel_names),
            np.array(shared_of),
            np.array(channel_of),
        )

    def search(self, model: LobeModel, loss: Loss, problem: Problem, hold: Hold | None, fixed, weight):
        """The grid's shapes (G,) as ``_candidates`` stacks them (moved onto ``hold``), the normal equations (G, C, B,
        B), (G, C, B) of each with the ``fixed`` bases (B₀, N, C) before its lobe, and ``cost_at(g, theta)``: the
        loss's cost of grid shape ``g``'s vector ``theta`` (its albedos; its shape is grid shape ``g``'s)."""
        lobe = model.lobe
        assert lobe is not None
        n_channels = problem.measured.shape[1]
        shared, channel = dict(self.shared), dict(self.channel)
        if hold is not None:
            shared, channel = _held_lobe_shapes(model, shared | channel, hold, 0, n_channels)
        stacked = {name: jnp.asarray(values)[self.shared_of] for name, values in shared.items()}
        stacked |= {name: jnp.asarray(values)[self.channel_of] for name, values in channel.items()}
        visible, wi, wo = above_horizon(problem.wi, problem.wo)
        units = jnp.where(visible, jax.vmap(lambda shape: lobe.shared_factor(shape, wi, wo))(shared), 0.0)  # (U, N)
        factors = jax.vmap(lambda shape: lobe.channel_factor(shape, wi, wo))(channel)  # (F, N, C)
        weighted = weight[None] * factors  # (F, N, C)
        squares = jnp.einsum("fnc,un->fuc", weighted * factors, units * units)  # Σ_n w F² U²
        crossed = jnp.einsum("bnc,fnc,un->fucb", fixed, weighted, units)  # Σ_n w B₀ F U
        lobe_rhs = jnp.einsum("fnc,un->fuc", weighted * problem.measured[None], units)  # Σ_n w y F U
        fixed_gram, fixed_rhs = _normal_equations(fixed, weight, problem.measured)  # (C, B₀, B₀), (C, B₀)
        pick = lambda array: array[self.channel_of, self.shared_of]  # (G, …)
        crossed, n_grid = pick(crossed), len(self.shared_of)  # (G, C, B₀)
        top = jnp.concatenate([jnp.broadcast_to(fixed_gram, (n_grid, *fixed_gram.shape)), crossed[..., None]], axis=3)
        bottom = jnp.concatenate([crossed, pick(squares)[..., None]], axis=2)[:, :, None, :]
        grams = jnp.concatenate([top, bottom], axis=2)  # (G, C, B, B)
        rhs = jnp.concatenate([jnp.broadcast_to(fixed_rhs, (n_grid, *fixed_rhs.shape)), pick(lobe_rhs)[..., None]], 2)
        diffuse = model.diffuse({}, wi, wo)
        shared_of, channel_of = jnp.asarray(self.shared_of), jnp.asarray(self.channel_of)

        dtype = problem.wi.dtype  # the model evaluated in the problem's precision, as ``residuals`` does

        def cost_at(index, theta):
            params = jax.tree.map(lambda leaf: leaf.astype(dtype), model.unconstrained.to_params(theta, n_channels))
            lobes = (factors[channel_of[index]] * units[shared_of[index]][:, None])[None].astype(dtype)
            predicted = model.combined(params, visible, diffuse, lobes)
            return jnp.sum(residuals_of_values(loss, predicted, problem) ** 2)

        return stacked, grams, rhs, cost_at


def _whole_candidates(model: LobeModel, stacked: dict, n_channels: int, hold: Hold | None, cost_of):
    """Costs (G,) and unconstrained vectors (G, k) of a whole-lobe model (``LobeModel.whole``) at each grid shape."""

    def theta_of(index):
        shape = {name: jnp.asarray(stacked[name])[index][None] for name in model.lobe.names}
        params = Params(*whole_albedos(n_channels, jnp), shape)
        return respected(model.unconstrained.from_params(params), hold)

    thetas = jax.vmap(theta_of)(jnp.arange(len(next(iter(stacked.values())))))
    return jax.lax.map(cost_of, thetas, batch_size=PER_CHANNEL_BATCH), thetas


def _held_shapes(model: LobeModel, stacked: dict, hold: Hold, lobe: int, n_channels: int) -> dict:
    """The grid's shapes (G,) for lobe ``lobe``, each moved onto what ``hold`` allows (its fixed values, inside its
    bounds), through the solver's coordinates."""
    shared, per_channel = _held_lobe_shapes(model, stacked, hold, lobe, n_channels)
    return shared | per_channel


def _held_lobe_shapes(model: LobeModel, stacked: dict, hold: Hold, lobe: int, n_channels: int) -> tuple[dict, dict]:
    """:func:`_held_shapes`, its shared parameters (G,) and its per-channel ones (G, C) apart; each part moved on its
    own, so that the two may have different lengths (:class:`_Separated`'s distinct factors)."""
    coordinates, per_channel = model.unconstrained.shared, model.unconstrained.per_channel
    k, s = model.n_lobes, len(coordinates.names)
    first = albedo_size(model, n_channels) + lobe * s
    own = jax.tree.map(lambda leaf: leaf[first : first + s, None], hold)  # (S, 1): broadcast over the grid
    shapes = coordinates.from_vector(respected(coordinates.to_vector(stacked), own))
    if per_channel is None:
        return shapes, {}
    p = len(per_channel.names)
    first = albedo_size(model, n_channels) + k * s + lobe * p * n_channels
    own = jax.tree.map(lambda leaf: leaf[first : first + p * n_channels].reshape(p, 1, n_channels), hold)
    return shapes, per_channel.from_vector(respected(per_channel.to_vector(stacked), own))  # (P, G, C)


def _held_albedos(hold: Hold, n_basis: int, n_channels: int):
    """Which albedos (C, B) of the least squares' basis (diffuse, then the lobes in order) ``hold`` fixes, and at
    what values: a mask and the values, for :func:`nonnegative_least_squares`."""
    entries = jnp.arange(n_basis)[None, :] * n_channels + jnp.arange(n_channels)[:, None]  # (C, B) into θ
    return 1.0 - hold.free[entries], ALBEDO.to_physical(hold.value[entries])


def _normal_equations(basis, weight, measured):
    """Per-channel normal equations (C, B, B), (C, B) of ``Σ_n w[n,c] (Σ_b x[b,c] basis[b,n] - y[n,c])²``; a basis
    (B, N, C) has one per channel, ``basis[b, n, c]``."""
    if basis.ndim == 3:
        weighted = basis * weight[None]  # (B, N, C)
        return jnp.einsum("bnc,dnc->cbd", weighted, basis), jnp.einsum("bnc,nc->cb", weighted, measured)
    weighted = basis[None, :, :] * weight.T[:, None, :]  # (C, B, N)
    return jnp.einsum("cbn,dn->cbd", weighted, basis), jnp.einsum("cbn,nc->cb", weighted, measured)


def nonnegative_least_squares(gram, rhs, held=None):
    """``argmin_{x ≥ 0} xᵀ G x − 2 bᵀ x`` for small systems (B ≤ 9), batched over leading axes (JAX).

    ``held``: a mask and values (…, B) of entries of ``x`` fixed at those values (their part of ``Gx`` moves to
    the right-hand side), or None.

    The minimiser is the unconstrained one on its support (the KKT conditions), so it is found by trying
    every support: each of the ``2^B`` subsets solves its own equations, and the best of the feasible
    solutions (x = 0 always is one) wins. Exact, branch-free and cheap for the few albedos of a model, where
    Lawson & Hanson's active-set NNLS would loop on the host. A relative ridge ``1e-12·trace`` keeps the
    system of a lobe no sample sees (a zero row) solvable.
    """
    n_basis = rhs.shape[-1]
    held_mask, held_values = (jnp.zeros(n_basis), jnp.zeros(n_basis)) if held is None else held
    x_held = held_mask * held_values
    rhs = rhs - jnp.einsum("...ij,...j->...i", gram, jnp.broadcast_to(x_held, rhs.shape))
    eye = jnp.eye(n_basis, dtype=gram.dtype)
    trace = jnp.trace(gram, axis1=-2, axis2=-1)[..., None, None]
    gram = gram + (1e-12 * trace + jnp.finfo(gram.dtype).tiny) * eye
    supports = jnp.asarray(list(itertools.product((0.0, 1.0), repeat=n_basis))[1:], gram.dtype)  # (S, B)

    def on_support(mask):
        mask = mask * (1.0 - held_mask)  # (…, B): a held entry is never in a support
        pair = mask[..., :, None] * mask[..., None, :]
        restricted = gram * pair + eye * (1.0 - mask)[..., None, :]  # the support's equations, identity off it
        x = jnp.linalg.solve(restricted, (rhs * mask)[..., None])[..., 0]
        objective = jnp.einsum("...i,...ij,...j->...", x, gram, x) - 2.0 * jnp.sum(rhs * x, axis=-1)
        feasible = jnp.all(x >= 0.0, axis=-1)
        return x, jnp.where(feasible, objective, jnp.inf)

    solutions, objectives = jax.vmap(on_support)(supports)  # (S, …, B), (S, …)
    best = jnp.argmin(objectives, axis=0)  # (…)
    chosen = jnp.take_along_axis(solutions, best[None, ..., None], axis=0)[0]
    return jnp.where(jnp.min(objectives, axis=0)[..., None] < 0.0, chosen, 0.0) + x_held
