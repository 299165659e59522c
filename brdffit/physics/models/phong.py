"""Phong-type cosine-power lobes, energy-normalised.

``phong`` is the modified Phong model of Lewis, "Making shaders more physically
plausible", CGF 1994 (the mirror-direction lobe Ngan et al. 2005 fit);
``blinn-phong`` is Blinn's half-vector variant, "Models of light reflection for
computer synthesized pictures", SIGGRAPH 1977, with the ``(n+8)/(8π)``
normalisation of Akenine-Möller et al., *Real-Time Rendering*::

    phong        rho_s · (n+2)/(2π) · max(0, r·wo)^n,  r = (-wi_x, -wi_y, wi_z)
    blinn-phong  rho_s · (n+8)/(8π) · ch^n
"""

from dataclasses import dataclass
from typing import final

from ..._jax import jnp
from ..domains import ALBEDO, EXPONENT
from ..geometry import half_vector, mirror_direction, safe_power
from .grids import EXPONENT_GRID
from .lobe import MappedLobe
from .model import LobeModel, ModelEntry


@final
@dataclass(frozen=True)
class PhongLobe(MappedLobe):
    """Cosine power ``n`` of the angle between ``wo`` and the mirror direction of ``wi``."""

    summary = "(n+2)/(2π) · max(0, r·wo)^n around the mirror direction r"

    albedo_domain = ALBEDO
    peaks_at_mirror = True

    @property
    def parameters(self):
        return (("n", EXPONENT),)

    @property
    def grid(self):
        return tuple({"n": n} for n in EXPONENT_GRID)

    def __call__(self, shape, wi, wo):
        n = shape["n"]
        cos_alpha = jnp.sum(mirror_direction(wi) * wo, axis=-1)
        return (n + 2.0) / (2.0 * jnp.pi) * safe_power(cos_alpha, n)


@final
@dataclass(frozen=True)
class BlinnPhongLobe(MappedLobe):
    """Cosine power ``n`` of the half-vector's zenith angle."""

    summary = "(n+8)/(8π) · ch^n around the normal, in the half vector"

    albedo_domain = ALBEDO
    peaks_at_mirror = True

    @property
    def parameters(self):
        return (("n", EXPONENT),)

    @property
    def grid(self):
        return tuple({"n": n} for n in EXPONENT_GRID)

    def __call__(self, shape, wi, wo):
        n = shape["n"]
        return (n + 8.0) / (8.0 * jnp.pi) * safe_power(half_vector(wi, wo)[:, 2], n)


def phong() -> LobeModel:
    return LobeModel("phong", "modified Phong (Lewis 1994), mirror-direction lobe", PhongLobe(), 1)


def blinn_phong() -> LobeModel:
    return LobeModel("blinn-phong", "normalised Blinn-Phong (Blinn 1977), half-vector lobe", BlinnPhongLobe(), 1)


PHONG = ModelEntry(phong, compare=("phong",))
BLINN_PHONG = ModelEntry(blinn_phong, compare=("blinn-phong",))
