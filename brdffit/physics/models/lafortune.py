"""Lafortune's generalised cosine lobes.

Lafortune, Foo, Torrance & Greenberg, "Non-linear approximation of reflectance
functions", SIGGRAPH 1997, isotropic form (``C_x = C_y = cxy``), with the
normalisation Ngan et al. 2005 fit::

    lobe = (n+2)/(2π) · max(0, (cxy (wi_x wo_x + wi_y wo_y) + cz ci co) / max(|cxy|, |cz|))^n

The ratio form makes the lobe independent of the length of ``(cxy, cz)``; brdffit
fixes that length by ``2 cxy² + cz² = 1``, so a lobe's direction is one angle
``ψ`` with ``cxy = sin ψ / √2``, ``cz = cos ψ``, which is what the fit moves.
``cxy < 0`` is a forward (specular) lobe, ``cxy > 0`` a retro-reflective one.
Since ``|cxy·a + cz·b| ≤ max(|cxy|, |cz|)·(|a| + |b|) ≤ max(|cxy|, |cz|)``
for unit directions, the base is at most 1 and ``n`` of 10⁴ stays finite.
"""

from dataclasses import dataclass
from typing import final

import numpy as np

from ..._jax import jnp, namespace
from ...checks import whole_number
from ...errors import BrdfInputError
from ..domains import EXPONENT, Domain, Interval, Positive
from ..geometry import safe_power
from .grids import EXPONENT_GRID
from .lobe import BoundedShapeCoordinates, Lobe, ShapeCoordinates
from .model import LobeModel, ModelEntry

#: The most lobes the ``lobes`` option accepts; more than a handful cannot be told apart by any measurement.
MAX_LOBES = 8

#: How far ``2 cxy² + cz²`` may be from 1 in a user's parameters (published tables round to 3 digits).
NORM_TOLERANCE = 0.01

#: Lobe directions ψ to start from: forward (cxy = -cz), flatter and steeper forward, normal, retro.
_FORWARD = float(np.arctan2(-np.sqrt(2.0), 1.0))
DIRECTION_GRID = (_FORWARD, -1.25, -0.6, 0.0, -_FORWARD)


def direction_from_angle(psi):
    """``(cxy, cz) = (sin ψ / √2, cos ψ)``, which satisfies ``2 cxy² + cz² = 1``."""
    xp = namespace(psi)
    return xp.sin(psi) / np.sqrt(2.0), xp.cos(psi)


def angle_of_direction(cxy, cz):
    """``ψ = atan2(√2 cxy, cz)``, the inverse of :func:`direction_from_angle` on ``2 cxy² + cz² = 1``."""
    xp = namespace(cxy, cz)
    return xp.arctan2(np.sqrt(2.0) * xp.asarray(cxy, dtype=float), xp.asarray(cz, dtype=float))


@final
@dataclass(frozen=True)
class AngleAndLogExponent(ShapeCoordinates):
    """What the solver moves: the direction's angle ``ψ`` and ``ln n``."""

    @property
    def names(self) -> tuple[str, ...]:
        return ("psi", "n")

    def to_vector(self, shape) -> np.ndarray:
        xp = namespace(shape["cxy"], shape["cz"], shape["n"])
        return xp.stack([angle_of_direction(shape["cxy"], shape["cz"]), EXPONENT.to_unconstrained(shape["n"])])

    def from_vector(self, u):
        cxy, cz = direction_from_angle(u[0])
        return {"cxy": cxy, "cz": cz, "n": EXPONENT.to_physical(u[1])}


@final
@dataclass(frozen=True)
class AngleAndExponent(BoundedShapeCoordinates):
    """What the MCMC walkers move: the direction's angle ``ψ`` (so that every proposal satisfies
    ``2 cxy² + cz² = 1``) and ``n`` itself."""

    @property
    def names(self) -> tuple[str, ...]:
        return ("psi", "n")

    @property
    def domains(self) -> tuple[Domain, ...]:
        return (Interval(-np.pi, np.pi), EXPONENT)

    def to_vector(self, shape) -> np.ndarray:
        return np.stack([angle_of_direction(shape["cxy"], shape["cz"]), np.asarray(shape["n"], dtype=float)])

    def from_vector(self, u):
        cxy, cz = direction_from_angle(u[0])
        return {"cxy": cxy, "cz": cz, "n": u[1]}


@final
@dataclass(frozen=True)
class LafortuneLobe(Lobe):
    """One generalised cosine lobe with direction ``(cxy, cz)`` and exponent ``n``."""

    summary = "(n+2)/(2π) · (cxy (wi_x wo_x + wi_y wo_y) + cz ci co)^n / max(|cxy|, |cz|)^n"

    #: The normalisation (n+2)/(2π) is exact only for cz = 1, so rho_s may exceed 1: published fits reach 1.71 (Ngan
    #: et al. 2005). Far beyond (the real tape's l2 fit put 8·10⁸ on a lobe whose peak no sample saw, fitting its
    #: tail) the lobe is degenerate: its albedo and exponent trade off, and the fit says so.
    albedo_domain = Positive(allow_zero=True, plausible_max=10.0)
    #: A lobe may point anywhere (forward, retro-reflective, towards the normal).
    peaks_at_mirror = False

    @property
    def parameters(self):
        return (("cxy", DirectionComponent()), ("cz", DirectionComponent()), ("n", EXPONENT))

    @property
    def unconstrained(self) -> ShapeCoordinates:
        return AngleAndLogExponent()

    @property
    def sampling(self) -> BoundedShapeCoordinates:
        return AngleAndExponent()

    @property
    def grid(self):
        shapes = []
        for psi in DIRECTION_GRID:
            cxy, cz = (float(x) for x in direction_from_angle(psi))
            shapes += [{"cxy": cxy, "cz": cz, "n": n} for n in EXPONENT_GRID]
        return tuple(shapes)

    def checked_shape(self, shape, where):
        """Check ``n`` and ``2 cxy² + cz² = 1`` (within 1%), and rescale ``(cxy, cz)`` onto it exactly."""
        if not EXPONENT.contains(shape["n"]):
            raise BrdfInputError(f"{where}n = {shape['n']!r} is outside its domain {EXPONENT.text}")
        cxy, cz = float(shape["cxy"]), float(shape["cz"])
        norm2 = 2.0 * cxy * cxy + cz * cz
        if not np.isfinite(norm2) or abs(norm2 - 1.0) > NORM_TOLERANCE:
            raise BrdfInputError(
                f"{where}cxy, cz must satisfy 2·cxy² + cz² = 1 (got {norm2:.4g}); the lobe depends only on"
                " their ratio, so divide both by sqrt(2·cxy² + cz²)"
            )
        scale = 1.0 / np.sqrt(norm2)
        return {"cxy": cxy * scale, "cz": cz * scale, "n": float(shape["n"])}

    def shape_holding(self, given, where):
        """``cxy`` alone gives ``cz = +sqrt(1 - 2 cxy²)`` (a lobe above the surface, forward or retro-reflective by
        the sign of ``cxy``); ``cz`` alone is refused, since it leaves that sign open."""
        shape = dict(self.grid[0]) | dict(given)
        if "cz" in given and "cxy" not in given:
            raise BrdfInputError(
                f"{where}cz alone leaves the lobe forward or retro-reflective; give {where}cxy instead"
                " (cz follows from 2·cxy² + cz² = 1)"
            )
        if "cxy" in given and "cz" not in given:
            cxy = float(given["cxy"])
            if not abs(cxy) <= 1.0 / np.sqrt(2.0) + 1e-12:  # ±1/√2 as a user writes it: cz = 0
                raise BrdfInputError(
                    f"{where}cxy = {cxy!r} is outside [-0.7071, 0.7071], where 2·cxy² + cz² = 1 leaves cz ≥ 0"
                )
            shape["cz"] = float(np.sqrt(max(0.0, 1.0 - 2.0 * cxy * cxy)))
        return self.checked_shape(shape, where)

    def canonical(self, shape):
        """A lobe's direction and exponent are one lobe each (``2 cxy² + cz² = 1`` fixes the rest)."""
        return dict(shape)

    def coordinate_index(self, name):
        """``cxy`` and ``cz`` are both the direction's angle ψ; ``n`` is ``ln n``'s or ``n``'s coordinate."""
        return {"cxy": 0, "cz": 0, "n": 1}[name]

    def __call__(self, shape, wi, wo):
        cxy, cz, n = shape["cxy"], shape["cz"], shape["n"]
        tangential = wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]
        base = (cxy * tangential + cz * wi[:, 2] * wo[:, 2]) / jnp.maximum(jnp.abs(cxy), jnp.abs(cz))
        return (n + 2.0) / (2.0 * jnp.pi) * safe_power(base, n)


@final
@dataclass(frozen=True)
class DirectionComponent(Domain):
    """The domain of ``cxy`` and ``cz``: within [-1, 1], and jointly ``2 cxy² + cz² = 1`` (checked by the lobe)."""

    @property
    def text(self) -> str:
        return "real, with 2·cxy² + cz² = 1"

    @property
    def bounds(self) -> tuple[float, float]:
        return -1.0, 1.0

    def contains(self, x) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(np.isfinite(x) & (np.abs(x) <= 1.0)))

    def log_prior(self, x):
        """Uniform on [-1, 1] (the walkers move ψ, never these)."""
        return jnp.where(jnp.abs(x) <= 1.0, 0.0, -jnp.inf)


def lafortune(lobes: int = 1) -> LobeModel:
    """``rho_d/π`` plus ``lobes`` generalised cosine lobes (default 1)."""
    lobes = whole_number("lobes", lobes, 1, MAX_LOBES)
    return LobeModel(
        "lafortune",
        "Lafortune 1997 generalised cosine lobes",
        LafortuneLobe(),
        lobes,
        options=(("lobes", lobes),),
        lobes_as_list=True,
    )


#: Compared with one to three lobes.
LAFORTUNE = ModelEntry(lafortune, compare=tuple(f"lafortune:lobes={lobes}" for lobes in (1, 2, 3)))
