"""Cook-Torrance microfacet lobe: Beckmann distribution, V-groove shadowing, Fresnel.

Cook & Torrance, "A reflectance model for computer graphics", ACM TOG 1982,
normalised as in Walter et al., "Microfacet models for refraction through
rough surfaces", EGSR 2007::

    lobe = F(cos β) · D · G / (4 ci co)
    D    = exp(-tan²θh / m²) / (π m² ch⁴)                     (Beckmann; m is the rms slope)
    G    = min(1, 2 ch co / (wo·h), 2 ch ci / (wo·h))       (V-groove, Torrance & Sparrow 1967)

It equals the V-groove model as it is often written, ``F/π · D'G/(ci co)``, with
``D' = exp(-tan²θh/m²)/(4 m² cos⁴θh)``. The Fresnel term is one of ``fresnel.FRESNEL``. With ``ks = 1`` and
``F = 1`` the lobe's directional albedo is at most 1.
"""

from dataclasses import dataclass
from typing import final

import jax.numpy as jnp

from ...checks import choice
from ..domains import ALBEDO, NON_NEGATIVE, ROUGHNESS, Domain
from ..fresnel import FRESNEL
from ..geometry import half_vector, tan2_from_cos
from .grids import ROUGHNESS_GRID
from .lobe import MappedLobe
from .model import Model


def beckmann_distribution(cos_theta_h, m):
    """Beckmann 1963 microfacet distribution ``exp(-tan²θh/m²) / (π m² cos⁴θh)``, in 1/sr."""
    cos2 = cos_theta_h * cos_theta_h
    return jnp.exp(-tan2_from_cos(cos_theta_h) / (m * m)) / (jnp.pi * m * m * cos2 * cos2)


def v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta):
    """Torrance-Sparrow V-groove masking-shadowing ``min(1, 2 ch co/(wo·h), 2 ch ci/(wo·h))``.

    ``cos_beta = wi·h = wo·h``.
    """
    return jnp.minimum(1.0, 2.0 * cos_theta_h * jnp.minimum(cos_i, cos_o) / cos_beta)


@final
@dataclass(frozen=True)
class CookTorranceLobe(MappedLobe):
    """Cook-Torrance lobe with rms slope ``m`` and the Fresnel term named by ``fresnel``."""

    fresnel: str = "schlick"

    def __post_init__(self):
        choice("fresnel", self.fresnel, FRESNEL, verb="is not known")

    @property
    def summary(self) -> str:
        return f"Beckmann D, V-groove G, {self.fresnel} Fresnel, F·D·G/(4 ci co)"

    @property
    def specular_domain(self) -> Domain:
        """``ks`` is the lobe's albedo without a Fresnel term; with one, ``ks·F`` is (Ngan et al. 2005: ks to 1.25)."""
        return ALBEDO if self.fresnel == "none" else NON_NEGATIVE

    @property
    def parameters(self):
        return (("m", ROUGHNESS), *((name, domain) for name, domain, _ in FRESNEL[self.fresnel].parameters))

    @property
    def grid(self):
        shapes = [{"m": m} for m in ROUGHNESS_GRID]
        for name, _, starts in FRESNEL[self.fresnel].parameters:
            shapes = [shape | {name: start} for shape in shapes for start in starts]
        return tuple(shapes)

    def __call__(self, shape, wi, wo):
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        h = half_vector(wi, wo)
        cos_theta_h = h[:, 2]
        cos_beta = jnp.sum(wi * h, axis=-1)
        distribution = beckmann_distribution(cos_theta_h, shape["m"])
        shadowing = v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta)
        fresnel = FRESNEL[self.fresnel].reflectance(cos_beta, shape)
        return fresnel * distribution * shadowing / (4.0 * cos_i * cos_o)


def cook_torrance(fresnel: str = "schlick") -> Model:
    """``kd/π + ks · F·D·G/(4 ci co)``; ``fresnel`` one of schlick (default), dielectric, conductor, none."""
    lobe = CookTorranceLobe(fresnel)
    return Model(
        "cook-torrance", "Cook-Torrance 1982 (Walter 2007 normalisation)", lobe, 1, "kd", "ks", (("fresnel", fresnel),)
    )
