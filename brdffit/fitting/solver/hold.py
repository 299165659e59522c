"""Fixed and bounded entries of the solver's vector: the coordinates the solver moves when a user holds some.

A fit moves the unconstrained vector ``θ`` (``Model.unconstrained``). With a :class:`Hold` it moves ``z`` of the
same length instead, and every entry is one of three kinds::

    free      θ = z
    bounded   θ = low + (high - low) · σ(z)        σ the logistic function: a scaled logit's inverse
    fixed     θ = value                            z has no effect: its Jacobian column is 0

The bounds are those of ``θ``, each domain's map of the user's physical bounds (``constraints.py``); every map is
increasing, so a physical value in ``[lo, hi]`` is exactly a ``θ`` in ``[low, high]``. A fixed entry's column
of ``JᵀJ`` is 0, which the solver's dead-column rule (``levenberg_marquardt.py``) leaves out of every step and of the
stopping tests, so it never moves and costs nothing but its share of the normal equations' size.

Everything in a hold is a float array (masks as 0 and 1), so it is data to a compiled program: changing a fixed
value, a bound, or which entries are held runs the same compiled solver. The maps are elementwise, so the
Jacobian ``dθ/dz`` is the diagonal :func:`slopes`.

A hold may also draw entries softly towards values, a Gaussian prior on ``θ``: ``prior_weight · (θ − prior_mean)²``
summed is added to the fit's ``rᵀr`` as residuals ``√prior_weight · (θ − prior_mean)`` (``solver/compiled.py``), which
the cost a fit reports leaves out. A spatially varying fit's smoothness prior draws each texel towards its
neighbours so (``svbrdf/smoothing.py``).
"""

from typing import Any, NamedTuple

import numpy as np

from ..._jax import jax, jnp, namespace

#: A start is moved this far inside a bound (a fraction of the bounded range), where σ's slope is not 0.
START_MARGIN = 1e-3
#: A bounded entry whose ``θ`` ends within this fraction of its range from a bound ended on that bound.
ON_BOUND = 1e-4
#: A bounded entry that ends within this fraction of its range from a bound is tried on the bound (:func:`at_bounds`).
NEAR_BOUND = 1e-2


class Hold(NamedTuple):
    """Which entries of the unconstrained vector move and how (arrays (k,), or (D, k) for a batch), float64."""

    free: Any  # 1 where the entry moves (freely or within bounds), 0 where it is fixed
    bounded: Any  # 1 where it moves within [low, high]
    value: Any  # θ of each fixed entry (anything elsewhere)
    low: Any  # the bounds of θ on bounded entries (0 elsewhere)
    high: Any
    prior_mean: Any = None  # θ the prior draws each entry towards (module docstring); None: no prior
    prior_weight: Any = None  # the prior's weight on each entry, 0 where it has none


def free_hold(k: int) -> Hold:
    """The hold (arrays (k,)) of a fit that holds none of its ``k`` entries: every one free."""
    zeros = np.zeros(k)
    return Hold(np.ones(k), zeros, zeros, zeros, zeros)


def prior_cost(theta, hold: Hold | None):
    """``Σ prior_weight · (θ − prior_mean)²`` over the last axis, the prior's part of the solver's ``rᵀr``: a number
    for ``theta`` (k,), one per dataset for (D, k) and a hold's (D, k) arrays; JAX or numpy as they are given; 0
    without a prior."""
    if hold is None or hold.prior_weight is None:
        return 0.0
    xp = namespace(theta, hold.prior_mean, hold.prior_weight)
    return xp.sum(hold.prior_weight * (theta - hold.prior_mean) ** 2, axis=-1)


def theta_of(z, hold: Hold):
    """The unconstrained vector at the solver's coordinates ``z`` (JAX)."""
    within = hold.low + (hold.high - hold.low) * jax.nn.sigmoid(z)
    return jnp.where(hold.free > 0, jnp.where(hold.bounded > 0, within, z), hold.value)


def slopes(z, hold: Hold):
    """``dθ/dz``, the diagonal of the map's Jacobian: 1 on free entries, σ'·(high - low) on bounded, 0 on fixed."""
    sigma = jax.nn.sigmoid(z)
    within = (hold.high - hold.low) * sigma * (1.0 - sigma)
    return jnp.where(hold.free > 0, jnp.where(hold.bounded > 0, within, 1.0), 0.0)


def z_of(theta, hold: Hold):
    """The solver's coordinates of ``theta`` (JAX), a bounded entry first moved :data:`START_MARGIN` inside its
    range; 0 on fixed entries."""
    span = hold.high - hold.low
    fraction = jnp.clip((theta - hold.low) / jnp.where(span > 0, span, 1.0), START_MARGIN, 1.0 - START_MARGIN)
    logit = jnp.log(fraction) - jnp.log1p(-fraction)
    return jnp.where(hold.free > 0, jnp.where(hold.bounded > 0, logit, theta), 0.0)


def respected(theta, hold: Hold | None):
    """``theta`` with every fixed entry at its value and every bounded one inside its range (JAX): a start."""
    return theta if hold is None else theta_of(z_of(theta, hold), hold)


def at_bounds(theta, hold: Hold) -> Hold:
    """``hold`` (numpy, (k,) or (D, k)) with every bounded entry of ``theta`` that lies within :data:`NEAR_BOUND` of a
    bound fixed on that bound.

    The logistic map reaches a bound only in the limit: a fit whose optimum lies beyond a bound creeps toward it,
    each step gaining less, and stops a little short (1e-6 of the cost short on a real 3-lobe Lafortune fit). Solving
    again with those entries on their bounds finds the constrained optimum exactly; the caller keeps that solve when
    its cost is no higher (an optimum just inside a bound makes it higher, and is kept).
    """
    side = on_bound(theta, hold, NEAR_BOUND)
    low, high, value, free, bounded = (
        _as(leaf, side.shape) for leaf in (hold.low, hold.high, hold.value, hold.free, hold.bounded)
    )
    value = np.where(side < 0, low, np.where(side > 0, high, value))
    moved = Hold(np.where(side != 0, 0.0, free), np.where(side != 0, 0.0, bounded), value, low, high)
    return moved._replace(prior_mean=hold.prior_mean, prior_weight=hold.prior_weight)


def on_bound(theta, hold: Hold, within: float = ON_BOUND) -> np.ndarray:
    """-1 where a bounded entry of ``theta`` lies within ``within`` (a fraction of its range) of its lower bound, +1
    of its upper, 0 elsewhere (numpy, (k,) or (D, k))."""
    theta = np.asarray(theta, float)
    low, high, bounded = (_as(leaf, theta.shape) for leaf in (hold.low, hold.high, hold.bounded))
    fraction = (theta - low) / np.where(high > low, high - low, 1.0)
    lower = (bounded > 0) & (fraction <= within)
    upper = (bounded > 0) & (fraction >= 1.0 - within)
    return np.where(lower, -1, np.where(upper, 1, 0))


def _as(leaf, shape) -> np.ndarray:
    return np.broadcast_to(np.asarray(leaf, float), shape)
