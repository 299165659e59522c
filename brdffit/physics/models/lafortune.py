"""Lafortune's generalised cosine lobes.

Lafortune, Foo, Torrance & Greenberg, "Non-linear approximation of reflectance
functions", SIGGRAPH 1997, isotropic form (``C_x = C_y = cxy``), with the
normalisation Ngan et al. 2005 fit (SPEC section 2)::

    lobe = (n+2)/(2π) · max(0, (cxy (wi_x wo_x + wi_y wo_y) + cz ci co) / max(|cxy|, |cz|))^n

The ratio form makes the lobe independent of the length of ``(cxy, cz)``; SPEC
fixes that length by ``2 cxy² + cz² = 1``, so a lobe's direction is one angle
``ψ`` with ``cxy = sin ψ / √2``, ``cz = cos ψ``, which is what the fit moves.
``cxy < 0`` is a forward (specular) lobe, ``cxy > 0`` a retro-reflective one.
Since ``|cxy·a + cz·b| ≤ max(|cxy|, |cz|)·(|a| + |b|) ≤ max(|cxy|, |cz|)``
for unit directions, the base is at most 1 and ``n`` of 10⁴ stays finite.
"""

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from ... import _jax  # noqa: F401  (float64 before any array)
from ...checks import whole_number
from ...errors import BrdfInputError
from ..domains import POSITIVE, Interval
from ..geometry import safe_power
from .base import Lobe, Model
from .grids import EXPONENT_GRID

#: The most lobes ``--lobes`` accepts; more than a handful cannot be told apart by any measurement.
MAX_LOBES = 8

#: How far ``2 cxy² + cz²`` may be from 1 in a user's parameters (published tables round to 3 digits).
NORM_TOLERANCE = 0.01

#: Lobe directions ψ to start from: forward (cxy = -cz), flatter and steeper forward, normal, retro.
_FORWARD = float(np.arctan2(-np.sqrt(2.0), 1.0))
DIRECTION_GRID = (_FORWARD, -1.25, -0.6, 0.0, -_FORWARD)


def direction_from_angle(psi):
    """``(cxy, cz) = (sin ψ / √2, cos ψ)``, which satisfies ``2 cxy² + cz² = 1``."""
    return jnp.sin(psi) / jnp.sqrt(2.0), jnp.cos(psi)


@dataclass(frozen=True)
class LafortuneLobe(Lobe):
    """One generalised cosine lobe with direction ``(cxy, cz)`` and exponent ``n``."""

    summary = "(n+2)/(2π) · (cxy (wi_x wo_x + wi_y wo_y) + cz ci co)^n / max(|cxy|, |cz|)^n"

    @property
    def parameters(self):
        return (("cxy", _DirectionComponent()), ("cz", _DirectionComponent()), ("n", POSITIVE))

    @property
    def unconstrained_names(self):
        return ("psi", "n")

    @property
    def n_unconstrained(self) -> int:
        return 2

    @property
    def grid(self):
        shapes = []
        for psi in DIRECTION_GRID:
            cxy, cz = (float(x) for x in direction_from_angle(psi))
            shapes += [{"cxy": cxy, "cz": cz, "n": n} for n in EXPONENT_GRID]
        return tuple(shapes)

    def shape_to_unconstrained(self, shape):
        psi = np.arctan2(np.sqrt(2.0) * shape["cxy"], shape["cz"])
        return np.array([psi, POSITIVE.to_unconstrained(shape["n"])])

    def shape_from_unconstrained(self, u):
        cxy, cz = direction_from_angle(u[0])
        return {"cxy": cxy, "cz": cz, "n": POSITIVE.to_physical(u[1])}

    @property
    def sampling_parameters(self):
        # The walkers move the direction's angle, so every proposal satisfies 2 cxy² + cz² = 1.
        return (("psi", Interval(-np.pi, np.pi)), ("n", POSITIVE))

    def shape_to_sampling(self, shape):
        return np.array([np.arctan2(np.sqrt(2.0) * shape["cxy"], shape["cz"]), float(shape["n"])])

    def shape_from_sampling(self, values):
        cxy, cz = direction_from_angle(values[0])
        return {"cxy": cxy, "cz": cz, "n": values[1]}

    def checked_shape(self, shape, where):
        """Check ``n`` and ``2 cxy² + cz² = 1`` (within 1%), and rescale ``(cxy, cz)`` onto it exactly."""
        if not POSITIVE.contains(shape["n"]):
            raise BrdfInputError(f"{where}n = {shape['n']!r} is outside its domain {POSITIVE.text}")
        cxy, cz = float(shape["cxy"]), float(shape["cz"])
        norm2 = 2.0 * cxy * cxy + cz * cz
        if not np.isfinite(norm2) or abs(norm2 - 1.0) > NORM_TOLERANCE:
            raise BrdfInputError(
                f"{where}cxy, cz must satisfy 2·cxy² + cz² = 1 (got {norm2:.4g}); the lobe depends only on"
                " their ratio, so divide both by sqrt(2·cxy² + cz²)"
            )
        scale = 1.0 / np.sqrt(norm2)
        return {"cxy": cxy * scale, "cz": cz * scale, "n": float(shape["n"])}

    def __call__(self, shape, wi, wo):
        cxy, cz, n = shape["cxy"], shape["cz"], shape["n"]
        tangential = wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]
        base = (cxy * tangential + cz * wi[:, 2] * wo[:, 2]) / jnp.maximum(jnp.abs(cxy), jnp.abs(cz))
        return (n + 2.0) / (2.0 * jnp.pi) * safe_power(base, n)


@dataclass(frozen=True)
class _DirectionComponent:
    """Domain text for ``cxy`` and ``cz``; the joint constraint is checked by the lobe."""

    text: str = "real, with 2·cxy² + cz² = 1"

    @property
    def bounds(self) -> tuple[float, float]:
        return -1.0, 1.0


def lafortune(lobes: int = 1) -> Model:
    """``rho_d/π`` plus ``lobes`` generalised cosine lobes (default 1)."""
    lobes = whole_number("--lobes", lobes, 1, MAX_LOBES)
    return Model(
        "lafortune",
        "Lafortune 1997 generalised cosine lobes",
        LafortuneLobe(),
        lobes,
        options=(("lobes", lobes),),
        lobes_as_list=True,
    )
