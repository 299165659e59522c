"""glTF 2.0's metallic-roughness material as a fit model, ``gltf``: fitted, it exports to glTF unchanged.

The BRDF is the one a glTF viewer renders (``gltf.py``: the specification's Appendix B complete model,
``mix(dielectric_brdf, metal_brdf, metallic)``, GGX with height-correlated Smith, Schlick's Fresnel term), with
``KHR_materials_ior``'s index for the dielectric::

    f = (1 − metallic) · [(1 − F_d) · base_color/π + F_d · V·D] + metallic · (base_color + (1 − base_color) S) · V·D
    S = (1 − |V·H|)⁵,   F_d = f0 + (1 − f0) S,   f0 = ((1 − ior)/(1 + ior))²,   α = roughness²

Parameters: ``roughness`` and ``metallic`` in [0, 1]; ``ior`` > 1, held at glTF's 1.5 unless freed (``--free ior``:
``KHR_materials_ior``, for a dielectric whose reflectance at normal incidence is not 4%); ``base_color`` in [0, 1], one
per channel. The material is the whole BRDF: a whole-lobe model (``LobeModel.whole``), no albedos beside it.
"""

from dataclasses import dataclass
from typing import final

from ..domains import ALBEDO, UNIT_INTERVAL, Domain
from ..fresnel import FRESNEL
from ..models.lobe import MappedLobe
from ..models.model import LobeModel, ModelEntry
from .gltf import DEFAULT_IOR, ior_f0, material_brdf

#: The dielectric's index: a dielectric's Fresnel domain (``fresnel.py``), greater than 1.
IOR = dict((name, domain) for name, domain, _ in FRESNEL["dielectric"].parameters)["eta"]
#: Starting roughnesses (``α = roughness²`` from 0.0025 to 0.64, a factor of ~2 in ``α`` apart), metallic values
#: (off the ends of [0, 1], where the solver's logistic map has no slope) and grey base colours.
ROUGHNESS_STARTS = (0.05, 0.1, 0.15, 0.22, 0.3, 0.42, 0.6, 0.8)
METALLIC_STARTS = (0.02, 0.5, 0.98)
BASE_COLOR_STARTS = (0.05, 0.25, 0.7)


@final
@dataclass(frozen=True)
class GltfLobe(MappedLobe):
    """glTF's metallic-roughness BRDF as one lobe, the whole material (module docstring)."""

    @property
    def summary(self) -> str:
        return "glTF 2.0 metallic-roughness (Appendix B, height-correlated Smith GGX, Schlick)"

    peaks_at_mirror = True

    @property
    def albedo_domain(self) -> Domain:
        return ALBEDO  # a whole-lobe model has no albedo (LobeModel.whole)

    @property
    def parameters(self):
        return (("roughness", UNIT_INTERVAL), ("metallic", UNIT_INTERVAL), ("ior", IOR), ("base_color", UNIT_INTERVAL))

    channel_names = ("base_color",)
    meaningful_ends = ("metallic",)

    @property
    def grid(self):
        return tuple(
            {"roughness": roughness, "metallic": metallic, "ior": DEFAULT_IOR, "base_color": base}
            for roughness in ROUGHNESS_STARTS
            for metallic in METALLIC_STARTS
            for base in BASE_COLOR_STARTS
        )

    def __call__(self, shape, wi, wo):
        f0 = ior_f0(shape["ior"])
        return material_brdf(shape["base_color"], shape["metallic"], shape["roughness"], 1.0, f0, wi, wo)


def gltf() -> LobeModel:
    """glTF 2.0's metallic-roughness material (module docstring); ``ior`` held at 1.5 unless freed."""
    summary = "glTF 2.0 metallic-roughness material (KHR_materials_ior for the dielectric)"
    return LobeModel("gltf", summary, GltfLobe(), 1, held=(("ior", DEFAULT_IOR),), whole=True)


#: glTF's material in the registry: ``brdffit compare`` tries it; its glTF export is exact.
GLTF = ModelEntry(gltf, compare=("gltf",), exports={"gltf": "brdffit.export.gltf:gltf_of_gltf_fit"})
