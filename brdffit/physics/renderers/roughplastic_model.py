"""Mitsuba 3's ``roughplastic`` BSDF as a fit model, ``roughplastic``: fitted, it exports to Mitsuba unchanged.

The BRDF is Mitsuba's own (``roughplastic.py``): a diffuse base under a rough dielectric coating,
``ks · F D G1 G1/(4 ci co) + kd/(1 − Ri(α)) · T(α, ci) T(α, co)/(π η²)``, with Mitsuba's precomputed rough
transmittance ``T`` and internal reflectance ``Ri`` tabulated over ``α``. Parameters, named as Mitsuba names them:
``alpha`` (the coating's roughness), ``diffuse_reflectance`` and ``specular_reflectance`` (in [0, 1], one per
channel; the latter held at Mitsuba's 1 unless freed: "for physical realism, this parameter should never be
touched", Mitsuba's documentation). Options: ``distribution`` (``beckmann``, Mitsuba's default, or ``ggx``) and
``int_ior`` (the coating's index, Mitsuba's 1.49 by default, whose tables ship; another's are computed once a
process, ~2.5 s). The material is the whole BRDF: a whole-lobe model (``LobeModel.whole``), no albedos beside it.
"""

import math
from dataclasses import dataclass
from typing import final

from ...checks import choice
from ...errors import Argument, BrdfInputError
from ..domains import ROUGHNESS, UNIT_INTERVAL
from ..models.grids import BASE_COLOR_STARTS, ROUGHNESS_GRID
from ..models.lobe import WholeLobe
from ..models.model import LobeModel, ModelEntry
from .roughplastic import DEFAULT_INT_IOR, EXT_IOR, roughplastic_brdf

#: Mitsuba's distributions for the coating.
DISTRIBUTIONS = {"beckmann": "Beckmann (Mitsuba's default)", "ggx": "GGX (Trowbridge-Reitz)"}


@final
@dataclass(frozen=True)
class RoughPlasticLobe(WholeLobe):
    """Mitsuba's ``roughplastic`` BRDF as one lobe, the whole material (module docstring)."""

    distribution: str = "beckmann"
    int_ior: float = DEFAULT_INT_IOR

    def __post_init__(self):
        choice("distribution", self.distribution, DISTRIBUTIONS, verb="is not known")

    @property
    def summary(self) -> str:
        return f"Mitsuba 3 roughplastic ({self.distribution}, int_ior {self.int_ior:g}): a coated diffuse base"

    peaks_at_mirror = True
    channel_names = ("diffuse_reflectance", "specular_reflectance")
    fusion_emitters = True  # a fit's steps take half the time so (``_programs/jit.py``)

    @property
    def parameters(self):
        return (
            ("alpha", ROUGHNESS),
            ("diffuse_reflectance", UNIT_INTERVAL),
            ("specular_reflectance", UNIT_INTERVAL),
        )

    @property
    def grid(self):
        return tuple(
            {"alpha": alpha, "diffuse_reflectance": base, "specular_reflectance": 1.0}
            for alpha in ROUGHNESS_GRID
            for base in BASE_COLOR_STARTS
        )

    def __call__(self, shape, wi, wo):
        return roughplastic_brdf(shape, wi, wo, distribution=self.distribution, int_ior=self.int_ior, ext_ior=EXT_IOR)


def roughplastic(distribution: str = "beckmann", int_ior: float = DEFAULT_INT_IOR) -> LobeModel:
    """Mitsuba 3's ``roughplastic`` material (module docstring); ``specular_reflectance`` held at 1 unless freed."""
    try:
        index = float(int_ior) if not isinstance(int_ior, bool) else math.nan
    except (TypeError, ValueError):
        index = math.nan
    if not (math.isfinite(index) and index > EXT_IOR):
        raise BrdfInputError(Argument("int_ior", int_ior), f" must be a number above the air's {EXT_IOR}")
    lobe = RoughPlasticLobe(distribution, index)
    options = (("distribution", distribution), ("int_ior", index))
    summary = "Mitsuba 3 roughplastic BSDF (nonlinear=false)"
    return LobeModel(
        "roughplastic", summary, lobe, 1, options=options, held=(("specular_reflectance", 1.0),), whole=True
    )


#: Mitsuba's rough plastic in the registry: ``brdffit compare`` tries both distributions; its Mitsuba export is exact.
ROUGHPLASTIC = ModelEntry(
    roughplastic,
    compare=("roughplastic", "roughplastic:distribution=ggx"),
    choices={"distribution": DISTRIBUTIONS},
    exports={"mitsuba": "brdffit.export.mitsuba:roughplastic_bsdf"},
)
