"""Parameter domains, the smooth maps from the real line onto them, and their priors.

A :class:`Domain` says where a parameter's values may lie (``contains``, ``bounds``, the ``text``
users read) and which prior the MCMC posterior puts on them (``log_prior``): uniform on bounded
domains and on albedos (which enter the model linearly, so a flat prior is the uninformative one),
log-uniform (``1/x``, Jeffreys) on scales such as roughness and exponents; ``-inf`` outside.

A :class:`MappedDomain` is also one the solver moves through: it works on an unconstrained
``u ∈ ℝ`` with ``x = to_physical(u)``, so that positivity and bounds hold at every step without
constraints in the solver. ``to_unconstrained`` is the inverse, clamped so that a value on the
boundary (an albedo of 0, an ``f0`` of 1) maps to a finite number.

Every domain also has a *plausible* range, inside its bounds: where real materials lie. A fitted value
beyond it earns a warning (a roughness above 2, an exponent above 10⁴, an albedo above 1, a dielectric
index within 10⁻⁶ of 1), and a start beyond :data:`START_FACTOR` times its upper end is refused, since a fit
cannot move from there (a Phong exponent of 10⁹ is a delta function with no gradient).

Concrete domains are final (equinox's abstract/final pattern): a new kind of domain subclasses one
of the two abstract classes, never a concrete one.
"""

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import final

import numpy as np

from .._jax import jax, jnp, namespace

#: Boundary values are moved this far inside the domain before inverting.
BOUNDARY_OFFSET = 1e-12
#: A start may lie at most this factor beyond the upper end of a parameter's plausible range.
START_FACTOR = 100.0


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

    @property
    def plausible(self) -> tuple[float, float]:
        """Where real materials lie: the bounds, unless a domain narrows them."""
        return self.bounds

    def nearest_inside(self, x) -> np.ndarray:
        """``x`` (numpy) moved onto the domain where it lies on or beyond an open bound. A fit's map reaches an
        open bound only by rounding (``1 + exp(u)`` is exactly 1 for ``u < -37``); a result must still be a value
        the domain holds, or no command could read the result file back."""
        low, high = self.bounds
        x = np.clip(np.asarray(x, dtype=float), low, high)
        if not self.contains(x):  # as far inside as to_unconstrained clamps: finite to every model there
            x = np.where(x <= low, low + BOUNDARY_OFFSET, x)
            x = np.where(x >= high, high - BOUNDARY_OFFSET, x)
        return x


class MappedDomain(Domain):
    """A domain reached from the real line by a smooth map, so that the solver can move freely."""

    @abstractmethod
    def to_physical(self, u):
        """The value at unconstrained ``u`` (JAX)."""

    @abstractmethod
    def to_unconstrained(self, x) -> np.ndarray:
        """The unconstrained coordinate of ``x``, finite on the boundary (numpy for numpy ``x``, else JAX)."""


@final
@dataclass(frozen=True)
class Positive(MappedDomain):
    """``x > 0`` (``≥ 0`` when ``allow_zero``), through ``x = exp(u)``: scales fit in log space.

    ``plausible_max``: the upper end of the plausible range (None: no limit).
    """

    allow_zero: bool = False
    plausible_max: float | None = None

    @property
    def plausible(self) -> tuple[float, float]:
        return 0.0, float("inf") if self.plausible_max is None else self.plausible_max

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
        xp = namespace(x)
        return xp.log(xp.maximum(xp.asarray(x, dtype=float), BOUNDARY_OFFSET))

    def log_prior(self, x):
        """Flat on ``x ≥ 0`` (an amplitude, ``allow_zero``); log-uniform ``1/x`` on ``x > 0`` (a scale)."""
        if self.allow_zero:
            return jnp.where(x >= 0, 0.0, -jnp.inf)
        return jnp.where(x > 0, -jnp.log(jnp.where(x > 0, x, 1.0)), -jnp.inf)


@final
@dataclass(frozen=True)
class GreaterThan(MappedDomain):
    """``x > lower``, through ``x = lower + exp(u)``; ``plausible_margin``: how far above ``lower`` real values lie."""

    lower: float
    plausible_margin: float = 0.0

    @property
    def plausible(self) -> tuple[float, float]:
        return self.lower + self.plausible_margin, float("inf")

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
        xp = namespace(x)
        return xp.log(xp.maximum(xp.asarray(x, dtype=float) - self.lower, BOUNDARY_OFFSET))

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
        xp = namespace(x)
        x = xp.clip(xp.asarray(x, dtype=float), BOUNDARY_OFFSET, 1 - BOUNDARY_OFFSET)
        return xp.log(x) - xp.log1p(-x)

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


@final
@dataclass(frozen=True)
class AxisAzimuth(MappedDomain):
    """The azimuth of an axis, in degrees, in ``(−90, 90]`` (in radians, in ``(−π/2, π/2]``, with ``radians``: glTF's
    ``anisotropyRotation``): an axis and its opposite are one (an anisotropic lobe's tangent, whose lobe is
    π-periodic in it). Reached from the real line (radians) by wrapping, ``x = 90 − ((90 − degrees(u)) mod 180)``: the
    lobe is the same on both sides of the seam at ±90°, so the solver moves across it freely; uniform prior."""

    radians: bool = False

    @property
    def _quarter_turn(self) -> float:
        return np.pi / 2 if self.radians else 90.0

    @property
    def text(self) -> str:
        return "(-π/2, π/2] radians" if self.radians else "(-90, 90] degrees"

    @property
    def bounds(self) -> tuple[float, float]:
        return -self._quarter_turn, self._quarter_turn

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (x > -self._quarter_turn) & (x <= self._quarter_turn)))

    def wrapped(self, angle):
        """``angle`` (any real, in the domain's unit; numpy or JAX) as the same axis's azimuth in the domain."""
        xp = namespace(angle)
        quarter = self._quarter_turn
        return quarter - xp.mod(quarter - angle, 2.0 * quarter)

    def to_physical(self, u):
        return self.wrapped(u if self.radians else jnp.degrees(u))

    def to_unconstrained(self, x) -> np.ndarray:
        xp = namespace(x)
        x = xp.asarray(x, dtype=float)
        return x if self.radians else xp.radians(x)

    def log_prior(self, x):
        """Uniform on the domain."""
        return jnp.where((x > -self._quarter_turn) & (x <= self._quarter_turn), 0.0, -jnp.inf)


NON_NEGATIVE = Positive(allow_zero=True)
POSITIVE = Positive()
UNIT_INTERVAL = UnitInterval()
#: An albedo: a fraction of the light, so at most 1 for a real material (fits beyond it get a warning).
ALBEDO = Positive(allow_zero=True, plausible_max=1.0)
#: A roughness (rms slope, Beckmann or Ward): beyond 2 the surface is a diffuser and the lobe meaningless.
ROUGHNESS = Positive(plausible_max=2.0)
#: A cosine-power exponent: beyond 10⁴ a lobe is narrower than any gonioreflectometer resolves (0.6°).
EXPONENT = Positive(plausible_max=1e4)
#: The azimuth of an anisotropic lobe's tangent (degrees from +x, in (−90, 90]).
AXIS_AZIMUTH = AxisAzimuth()
#: The same in radians, in (−π/2, π/2] (glTF's anisotropyRotation).
AXIS_ANGLE = AxisAzimuth(radians=True)
