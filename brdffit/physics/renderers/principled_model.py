"""Mitsuba 3's ``principled`` BSDF as a fit model, ``principled``: fitted, it exports to Mitsuba unchanged.

The BRDF is Mitsuba's own, reflection only (``principled.py``: Burley's diffuse with
retro-reflection, sheen, anisotropic GGX specular with Mitsuba's Fresnel blend, and a GTR1 clear coat), with its
documented parameters, each in [0, 1]: ``roughness``, ``metallic``, ``specular`` (the dielectric's index,
``η = 2/(1 − sqrt(0.08 specular)) − 1``), ``clearcoat``, ``clearcoat_gloss``, ``spec_tint``, ``sheen``,
``sheen_tint``, ``anisotropic`` (``alpha_u`` along the surface's tangent, ``+x`` of the data), and ``base_color``, one
per channel (r, g, b, or one grey channel: the tints need the colour's luminance).

What one measurement determines is fitted: ``base_color``, ``roughness``, ``metallic``, ``specular``, ``clearcoat``
and ``clearcoat_gloss``. The rest are held at Mitsuba's defaults (0) unless freed (``--free sheen``): a sheen, a
tint or an anisotropy is seldom told apart from the others by a gonioreflectometer's few planes. The material is the
whole BRDF: a whole-lobe model (``LobeModel.whole``), no albedos beside it.
"""

from dataclasses import dataclass
from typing import final

from ..domains import UNIT_INTERVAL
from ..models.grids import BASE_COLOR_STARTS, METALLIC_STARTS, ROUGHNESS_STARTS
from ..models.lobe import WholeLobe
from ..models.model import LobeModel, ModelEntry
from .principled import DEFAULTS, principled_brdf

#: The parameters held at Mitsuba's default unless a user frees them (module docstring).
HELD = ("spec_tint", "sheen", "sheen_tint", "anisotropic")
#: Starting clear coats: none (off the end of [0, 1], where the logistic map has no slope) and a half-strength
#: glossy one.
CLEARCOAT_STARTS = ((0.02, 0.5), (0.5, 0.8))


@final
@dataclass(frozen=True)
class PrincipledLobe(WholeLobe):
    """Mitsuba's ``principled`` BRDF as one lobe, the whole material (module docstring)."""

    @property
    def summary(self) -> str:
        return "Mitsuba 3 principled (Burley 2012/2015): diffuse + retro-reflection, sheen, GGX specular, GTR1 coat"

    peaks_at_mirror = True
    channel_names = ("base_color",)
    channels_coupled = True  # the tints: base_color over its luminance
    anisotropy_names = ("anisotropic",)  # held at 0 (isotropic) unless freed: then checked as anisotropic
    meaningful_ends = ("metallic", "clearcoat", "clearcoat_gloss", "spec_tint", "sheen", "sheen_tint", "anisotropic")

    @property
    def parameters(self):
        scalars = [name for name in DEFAULTS if name != "base_color"]  # the per-channel one last (Lobe.channel_names)
        return tuple((name, UNIT_INTERVAL) for name in [*scalars, "base_color"])

    @property
    def grid(self):
        held = {name: DEFAULTS[name] for name in HELD}
        return tuple(
            {"roughness": roughness, "metallic": metallic, "specular": DEFAULTS["specular"], "base_color": base}
            | {"clearcoat": clearcoat, "clearcoat_gloss": gloss}
            | held
            for roughness in ROUGHNESS_STARTS
            for metallic in METALLIC_STARTS
            for base in BASE_COLOR_STARTS
            for clearcoat, gloss in CLEARCOAT_STARTS
        )

    def __call__(self, shape, wi, wo):
        return principled_brdf(shape, wi, wo)


def principled() -> LobeModel:
    """Mitsuba 3's ``principled`` material (module docstring); ``spec_tint``, ``sheen``, ``sheen_tint`` and
    ``anisotropic`` held at 0 unless freed."""
    summary = "Mitsuba 3 principled BSDF, reflection only"
    held = tuple((name, float(DEFAULTS[name])) for name in HELD)
    return LobeModel("principled", summary, PrincipledLobe(), 1, held=held, whole=True, isotropic=True)


#: Mitsuba's principled material in the registry: ``brdffit compare`` tries it; its Mitsuba export is exact.
PRINCIPLED = ModelEntry(
    principled, compare=("principled",), exports={"mitsuba": "brdffit.export.mitsuba:principled_bsdf"}
)
