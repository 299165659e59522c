"""Losses: the residual transform applied to model and measurement, and per-sample scales.

The losses of ``docs/losses.md``. With ``f`` the model, ``y`` the measurement (both BRDF, 1/sr)
and ``ci = cos θi``, each loss compares ``T(f)`` with ``T(y)``:

=========  ===========================  ==========================================
name       residual ``T(f) - T(y)``      source
=========  ===========================  ==========================================
log        ln(1 + f ci) - ln(1 + y ci)  Löw et al. 2012, E2 without grid weights
l2         f - y                        plain least squares
cosine     (f - y) ci                   Ngan et al. 2005 without grid weights
cbrt       cbrt(f) - cbrt(y)            cube-root compression of the dynamic range
relative   (f - y) / max(y, ε)          ε = :data:`RELATIVE_FLOOR`
=========  ===========================  ==========================================

Residuals are multiplied by ``sqrt(weight)`` and divided by the measurement's
1-σ uncertainty carried into the loss's units, ``sigma · |T'(y)|``, so that
with a ``sigma`` column every loss is a χ² to first order in ``f - y`` (see
:func:`residual_scale`). The cost is the sum of squared residuals.
"""

from collections.abc import Callable
from dataclasses import dataclass, field

from ..._jax import jax, jnp
from ...errors import not_a_choice

#: ε of the ``relative`` loss, in 1/sr: values below it count as if they were ε.
RELATIVE_FLOOR = 1e-4


@dataclass(frozen=True)
class Loss:
    """A residual transform ``T(v; y, ci)`` applied to model values ``v`` and measurements ``y`` alike (JAX)."""

    name: str
    summary: str
    #: (values, measured, cos_i) -> transformed values.
    transform: Callable = field(repr=False)
    #: Whether the residual grows linearly with the values (l2, cosine), so that the brightest samples (a narrow
    #: peak) rule the cost: a model of several lobes then has minima its default starts miss (``starts/lobes.py``).
    linear: bool = False

    def cache_key(self) -> list | None:
        """A built-in loss by its name (``brdffit/_programs/keys.py``); None for a loss of one's own, whose transform
        is a function no key names: its programs are compiled in each process."""
        return [self.name] if LOSSES.get(self.name) is self else None

    def value_and_slope(self, values, measured, cos_i):
        """``T(values)`` and ``dT/dv`` at ``values``, elementwise (forward mode)."""
        return jax.jvp(lambda v: self.transform(v, measured, cos_i), (values,), (jnp.ones_like(values),))


def _cbrt(values, measured, cos_i):
    # The cube root's derivative is infinite at 0; values below the smallest float count as 0.
    return jnp.cbrt(jnp.maximum(values, jnp.finfo(jnp.result_type(values)).tiny))


LOSSES = {
    "log": Loss("log", "ln(1 + f·cos θi) − ln(1 + y·cos θi) (Löw et al. 2012)", lambda v, y, ci: jnp.log1p(v * ci)),
    "l2": Loss("l2", "f − y", lambda v, y, ci: v, linear=True),
    "cosine": Loss("cosine", "(f − y)·cos θi (Ngan et al. 2005)", lambda v, y, ci: v * ci, linear=True),
    "cbrt": Loss("cbrt", "cbrt(f) − cbrt(y)", _cbrt),
    "relative": Loss(
        "relative", f"(f − y) / max(y, {RELATIVE_FLOOR:g})", lambda v, y, ci: v / jnp.maximum(y, RELATIVE_FLOOR)
    ),
}


def get_loss(name: "str | Loss") -> Loss:
    """The loss called ``name`` (a :class:`Loss` is returned as it is), or a one-line error listing the choices."""
    if isinstance(name, Loss):
        return name
    if name not in LOSSES:
        raise not_a_choice("loss", name, LOSSES, "is not a loss")
    return LOSSES[name]


def residual_scale(loss: Loss, values, cos_i, sigma=None, weight=None):
    """Per-sample, per-channel factor (N, C) that multiplies ``T(f) - T(y)`` (JAX).

    ``sqrt(weight) / (sigma · |T'(y*)|)`` with ``y* = max(y, sigma)``, where the
    slope is taken no closer to 0 than one σ (the cube root's slope is infinite
    at 0); ``sqrt(weight)`` alone without ``sigma``. For ``l2`` this is exactly
    ``sqrt(weight)/sigma``. ``cos_i`` is (N, 1).
    """
    scale = jnp.ones_like(values)
    if sigma is not None:
        _, slope = loss.value_and_slope(jnp.maximum(values, sigma), values, cos_i)
        scale = 1.0 / (sigma * jnp.abs(slope))
    if weight is not None:
        scale = scale * jnp.sqrt(weight)[:, None]
    return scale


def linearised_weight(loss: Loss, values, cos_i, scale):
    """Weights (N, C) of ``(f - y)²`` in the loss linearised about ``f = y``: ``(scale · T'(y))²`` (JAX).

    Used for the starting guess, where the albedos solve this weighted linear problem.
    The slope is taken no closer to 0 than 0.1% of the mean measurement (and
    1e-12 1/sr), where the cube root's slope would be infinite; the weights are
    divided by their largest, which leaves the weighted problem unchanged and
    keeps their squares finite. ``cos_i`` is (N, 1).
    """
    at = jnp.maximum(values, jnp.maximum(1e-3 * jnp.mean(values), 1e-12))
    _, slope = loss.value_and_slope(at, values, cos_i)
    weighted_slope = jnp.abs(scale * slope)
    return (weighted_slope / jnp.max(weighted_slope)) ** 2
