"""Cook-Torrance microfacet lobe: a distribution, a masking-shadowing term and a Fresnel term.

Cook & Torrance, "A reflectance model for computer graphics", ACM TOG 1982, normalised as in Walter et al.,
"Microfacet models for refraction through rough surfaces", EGSR 2007::

    lobe = F(cos β) · D · G / (4 ci co)

with ``D`` and ``G`` of ``microfacet.py`` and ``F`` of ``fresnel.py``. The defaults are Cook and Torrance's own:
Beckmann's ``D = exp(-tan²θh / m²) / (π m² ch⁴)`` (``m`` the rms slope) and the V-groove
``G = min(1, 2 ch co / (wo·h), 2 ch ci / (wo·h))`` (Torrance & Sparrow 1967), which equal the form often written
``F/π · D'G/(ci co)`` with ``D' = exp(-tan²θh/m²)/(4 m² cos⁴θh)``. ``distribution="ggx"`` and
``shadowing="smith"`` / ``"smith-correlated"`` give the microfacet models renderers implement (Mitsuba's
``roughconductor`` is GGX or Beckmann with separable Smith; glTF's is GGX with height-correlated Smith); ``m`` is
then GGX's ``α``. With ``ks = 1`` and ``F = 1`` the lobe's directional albedo is at most 1.
"""

from dataclasses import dataclass
from typing import final

from ..._jax import jnp
from ...checks import choice
from ..domains import ALBEDO, NON_NEGATIVE, ROUGHNESS, Domain
from ..fresnel import FRESNEL
from ..geometry import half_vector
from ..metals import metal_grid
from ..microfacet import DISTRIBUTIONS, SHADOWING, shadowing
from .grids import ROUGHNESS_GRID
from .lobe import MappedLobe
from .model import LobeModel, ModelEntry


@final
@dataclass(frozen=True)
class CookTorranceLobe(MappedLobe):
    """Cook-Torrance lobe with roughness ``m``, the ``distribution``, ``shadowing`` and ``fresnel`` terms named."""

    fresnel: str = "schlick"
    distribution: str = "beckmann"
    shadowing: str = "v-groove"

    def __post_init__(self):
        choice("fresnel", self.fresnel, FRESNEL, verb="is not known")
        choice("distribution", self.distribution, DISTRIBUTIONS, verb="is not known")
        choice("shadowing", self.shadowing, SHADOWING, verb="is not known")

    @property
    def summary(self) -> str:
        distribution = DISTRIBUTIONS[self.distribution].summary
        return f"{distribution} D, {SHADOWING[self.shadowing]} G, {self.fresnel} Fresnel, F·D·G/(4 ci co)"

    peaks_at_mirror = True

    @property
    def albedo_domain(self) -> Domain:
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

    @property
    def channel_names(self) -> tuple[str, ...]:
        return FRESNEL[self.fresnel].per_channel

    def channel_grid(self, channels):
        """A conductor's measured metals (``metals.py``) in ``channels``, at every roughness of the grid."""
        if self.fresnel != "conductor":
            return ()
        return tuple({"m": m} | metal for m in ROUGHNESS_GRID for metal in metal_grid(channels))

    def __call__(self, shape, wi, wo):
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        h = half_vector(wi, wo)
        cos_theta_h = h[:, 2]
        cos_beta = jnp.sum(wi * h, axis=-1)
        distribution = DISTRIBUTIONS[self.distribution]
        masking = shadowing(self.shadowing, distribution, shape["m"], cos_i, cos_o, cos_theta_h, cos_beta)
        unit = distribution.density(cos_theta_h, shape["m"]) * masking / (4.0 * cos_i * cos_o)
        if self.channel_names:  # an index per channel: F (N, C), one lobe per channel
            return FRESNEL[self.fresnel].reflectance(cos_beta[:, None], shape) * unit[:, None]
        return FRESNEL[self.fresnel].reflectance(cos_beta, shape) * unit


def cook_torrance(fresnel: str = "schlick", distribution: str = "beckmann", shadowing: str = "v-groove") -> LobeModel:
    """``kd/π + ks · F·D·G/(4 ci co)``; ``fresnel`` one of schlick (default), dielectric, conductor, none;
    ``distribution`` beckmann (default) or ggx; ``shadowing`` v-groove (default), smith or smith-correlated."""
    lobe = CookTorranceLobe(fresnel, distribution, shadowing)
    options = (("fresnel", fresnel), ("distribution", distribution), ("shadowing", shadowing))
    # A conductor's reflectance is its Fresnel term: ks is held at 1 unless a user frees it (docs/holding.md).
    held = (("ks", 1.0),) if fresnel == "conductor" else ()
    summary = "Cook-Torrance 1982 (Walter 2007 normalisation)"
    return LobeModel("cook-torrance", summary, lobe, 1, "kd", "ks", options, held=held)


#: The microfacet model renderers implement (GGX with Smith shadowing: Mitsuba's ``roughconductor``, glTF's
#: lobe), which ``brdffit compare`` tries beside Cook and Torrance's own, with a conductor's and a dielectric's
#: Fresnel term: each exports to Mitsuba exactly.
RENDERER_OPTIONS = ("distribution=ggx", "shadowing=smith")

#: Cook-Torrance in the registry: compared with each Fresnel term, and as the renderers' microfacet model
#: (:data:`RENDERER_OPTIONS`); exact in Mitsuba with Smith shadowing and a conductor, dielectric or no Fresnel term
#: (``brdffit/export/mitsuba.py``).
COOK_TORRANCE = ModelEntry(
    cook_torrance,
    compare=(
        *(f"cook-torrance:fresnel={kind}" for kind in FRESNEL),
        *(f"cook-torrance:fresnel={kind},{','.join(RENDERER_OPTIONS)}" for kind in ("conductor", "dielectric")),
    ),
    choices={
        "distribution": {name: kind.summary for name, kind in DISTRIBUTIONS.items()},
        "shadowing": dict(SHADOWING),
        "fresnel": {name: kind.summary for name, kind in FRESNEL.items()},
    },
    exports={"mitsuba": "brdffit.export.mitsuba:cook_torrance_bsdf"},
)
