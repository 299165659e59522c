"""glTF 2.0's metallic-roughness material as a fit model, ``gltf``: fitted, it exports to glTF unchanged.

The BRDF is the one a glTF viewer renders (``gltf.py``: the specification's Appendix B complete model,
``mix(dielectric_brdf, metal_brdf, metallic)``, GGX with height-correlated Smith, Schlick's Fresnel term), with
``KHR_materials_ior``'s index for the dielectric, ``KHR_materials_clearcoat``'s coat over it and
``KHR_materials_anisotropy``'s stretched lobe and ``KHR_materials_sheen``'s sheen, each as the Khronos glTF Sample
Viewer evaluates it::

    f = (1 − clearcoat · F_c) · s + clearcoat · F_c · V_c·D_c
    s = sheen_color · D_s·V_s + min(1 − max(sheen_color) E(N·V), 1 − max(sheen_color) E(N·L)) · m
    m = (1 − metallic) · [(1 − F_d) · base_color/π + F_d · V·D] + metallic · (base_color + (1 − base_color) S) · V·D
    S = (1 − |V·H|)⁵,   F_d = f0 + (1 − f0) S,   f0 = ((1 − ior)/(1 + ior))²,   α = roughness²
    F_c = f0 + (1 − f0)(1 − N·V)⁵,   V_c·D_c: GGX and height-correlated Smith at α_c = clearcoat_roughness²

``V·D`` is the core GGX lobe, or, where ``anisotropy_strength > 0``, the extension's anisotropic one with
``α_t = mix(α, 1, anisotropy_strength²)`` along the data's ``+x`` turned by ``anisotropy_rotation`` (radians,
counter-clockwise towards ``+y``) and ``α_b = α`` across it (``gltf.py`` has every term, its sources, and where the
Sample Viewer departs from the extensions' texts).

Parameters: ``roughness``, ``metallic``, ``clearcoat``, ``clearcoat_roughness`` and ``anisotropy_strength`` in
[0, 1]; ``ior`` > 1; ``anisotropy_rotation`` in (−π/2, π/2] (the lobe is the same turned by π); ``base_color`` in
[0, 1], one per channel. Fitted by default: ``base_color``, ``roughness``, ``metallic``, ``clearcoat`` and
``clearcoat_roughness``. Held unless freed: ``ior`` at glTF's 1.5 (``--free ior``: ``KHR_materials_ior``, for a
dielectric whose reflectance at normal incidence is not 4%; the coat's follows it, as in the Sample Viewer), and the
anisotropy at 0 (``--free anisotropy_strength,anisotropy_rotation``): one gonioreflectometer's few planes
seldom tell a stretched lobe from a round one, and its rotation is the tangent's, which a mesh must then carry.

The sheen is an option, ``gltf:sheen=true`` (default false: ``sheen_color`` 0, the extension's default, and then no
sheen parameters at all): it adds ``sheen_color`` (in [0, 1] per channel) and ``sheen_roughness`` (in [0, 1]), both
fitted, Estevez & Kulla's "Charlie" lobe ``D_s·V_s`` and its directional albedo ``E`` (``sheen.py``), which a velvet
or a cloth shows towards grazing angles. It is an option, not a held parameter, because its albedo scaling takes
``max(sheen_color)`` over the channels: each channel then depends on every channel's sheen colour, and the fit takes
the whole Jacobian (``Lobe.channels_coupled``); without it a glTF fit takes one tangent per parameter for all
channels, and never evaluates a sheen (measured: a warm fit of the example 3.4 s with the sheen held, under 1 s
without).

The model says it is isotropic (``LobeModel.isotropic``), as it is with its default holds: the fit's checks take the
shortcuts an isotropic model allows (the albedo on half the grid; at normal incidence, one azimuth), which keep a
narrow coat's albedo resolved. A fit that frees the anisotropy, or holds it elsewhere, is checked as an anisotropic
model's (``Lobe.anisotropy_names``; ``fitting/single/caveats.py``), and data in one plane of incidence then earn a
line saying they cannot determine it. The material is the whole BRDF: a whole-lobe model (``LobeModel.whole``), no
albedos beside it.
"""

import math
from dataclasses import dataclass
from typing import final

from ...checks import boolean
from ..domains import AXIS_ANGLE, UNIT_INTERVAL
from ..fresnel import FRESNEL
from ..models.grids import BASE_COLOR_STARTS, METALLIC_STARTS, ROUGHNESS_STARTS
from ..models.lobe import WholeLobe
from ..models.model import LobeModel, ModelEntry
from .gltf import DEFAULT_IOR, ior_f0, material_brdf

#: The dielectric's index: a dielectric's Fresnel domain (``fresnel.py``), greater than 1.
IOR = dict((name, domain) for name, domain, _ in FRESNEL["dielectric"].parameters)["eta"]
#: Starting coats ``(clearcoat, clearcoat_roughness)``: next to none (off the end of [0, 1]) and a half-strength glossy
#: one, both at roughness 0.1 (``α_c`` = 0.01: a varnish's narrow highlight; a fit widens it where the data do).
CLEARCOAT_STARTS = ((0.02, 0.1), (0.5, 0.1))
#: Starting anisotropies ``(anisotropy_strength, anisotropy_rotation)``, one beside each base colour of
#: :data:`BASE_COLOR_STARTS` rather than beside every shape: held (the default) they are all 0 and add no start; freed,
#: every roughness, metallic and coat start comes with each of three rotations, 60° apart, so that one lies within 30°
#: of any tangent (a rotation 90° from the truth is a stationary point of the cost, where a fit would stay).
ANISOTROPY_STARTS = ((0.4, 0.0), (0.4, math.pi / 3), (0.4, -math.pi / 3))
#: Starting sheens ``(sheen_color, sheen_roughness)`` of ``gltf:sheen=true``, one beside each base colour of
#: :data:`BASE_COLOR_STARTS` as the anisotropies are: a sheen of colour 0.1 (grey) at roughness 0.3, 0.5 or 0.8 (a
#: sheen's roughness moves its lobe, from the horizon towards the normal).
SHEEN_STARTS = ((0.1, 0.3), (0.1, 0.5), (0.1, 0.8))
#: What the fit holds unless a user frees it: glTF's index and no anisotropy (the extensions' defaults).
HELD = (("ior", DEFAULT_IOR), ("anisotropy_strength", 0.0), ("anisotropy_rotation", 0.0))
#: The sheen's parameters (``gltf:sheen=true``): the shared one, then the per-channel one.
SHEEN_PARAMETERS = (("sheen_roughness", UNIT_INTERVAL), ("sheen_color", UNIT_INTERVAL))


@final
@dataclass(frozen=True)
class GltfLobe(WholeLobe):
    """glTF's metallic-roughness BRDF with its clear coat and anisotropy as one lobe, the whole material, under a sheen
    where ``sheen`` (module docstring)."""

    sheen: bool = False

    @property
    def summary(self) -> str:
        under = " under a Charlie sheen (albedo scaling) and" if self.sheen else " under"
        return (
            f"Appendix B (height-correlated Smith GGX, Schlick){under} a clear coat (Schlick in N·V); anisotropic GGX"
            " along +x turned by anisotropy_rotation"
        )

    peaks_at_mirror = True

    @property
    def parameters(self):
        core = (
            ("roughness", UNIT_INTERVAL),
            ("metallic", UNIT_INTERVAL),
            ("ior", IOR),
            ("clearcoat", UNIT_INTERVAL),
            ("clearcoat_roughness", UNIT_INTERVAL),
            ("anisotropy_strength", UNIT_INTERVAL),
            ("anisotropy_rotation", AXIS_ANGLE),
        )
        if not self.sheen:
            return (*core, ("base_color", UNIT_INTERVAL))
        return (*core, *SHEEN_PARAMETERS[:1], ("base_color", UNIT_INTERVAL), *SHEEN_PARAMETERS[1:])  # per channel last

    @property
    def channel_names(self) -> tuple[str, ...]:
        return ("base_color", "sheen_color") if self.sheen else ("base_color",)

    @property
    def channels_coupled(self) -> bool:
        """With a sheen: its albedo scaling takes max(sheen_color) over the channels, so each channel depends on every
        channel's sheen colour and the fit takes the whole Jacobian (one tangent per parameter for all channels at
        once would be wrong in the sheen colour's columns)."""
        return self.sheen

    @property
    def meaningful_ends(self) -> tuple[str, ...]:
        return ("metallic", "clearcoat", "anisotropy_strength") + (("sheen_color",) if self.sheen else ())

    @property
    def fusion_emitters(self) -> bool:
        """Without a sheen: a fit's steps take a third of the time so (``_programs/jit.py``); with one (the whole
        Jacobian) the classic emitters' code is as fast."""
        return not self.sheen

    anisotropy_names = ("anisotropy_strength", "anisotropy_rotation")

    @property
    def grid(self):
        return tuple(
            {"roughness": roughness, "metallic": metallic, "ior": DEFAULT_IOR, "base_color": base}
            | {"clearcoat": clearcoat, "clearcoat_roughness": coat_roughness}
            | {"anisotropy_strength": strength, "anisotropy_rotation": rotation}
            | (dict(zip(("sheen_color", "sheen_roughness"), sheen, strict=True)) if self.sheen else {})
            for roughness in ROUGHNESS_STARTS
            for metallic in METALLIC_STARTS
            for base, (strength, rotation), sheen in zip(
                BASE_COLOR_STARTS, ANISOTROPY_STARTS, SHEEN_STARTS, strict=True
            )
            for clearcoat, coat_roughness in CLEARCOAT_STARTS
        )

    def __call__(self, shape, wi, wo):
        f0 = ior_f0(shape["ior"])  # the dielectric's, and the coat's (the Sample Viewer's getClearCoatInfo)
        sheen = {"sheen_color": shape["sheen_color"], "sheen_roughness": shape["sheen_roughness"]} if self.sheen else {}
        return material_brdf(
            shape["base_color"],
            shape["metallic"],
            shape["roughness"],
            1.0,
            f0,
            wi,
            wo,
            clearcoat=shape["clearcoat"],
            clearcoat_roughness=shape["clearcoat_roughness"],
            coat_reflectance=f0,
            anisotropy_strength=shape["anisotropy_strength"],
            anisotropy_rotation=shape["anisotropy_rotation"],
            **sheen,
        )


def gltf(sheen: bool = False) -> LobeModel:
    """glTF 2.0's metallic-roughness material with a clear coat and anisotropy (module docstring); ``ior`` held at
    1.5 and the anisotropy at 0 unless freed; ``sheen`` (True, or ``"true"`` as a spec writes it; default False):
    KHR_materials_sheen's sheen, ``sheen_color`` and ``sheen_roughness``, fitted."""
    sheen = boolean("sheen", sheen)
    summary = "glTF 2.0 metallic-roughness material (KHR_materials_ior, _clearcoat, _anisotropy"
    summary += ", _sheen)" if sheen else ")"
    options = (("sheen", sheen),)
    return LobeModel("gltf", summary, GltfLobe(sheen), 1, options=options, held=HELD, whole=True, isotropic=True)


#: glTF's material in the registry: ``brdffit compare`` tries it (without a sheen, which few measured materials show
#: and which couples the channels); its glTF export is exact.
GLTF = ModelEntry(
    gltf,
    compare=("gltf",),
    choices={
        "sheen": {
            "false": "no sheen (KHR_materials_sheen's default)",
            "true": "KHR_materials_sheen's Charlie sheen over the material, fitted",
        }
    },
    exports={"gltf": "brdffit.export.gltf:gltf_of_gltf_fit"},
)
