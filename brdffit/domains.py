"""Parameter domains and the smooth maps from the real line onto them.

The fit works on an unconstrained vector ``u ∈ ℝᵏ``; each physical parameter is
``to_physical(u)`` of its own entry, so positivity and bounds hold at every
step without constraints in the solver. ``to_unconstrained`` is the inverse,
clamped so that a value on the boundary (an albedo of 0, an ``f0`` of 1) maps
to a finite number.
"""

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from . import _jax  # noqa: F401  (float64 before any array)

#: Boundary values are moved this far inside the domain before inverting.
BOUNDARY_OFFSET = 1e-12


@dataclass(frozen=True)
class Positive:
    """``x > 0`` (``≥ 0`` when ``allow_zero``), through ``x = exp(u)``: scales fit in log space."""

    allow_zero: bool = False

    @property
    def text(self) -> str:
        return "≥ 0" if self.allow_zero else "> 0"

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        inside = x >= 0 if self.allow_zero else x > 0
        return bool(np.all(np.isfinite(x) & inside))

    def to_physical(self, u):
        return jnp.exp(u)

    def to_unconstrained(self, x):
        return np.log(np.maximum(np.asarray(x, dtype=float), BOUNDARY_OFFSET))


@dataclass(frozen=True)
class GreaterThan:
    """``x > lower``, through ``x = lower + exp(u)``."""

    lower: float

    @property
    def text(self) -> str:
        return f"> {self.lower:g}"

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x > self.lower)))

    def to_physical(self, u):
        return self.lower + jnp.exp(u)

    def to_unconstrained(self, x):
        return np.log(np.maximum(np.asarray(x, dtype=float) - self.lower, BOUNDARY_OFFSET))


@dataclass(frozen=True)
class UnitInterval:
    """``0 ≤ x ≤ 1``, through the logistic function ``x = 1 / (1 + exp(-u))``."""

    text: str = "[0, 1]"

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x >= 0) & (x <= 1)))

    def to_physical(self, u):
        return jax.nn.sigmoid(u)

    def to_unconstrained(self, x):
        x = np.clip(np.asarray(x, dtype=float), BOUNDARY_OFFSET, 1 - BOUNDARY_OFFSET)
        return np.log(x) - np.log1p(-x)


NON_NEGATIVE = Positive(allow_zero=True)
POSITIVE = Positive()
UNIT_INTERVAL = UnitInterval()
