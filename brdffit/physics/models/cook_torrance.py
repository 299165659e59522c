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

``anisotropic=True`` gives the anisotropic Beckmann or GGX distribution and its Smith ``Λ`` (Heitz, "Understanding
the masking-shadowing function in microfacet-based BRDFs", JCGT 2014): ``alpha_u`` along the tangent, ``alpha_v``
along the bitangent, the tangent at azimuth ``phi_t`` (degrees from ``+x``, in ``(−90, 90]``; the lobe is π-periodic
in it). ``(αu, αv, φt)`` and ``(αv, αu, φt ± 90°)`` are the same lobe: a fit reports the one with
``alpha_u ≤ alpha_v``, i.e. the tangent along the smoother direction (a brushed metal's grooves). The V-groove term,
which depends on the half vector alone, applies to it unchanged.
"""

from dataclasses import dataclass
from typing import Any, final

import numpy as np

from ..._jax import jnp
from ...checks import boolean, choice
from ..domains import ALBEDO, AXIS_AZIMUTH, NON_NEGATIVE, ROUGHNESS, Domain
from ..fresnel import FRESNEL
from ..geometry import half_vector, in_turned_frame
from ..metals import metal_grid
from ..microfacet import DISTRIBUTIONS, SHADOWING, anisotropic_shadowing, shadowing
from .grids import ROUGHNESS_GRID
from .lobe import MappedLobe, MappedShapeLobe
from .model import LobeModel, ModelEntry

#: The anisotropic lobe's starts: ``sqrt(αu αv)`` on the roughness grid, each with a round lobe and with these ratios
#: ``αv/αu`` (brushed metals: 2 to 10) at these tangent azimuths (degrees), 45° apart, so that the fit starts within
#: 22.5° of any tangent.
ANISOTROPY_RATIOS = (2.5, 6.0)
TANGENT_AZIMUTHS = (0.0, 45.0, 90.0, -45.0)


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
        return (("m", ROUGHNESS), *self.fresnel_parameters)

    @property
    def fresnel_parameters(self) -> tuple[tuple[str, Domain], ...]:
        """The Fresnel term's parameters (name, domain)."""
        return tuple((name, domain) for name, domain, _ in FRESNEL[self.fresnel].parameters)

    @property
    def grid(self):
        return self.with_fresnel_starts([{"m": m} for m in ROUGHNESS_GRID])

    def with_fresnel_starts(self, shapes: list[dict[str, float]]) -> tuple[dict[str, float], ...]:
        """Each of ``shapes`` with each of the Fresnel term's starting values, but those that reflect nothing.

        A conductor's ``eta = 1, k = 0`` is no interface: ``F = 0`` at every angle, the lobe is dead, and no
        parameter's derivative moves it. It is the model without its lobe, which the grid's race picked on the
        pickled-oak example (``ks`` held at 1: cost 8.717, Lambert's); without it the fit ends at 8.563, beside
        the 8.547 that starts at ``k = 10⁻³`` reach (``F`` has a zero at ``eta = 1``, ``k = 0``, which a channel
        started below 1 does not cross)."""
        for name, _, starts in FRESNEL[self.fresnel].parameters:
            shapes = [shape | {name: start} for shape in shapes for start in starts]
        if not shapes or not FRESNEL[self.fresnel].parameters:
            return tuple(shapes)
        stacked = {name: np.array([shape[name] for shape in shapes]) for name in shapes[0]}
        at_normal = np.broadcast_to(FRESNEL[self.fresnel].at_normal(stacked), (len(shapes),))  # numpy: never traced
        return tuple(shape for shape, reflects in zip(shapes, at_normal > 0.0, strict=True) if reflects)

    @property
    def channel_names(self) -> tuple[str, ...]:
        return FRESNEL[self.fresnel].per_channel

    def channel_grid(self, channels):
        """A conductor's measured metals (``metals.py``) in ``channels``, at every roughness of the grid."""
        if self.fresnel != "conductor":
            return ()
        return tuple({"m": m} | metal for m in ROUGHNESS_GRID for metal in metal_grid(channels))

    @property
    def separable(self) -> bool:
        """A conductor's lobe is ``F(cos β; eta, k)`` (N, C) times ``D·G/(4 ci co)`` (N,), and ``cos β`` depends on
        the directions alone."""
        return bool(self.channel_names)

    def shared_factor(self, shape, wi, wo):
        """``D·G/(4 ci co)`` (N,): the lobe without its Fresnel term."""
        return self._unit_and_cos_beta(shape, wi, wo)[0]

    def channel_factor(self, shape, wi, wo):
        """The Fresnel term ``F(cos β)`` (N, C) of an index per channel."""
        return self.fresnel_term(cos_beta(wi, half_vector(wi, wo)), shape)

    def __call__(self, shape, wi, wo):
        unit, cosine = self._unit_and_cos_beta(shape, wi, wo)
        return self.fresnel_term(cosine, shape) * (unit[:, None] if self.channel_names else unit)  # (N, C) or (N,)

    def fresnel_term(self, cosine, shape):
        """``F(cos β)`` at ``cosine`` (N,): (N, C) for an index per channel (:attr:`channel_names`: one lobe per
        channel), else (N,)."""
        if self.channel_names:
            return FRESNEL[self.fresnel].reflectance(cosine[:, None], shape)
        return FRESNEL[self.fresnel].reflectance(cosine, shape)

    def _unit_and_cos_beta(self, shape, wi, wo):
        """``D·G/(4 ci co)`` (N,) and ``cos β`` (N,), which the Fresnel term takes (one half vector for both: the lobe
        is evaluated in every step of a fit)."""
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        h = half_vector(wi, wo)
        cos_theta_h = h[:, 2]
        cosine = cos_beta(wi, h)
        distribution = DISTRIBUTIONS[self.distribution]
        masking = shadowing(self.shadowing, distribution, shape["m"], cos_i, cos_o, cos_theta_h, cosine)
        return distribution.density(cos_theta_h, shape["m"]) * masking / (4.0 * cos_i * cos_o), cosine


def cos_beta(wi, h):
    """``cos β = wi·h`` (N,) of directions ``wi`` and their half vectors ``h`` (N, 3), the cosine a Fresnel term takes:
    the same in every frame turned about the normal."""
    return jnp.sum(wi * h, axis=-1)


@final
@dataclass(frozen=True)
class AnisotropicCookTorranceLobe(MappedShapeLobe):
    """Cook-Torrance lobe with the anisotropic distribution (Heitz 2014) of the kind ``terms`` names, with its
    shadowing and Fresnel terms: roughness ``alpha_u`` along the tangent at azimuth ``phi_t`` (degrees from ``+x``),
    ``alpha_v`` along the bitangent (module docstring)."""

    terms: CookTorranceLobe = CookTorranceLobe()

    @property
    def summary(self) -> str:
        return f"anisotropic {self.terms.summary}, α_u along the tangent at azimuth φ_t, α_v across it"

    peaks_at_mirror = True

    @property
    def albedo_domain(self) -> Domain:
        return self.terms.albedo_domain

    @property
    def parameters(self):
        return (("alpha_u", ROUGHNESS), ("alpha_v", ROUGHNESS), ("phi_t", AXIS_AZIMUTH), *self.terms.fresnel_parameters)

    @property
    def grid(self):
        shapes = [{"alpha_u": m, "alpha_v": m, "phi_t": 0.0} for m in ROUGHNESS_GRID]
        shapes += [
            {"alpha_u": m / np.sqrt(ratio), "alpha_v": m * np.sqrt(ratio), "phi_t": azimuth}
            for m in ROUGHNESS_GRID
            for ratio in ANISOTROPY_RATIOS
            for azimuth in TANGENT_AZIMUTHS
        ]
        # Not a conductor's k = 0 starts (dielectric-like interfaces, for non-metals): k cannot leave 0 from there
        # (its log map's slope is 1e-12), and raced against the metals' starts from a grid shape off the truth they
        # won, at a local minimum, in 4 of 20 noiseless brushed-gold fits (0 of 20 without them). A brushed
        # non-metal takes fresnel="dielectric".
        return tuple(shape for shape in self.terms.with_fresnel_starts(shapes) if shape.get("k", 1.0) > 0.0)

    @property
    def channel_names(self) -> tuple[str, ...]:
        return self.terms.channel_names

    def channel_grid(self, channels):
        """A conductor's measured metals (``metals.py``) in ``channels``, on round lobes of the roughness grid (the
        scalar grid's anisotropic shapes find the tangent)."""
        return tuple(
            {"alpha_u": shape["m"], "alpha_v": shape["m"], "phi_t": 0.0} | {k: v for k, v in shape.items() if k != "m"}
            for shape in self.terms.channel_grid(channels)
        )

    def canonical(self, shape):
        """The twin with ``alpha_u ≤ alpha_v``: where ``alpha_u > alpha_v`` the two are exchanged and the tangent
        turned by 90° (the same lobe)."""
        alpha_u, alpha_v, phi_t = (np.asarray(shape[name], dtype=float) for name in ("alpha_u", "alpha_v", "phi_t"))
        swap = alpha_u > alpha_v
        turned = np.where(swap, AXIS_AZIMUTH.wrapped(phi_t + 90.0), phi_t)
        return dict(shape) | {
            "alpha_u": np.minimum(alpha_u, alpha_v),
            "alpha_v": np.maximum(alpha_u, alpha_v),
            "phi_t": turned,
        }

    @property
    def separable(self) -> bool:
        """As the isotropic lobe's (``CookTorranceLobe.separable``): ``cos β`` is the same in the tangent frame."""
        return self.terms.separable

    def shared_factor(self, shape, wi, wo):
        """``D·G/(4 ci co)`` (N,) in the tangent frame: the lobe without its Fresnel term."""
        return self._unit_and_cos_beta(shape, wi, wo)[0]

    def channel_factor(self, shape, wi, wo):
        """The Fresnel term ``F(cos β)`` (N, C) of an index per channel (``CookTorranceLobe.channel_factor``)."""
        return self.terms.channel_factor(shape, wi, wo)

    def __call__(self, shape, wi, wo):
        unit, cosine = self._unit_and_cos_beta(shape, wi, wo)
        return self.terms.fresnel_term(cosine, shape) * (unit[:, None] if self.channel_names else unit)

    def _unit_and_cos_beta(self, shape, wi, wo):
        """``D·G/(4 ci co)`` (N,) and ``cos β`` (N,) (``CookTorranceLobe._unit_and_cos_beta``), in the tangent frame."""
        alpha_u, alpha_v = shape["alpha_u"], shape["alpha_v"]
        azimuth = jnp.radians(shape["phi_t"])
        wi, wo = in_turned_frame(wi, azimuth), in_turned_frame(wo, azimuth)  # the tangent frame
        h = half_vector(wi, wo)
        cosine = cos_beta(wi, h)
        distribution = DISTRIBUTIONS[self.terms.distribution]
        density = distribution.anisotropic_density(h[:, 0], h[:, 1], h[:, 2], alpha_u, alpha_v)
        masking = anisotropic_shadowing(self.terms.shadowing, distribution, alpha_u, alpha_v, wi, wo, h[:, 2], cosine)
        return density * masking / (4.0 * wi[:, 2] * wo[:, 2]), cosine


def cook_torrance(
    fresnel: str = "schlick", distribution: str = "beckmann", shadowing: str = "v-groove", anisotropic: bool = False
) -> LobeModel:
    """``kd/π + ks · F·D·G/(4 ci co)``; ``fresnel`` one of schlick (default), dielectric, conductor, none;
    ``distribution`` beckmann (default) or ggx; ``shadowing`` v-groove (default), smith or smith-correlated;
    ``anisotropic``: roughness ``alpha_u``, ``alpha_v`` and the tangent's azimuth ``phi_t`` in place of ``m`` (True,
    or ``"true"`` as a spec writes it; default False)."""
    anisotropic = boolean("anisotropic", anisotropic)
    lobe = CookTorranceLobe(fresnel, distribution, shadowing)
    options: tuple[tuple[str, Any], ...] = (
        ("fresnel", fresnel),
        ("distribution", distribution),
        ("shadowing", shadowing),
    )
    options += (("anisotropic", anisotropic),)
    # A conductor's reflectance is its Fresnel term: ks is held at 1 unless a user frees it (docs/holding.md).
    held = (("ks", 1.0),) if fresnel == "conductor" else ()
    summary = "Cook-Torrance 1982 (Walter 2007 normalisation)"
    if anisotropic:
        summary += ", anisotropic (Heitz 2014)"
        family = AnisotropicCookTorranceLobe(lobe)
        return LobeModel("cook-torrance", summary, family, 1, "kd", "ks", options, isotropic=False, held=held)
    return LobeModel("cook-torrance", summary, lobe, 1, "kd", "ks", options, held=held)


#: The microfacet model renderers implement (GGX with Smith shadowing: Mitsuba's ``roughconductor``, glTF's
#: lobe), which ``brdffit compare`` tries beside Cook and Torrance's own, with a conductor's and a dielectric's
#: Fresnel term: each exports to Mitsuba exactly.
RENDERER_OPTIONS = ("distribution=ggx", "shadowing=smith")

#: Cook-Torrance in the registry: compared with each Fresnel term (the conductor with Smith shadowing: Mitsuba's
#: default ``roughconductor``, Beckmann and Smith, which a measured metal is most often rendered with), and as the
#: renderers' microfacet model (:data:`RENDERER_OPTIONS`); exact in Mitsuba with Smith shadowing and a conductor,
#: dielectric or no Fresnel term (``brdffit/export/mitsuba.py``).
COOK_TORRANCE = ModelEntry(
    cook_torrance,
    compare=(
        *(f"cook-torrance:fresnel={kind}" + (",shadowing=smith" if kind == "conductor" else "") for kind in FRESNEL),
        *(f"cook-torrance:fresnel={kind},{','.join(RENDERER_OPTIONS)}" for kind in ("conductor", "dielectric")),
        # A brushed metal: Mitsuba's anisotropic roughconductor, which no isotropic candidate follows (a brushed
        # silver's best isotropic fit lies 25 times off at the median pair; this one 0.8%).
        f"cook-torrance:fresnel=conductor,{','.join(RENDERER_OPTIONS)},anisotropic=true",
    ),
    choices={
        "distribution": {name: kind.summary for name, kind in DISTRIBUTIONS.items()},
        "shadowing": dict(SHADOWING),
        "fresnel": {name: kind.summary for name, kind in FRESNEL.items()},
        "anisotropic": {
            "false": "isotropic, roughness m",
            "true": "anisotropic, Heitz 2014: alpha_u along the tangent at azimuth phi_t, alpha_v across it",
        },
    },
    exports={"mitsuba": "brdffit.export.mitsuba:cook_torrance_bsdf"},
)
