"""Parameter domains, the smooth maps from the real line onto them, and their priors.

A :class:`Domain` says where a parameter's values may lie (``contains``, ``bounds``, the ``text``
users read) and which prior the MCMC posterior puts on them (``log_prior``): uniform on bounded
domains and on albedos (which enter the model linearly, so a flat prior is the uninformative one),
log-uniform (``1/x``, Jeffreys) on scales such as roughness and exponents; ``-inf`` outside.

A :class:`MappedDomain` is also one the solver moves through: it works on an unconstrained
``u ∈ ℝ`` with ``x = to_physical(u)``, so that positivity and bounds hold at every step without
constraints in the solver. ``to_unconstrained`` is the inverse, clamped so that a value on the
boundary (an albedo of 0, an ``f0`` of 1) maps to a finite number.

Concrete domains are final (equinox's abstract/final pattern): a new kind of domain subclasses one
of the two abstract classes, never a concrete one.
"""

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import final

import jax
import jax.numpy as jnp
import numpy as np

#: Boundary values are moved this far inside the domain before inverting.
BOUNDARY_OFFSET = 1e-12


class Domain(ABC):
    """Where a parameter's values lie, and the prior put on them."""

    @property
    @abstractmethod
    def text(self) -> str:
        """The domain as users read it, e.g. ``> 0`` or ``[0, 1]``."""

    @property
    @abstractmethod
    def bounds(self) -> tuple[float, float]:
        """Lower and upper bound (``±inf`` where there is none); quantiles are clipped to them."""

    @abstractmethod
    def contains(self, x) -> bool:
        """Whether every value of ``x`` (numpy) is finite and inside the domain."""

    @abstractmethod
    def log_prior(self, x):
        """The unnormalised log prior at ``x`` (JAX), ``-inf`` outside the domain."""


class MappedDomain(Domain):
    """A domain reached from the real line by a smooth map, so that the solver can move freely."""

    @abstractmethod
    def to_physical(self, u):
        """The value at unconstrained ``u`` (JAX)."""

    @abstractmethod
    def to_unconstrained(self, x) -> np.ndarray:
        """The unconstrained coordinate of ``x`` (numpy), finite on the boundary."""


@final
@dataclass(frozen=True)
class Positive(MappedDomain):
    """``x > 0`` (``≥ 0`` when ``allow_zero``), through ``x = exp(u)``: scales fit in log space."""

    allow_zero: bool = False

    @property
    def text(self) -> str:
        return "≥ 0" if self.allow_zero else "> 0"

    @property
    def bounds(self) -> tuple[float, float]:
        return 0.0, float("inf")

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        inside = x >= 0 if self.allow_zero else x > 0
        return bool(np.all(np.isfinite(x) & inside))

    def to_physical(self, u):
        return jnp.exp(u)

    def to_unconstrained(self, x) -> np.ndarray:
        return np.log(np.maximum(np.asarray(x, dtype=float), BOUNDARY_OFFSET))

    def log_prior(self, x):
        """Flat on ``x ≥ 0`` (an amplitude, ``allow_zero``); log-uniform ``1/x`` on ``x > 0`` (a scale)."""
        if self.allow_zero:
            return jnp.where(x >= 0, 0.0, -jnp.inf)
        return jnp.where(x > 0, -jnp.log(jnp.where(x > 0, x, 1.0)), -jnp.inf)


@final
@dataclass(frozen=True)
class GreaterThan(MappedDomain):
    """``x > lower``, through ``x = lower + exp(u)``."""

    lower: float

    @property
    def text(self) -> str:
        return f"> {self.lower:g}"

    @property
    def bounds(self) -> tuple[float, float]:
        return self.lower, float("inf")

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x > self.lower)))

    def to_physical(self, u):
        return self.lower + jnp.exp(u)

    def to_unconstrained(self, x) -> np.ndarray:
        return np.log(np.maximum(np.asarray(x, dtype=float) - self.lower, BOUNDARY_OFFSET))

    def log_prior(self, x):
        """Log-uniform on ``x - lower`` (a scale above its bound)."""
        excess = x - self.lower
        return jnp.where(excess > 0, -jnp.log(jnp.where(excess > 0, excess, 1.0)), -jnp.inf)


@final
@dataclass(frozen=True)
class UnitInterval(MappedDomain):
    """``0 ≤ x ≤ 1``, through the logistic function ``x = 1 / (1 + exp(-u))``."""

    @property
    def text(self) -> str:
        return "[0, 1]"

    @property
    def bounds(self) -> tuple[float, float]:
        return 0.0, 1.0

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x >= 0) & (x <= 1)))

    def to_physical(self, u):
        return jax.nn.sigmoid(u)

    def to_unconstrained(self, x) -> np.ndarray:
        x = np.clip(np.asarray(x, dtype=float), BOUNDARY_OFFSET, 1 - BOUNDARY_OFFSET)
        return np.log(x) - np.log1p(-x)

    def log_prior(self, x):
        """Uniform on [0, 1]."""
        return jnp.where((x >= 0) & (x <= 1), 0.0, -jnp.inf)


@final
@dataclass(frozen=True)
class Interval(Domain):
    """``lower ≤ x ≤ upper`` with a uniform prior; only sampled (by MCMC), never moved by the fit."""

    lower: float
    upper: float

    @property
    def text(self) -> str:
        return f"[{self.lower:g}, {self.upper:g}]"

    @property
    def bounds(self) -> tuple[float, float]:
        return self.lower, self.upper

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x >= self.lower) & (x <= self.upper)))

    def log_prior(self, x):
        """Uniform on [lower, upper]."""
        return jnp.where((x >= self.lower) & (x <= self.upper), 0.0, -jnp.inf)


NON_NEGATIVE = Positive(allow_zero=True)
POSITIVE = Positive()
UNIT_INTERVAL = UnitInterval()
