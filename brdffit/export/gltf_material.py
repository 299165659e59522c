"""A glTF 2.0 metallic-roughness material: its parameters checked, its BRDF evaluated, its glTF and glb documents.

The BRDF is ``physics/renderers/gltf.py``'s (the glTF 2.0 specification's Appendix B, with height-correlated Smith);
the material is fitted to a brdffit fit, or mapped exactly from a fit of the ``gltf`` model, and written as a
``.gltf`` file by ``gltf.py``.
"""

import math
from dataclasses import dataclass
from typing import Any

import jax.numpy as jnp
import numpy as np

from .._jax import float64
from .._programs import jit
from .._version import __version__
from ..errors import Argument, BrdfInputError
from ..physics.renderers.gltf import DEFAULT_IOR, MIN_ANISOTROPY, dielectric_f0, ior_f0, material_brdf
from .gltf_preview import glb_bytes, gltf_document

#: The ``asset.generator`` of every file brdffit writes.
_GENERATOR = f"brdffit {__version__}"


@float64
def gltf_brdf(
    base_color,
    metallic,
    roughness,
    wi,
    wo,
    *,
    specular=1.0,
    specular_color=(1.0, 1.0, 1.0),
    ior=DEFAULT_IOR,
    clearcoat=0.0,
    clearcoat_roughness=0.0,
    anisotropy_strength=0.0,
    anisotropy_rotation=0.0,
    sheen_color=0.0,
    sheen_roughness=0.0,
):
    """The glTF 2.0 metallic-roughness BRDF (N, 3) in 1/sr at direction pairs ``wi``, ``wo`` (N, 3), JAX.

    ``base_color`` (3,) linear RGB, ``metallic`` and ``roughness`` in [0, 1] (``α = roughness²``); ``specular``
    (in [0, 1]), ``specular_color`` (3,) (≥ 0) and ``ior`` (0 or ≥ 1) are ``KHR_materials_specular``'s and
    ``KHR_materials_ior``'s; ``clearcoat`` and ``clearcoat_roughness`` (in [0, 1]) ``KHR_materials_clearcoat``'s, the
    coat's reflectance at normal incidence that of ``ior`` (as the Sample Viewer takes it); ``anisotropy_strength`` (in
    [0, 1]) and ``anisotropy_rotation`` (radians from the data's ``+x``, counter-clockwise towards ``+y``)
    ``KHR_materials_anisotropy``'s; ``sheen_color`` (3,) (in [0, 1]) and ``sheen_roughness`` (in [0, 1])
    ``KHR_materials_sheen``'s, layered by albedo scaling (``physics/renderers/sheen.py``). Their defaults give the core
    model exactly. The model is
    ``physics/renderers/gltf.py``'s: Appendix B's complete model ``mix(dielectric_brdf, metal_brdf, metallic)`` (not
    its former single-F shortcut), GGX with height-correlated Smith (as the Khronos Sample Viewer and Filament
    implement it; Appendix B writes the separable Smith form), Schlick's Fresnel term in ``|V·H|``, the coat's in
    ``N·V``, and the Sample Viewer's anisotropic GGX (its visibility clamped to 1) where ``anisotropy_strength`` is
    ``MIN_ANISOTROPY`` (10⁻⁶) or more.

    Zero where either direction is at or below the horizon; finite, with finite derivatives with respect to the
    parameters, for both cosines in (0, 1] (θ = 89.9° included) and roughness down to 0.001 (``α`` is held at
    :data:`MIN_ALPHA` or above). Traceable and differentiable (``jax.grad``, ``jax.jit``).
    """
    wi, wo = jnp.asarray(wi), jnp.asarray(wo)
    reflectance = dielectric_f0(specular_color, ior)
    return material_brdf(
        base_color,
        metallic,
        roughness,
        specular,
        reflectance,
        wi,
        wo,
        clearcoat=clearcoat,
        clearcoat_roughness=clearcoat_roughness,
        coat_reflectance=ior_f0(ior),
        anisotropy_strength=anisotropy_strength,
        anisotropy_rotation=anisotropy_rotation,
        sheen_color=sheen_color,
        sheen_roughness=sheen_roughness,
    )


@jit
def _gltf_brdf_compiled(
    base_color,
    metallic,
    roughness,
    specular,
    specular_color,
    ior,
    coat,
    anisotropy,
    sheen_color,
    sheen_roughness,
    wi,
    wo,
):
    return gltf_brdf(
        base_color,
        metallic,
        roughness,
        wi,
        wo,
        specular=specular,
        specular_color=specular_color,
        ior=ior,
        clearcoat=coat[0],
        clearcoat_roughness=coat[1],
        anisotropy_strength=anisotropy[0],
        anisotropy_rotation=anisotropy[1],
        sheen_color=sheen_color,
        sheen_roughness=sheen_roughness,
    )


# ---------------------------------------------------------------------- the material
def _is_number(value) -> bool:
    """A real number (a Python or numpy int or float), not a boolean."""
    return not isinstance(value, bool) and isinstance(value, int | float | np.floating | np.integer)


def _unit_interval(name: str, value) -> float:
    if not _is_number(value):
        raise BrdfInputError(Argument.given(name, value), " is not allowed; give a number in [0, 1]")
    if not 0.0 <= float(value) <= 1.0:
        raise BrdfInputError(Argument.given(name, value), " is not allowed; give a number in [0, 1]")
    return float(value)


def _three_numbers(name: str, value, upper: float | None) -> tuple[float, float, float]:
    allowed = "three numbers in [0, 1] (linear RGB)" if upper == 1.0 else "three numbers ≥ 0 (linear RGB)"
    try:
        numbers = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        numbers = np.full(1, np.nan)
    if numbers.shape != (3,) or not np.all(np.isfinite(numbers)) or np.any(numbers < 0):
        raise BrdfInputError(Argument.given(name, value), f" is not allowed; give {allowed}")
    if upper is not None and np.any(numbers > upper):
        raise BrdfInputError(Argument.given(name, value), f" is not allowed; give {allowed}")
    return float(numbers[0]), float(numbers[1]), float(numbers[2])


@dataclass(frozen=True)
class GltfMaterial:
    """A glTF 2.0 metallic-roughness material: ``base_color`` (3 floats in [0, 1], linear RGB), ``metallic`` and
    ``roughness`` (in [0, 1]); ``specular`` (in [0, 1]) and ``specular_color`` (3 floats ≥ 0) of
    ``KHR_materials_specular`` and ``ior`` (0 or ≥ 1; 0 means ``f0 = 1``) of ``KHR_materials_ior``, each None
    when not used (its default applies: 1, (1, 1, 1), 1.5); ``clearcoat`` and ``clearcoat_roughness`` (in [0, 1]) of
    ``KHR_materials_clearcoat``, used where ``clearcoat`` is not 0; ``anisotropy_strength`` (in [0, 1]) and
    ``anisotropy_rotation`` (radians, any finite number) of ``KHR_materials_anisotropy``, used where the strength is
    not 0 (the tangent is the mesh's ``TANGENT``, the data's ``+x`` for a fit); a strength below
    ``physics/renderers/gltf.py``'s ``MIN_ANISOTROPY`` (10⁻⁶) is none, and is set to 0; ``sheen_color`` (3 floats in
    [0, 1], linear RGB) and ``sheen_roughness`` (in [0, 1]) of ``KHR_materials_sheen``, used where a sheen colour is not
    0 (the extension: "If sheenColorFactor is zero, the whole sheen layer is disabled")."""

    base_color: tuple[float, float, float]
    metallic: float
    roughness: float
    specular: float | None = None
    specular_color: tuple[float, float, float] | None = None
    ior: float | None = None
    clearcoat: float = 0.0
    clearcoat_roughness: float = 0.0
    anisotropy_strength: float = 0.0
    anisotropy_rotation: float = 0.0
    sheen_color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sheen_roughness: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "base_color", _three_numbers("base_color", self.base_color, 1.0))
        object.__setattr__(self, "sheen_color", _three_numbers("sheen_color", self.sheen_color, 1.0))
        names = ("metallic", "roughness", "clearcoat", "clearcoat_roughness", "anisotropy_strength", "sheen_roughness")
        for name in names:
            object.__setattr__(self, name, _unit_interval(name, getattr(self, name)))
        if self.anisotropy_strength < MIN_ANISOTROPY:  # none, as the BRDF takes it: no extension written either
            object.__setattr__(self, "anisotropy_strength", 0.0)
        rotation = self.anisotropy_rotation
        if not _is_number(rotation) or not math.isfinite(rotation):
            raise BrdfInputError(
                Argument.given("anisotropy_rotation", rotation), " is not allowed; give a finite number (radians)"
            )
        object.__setattr__(self, "anisotropy_rotation", float(rotation))
        if self.specular is not None:
            object.__setattr__(self, "specular", _unit_interval("specular", self.specular))
        if self.specular_color is not None:
            object.__setattr__(self, "specular_color", _three_numbers("specular_color", self.specular_color, None))
        if self.ior is not None:
            ior = self.ior
            if not _is_number(ior) or not (ior == 0 or 1.0 <= ior < math.inf):
                raise BrdfInputError(Argument.given("ior", ior), " is not allowed; give 0 or a finite number ≥ 1")
            object.__setattr__(self, "ior", float(ior))

    @property
    def extensions(self) -> tuple[str, ...]:
        """The glTF extensions this material uses, in the order the file lists them."""
        used = []
        if self.specular is not None or self.specular_color is not None:
            used.append("KHR_materials_specular")
        if self.ior is not None:
            used.append("KHR_materials_ior")
        if self.clearcoat != 0.0:
            used.append("KHR_materials_clearcoat")
        if self.anisotropy_strength != 0.0:
            used.append("KHR_materials_anisotropy")
        if any(self.sheen_color):
            used.append("KHR_materials_sheen")
        return tuple(used)

    @property
    def needs_tangents(self) -> bool:
        """Whether a mesh must carry tangents (glTF's ``TANGENT`` attribute) to show this material as fitted: an
        anisotropic lobe is stretched along the tangent (``KHR_materials_anisotropy``: "MUST have a defined tangent
        space")."""
        return "KHR_materials_anisotropy" in self.extensions

    def brdf(self, wi, wo) -> np.ndarray:
        """This material's BRDF (N, 3) in 1/sr at direction pairs ``wi``, ``wo`` (N, 3) (:func:`gltf_brdf`)."""
        arguments = (
            self.base_color,
            self.metallic,
            self.roughness,
            1.0 if self.specular is None else self.specular,
            self.specular_color or (1.0, 1.0, 1.0),
            DEFAULT_IOR if self.ior is None else self.ior,
            (self.clearcoat, self.clearcoat_roughness),
            (self.anisotropy_strength, self.anisotropy_rotation),
            self.sheen_color,
            self.sheen_roughness,
            wi,
            wo,
        )
        with float64():  # every argument an array, so that a later process runs the stored program (``_programs``)
            values = _gltf_brdf_compiled(*(np.asarray(argument, dtype=np.float64) for argument in arguments))
        return np.asarray(values)

    def material_object(self, name: str, extras: dict[str, Any] | None = None) -> dict[str, Any]:
        """This material as a glTF 2.0 material object (JSON as Python objects), named ``name``:
        ``pbrMetallicRoughness`` with ``baseColorFactor`` (opaque: alpha 1), ``metallicFactor`` and
        ``roughnessFactor``, the extensions' objects only where the material uses them (:attr:`extensions`), and
        ``extras`` (application data) when given."""
        material: dict[str, Any] = {
            "name": str(name),
            "pbrMetallicRoughness": {
                "baseColorFactor": [*self.base_color, 1.0],
                "metallicFactor": self.metallic,
                "roughnessFactor": self.roughness,
            },
        }
        extensions: dict[str, Any] = {}
        if "KHR_materials_specular" in self.extensions:
            specular: dict[str, Any] = {}
            if self.specular is not None:
                specular["specularFactor"] = self.specular
            if self.specular_color is not None:
                specular["specularColorFactor"] = list(self.specular_color)
            extensions["KHR_materials_specular"] = specular
        if self.ior is not None:
            extensions["KHR_materials_ior"] = {"ior": self.ior}
        if "KHR_materials_clearcoat" in self.extensions:
            extensions["KHR_materials_clearcoat"] = {
                "clearcoatFactor": self.clearcoat,
                "clearcoatRoughnessFactor": self.clearcoat_roughness,
            }
        if "KHR_materials_anisotropy" in self.extensions:
            extensions["KHR_materials_anisotropy"] = {
                "anisotropyStrength": self.anisotropy_strength,
                "anisotropyRotation": self.anisotropy_rotation,
            }
        if "KHR_materials_sheen" in self.extensions:
            extensions["KHR_materials_sheen"] = {
                "sheenColorFactor": list(self.sheen_color),
                "sheenRoughnessFactor": self.sheen_roughness,
            }
        if extensions:
            material["extensions"] = extensions
        if extras is not None:
            material["extras"] = extras
        return material

    def to_gltf(self, name: str, extras: dict[str, Any] | None = None) -> dict[str, Any]:
        """A complete glTF 2.0 document (JSON as Python objects, a ``.gltf`` file's content): this material
        (:meth:`material_object`) on a preview sphere in a scene named ``name``, so that a viewer shows it; the
        top-level ``extensionsUsed`` lists the material's extensions; ``asset.generator`` names brdffit
        (``export/gltf_preview.py``)."""
        material = self.material_object(name, extras)
        return gltf_document(material, list(self.extensions), name, _GENERATOR, tangents=self.needs_tangents)

    def to_glb(self, name: str, extras: dict[str, Any] | None = None) -> bytes:
        """The document of :meth:`to_gltf` as a binary glTF (``.glb``) file's bytes."""
        material = self.material_object(name, extras)
        return glb_bytes(material, list(self.extensions), name, _GENERATOR, tangents=self.needs_tangents)
