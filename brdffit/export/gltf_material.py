"""The glTF 2.0 metallic-roughness BRDF and a material of it: what a glTF viewer renders, evaluable by brdffit.

**The glTF BRDF** (:func:`gltf_brdf`), as the glTF 2.0 specification's Appendix B ("BRDF Implementation",
Khronos) writes its *complete model*, in 1/sr, with ``α = roughness²``::

    material        = mix(dielectric_brdf, metal_brdf, metallic)
                    = (1 − metallic) · dielectric_brdf + metallic · metal_brdf
    metal_brdf      = conductor_fresnel(f0 = baseColor, bsdf = specular_brdf(α))
                    = (baseColor + (1 − baseColor) (1 − |V·H|)⁵) · specular_brdf
    dielectric_brdf = fresnel_mix(ior = 1.5, base = diffuse_brdf(baseColor), layer = specular_brdf(α))
                    = (1 − fr) · baseColor/π + fr · specular_brdf,   fr = f0 + (1 − f0)(1 − |V·H|)⁵,
                      f0 = ((1 − ior)/(1 + ior))² = 0.04
    specular_brdf   = V · D,   D = α² / (π ((N·H)² (α² − 1) + 1)²)                      (GGX)
                               V = G / (4 |N·L| |N·V|),   G = 1 / (1 + Λ(L) + Λ(V))    (height-correlated Smith)

``L = wi`` (towards the light), ``V = wo`` (towards the viewer), ``H = normalize(L + V)``, ``N`` the normal (``z``).
D is GGX (Trowbridge & Reitz 1975; Walter, Marschner, Li & Torrance, "Microfacet models for refraction through
rough surfaces", EGSR 2007, eq. 33); Λ is GGX's Smith term, ``(−1 + sqrt(1 + α² tan²θ))/2`` (Walter et al. 2007;
Heitz, "Understanding the masking-shadowing function in microfacet-based BRDFs", JCGT 2014), and
``1/(1 + Λ(L) + Λ(V))`` is Heitz's height-correlated masking-shadowing (eq. 99). Written out,
``V = 0.5 / (|N·L| sqrt((N·V)² (1 − α²) + α²) + |N·V| sqrt((N·L)² (1 − α²) + α²))``: the form the Khronos glTF
Sample Viewer and Filament implement. **Appendix B itself writes the separable form**
``G = G1(L) G1(V) = 1/((1 + Λ(L))(1 + Λ(V)))``; brdffit follows the renderers (and the issue that asked for this
export). The separable form is darker by the fraction ``Λ(L)Λ(V)/((1 + Λ(L))(1 + Λ(V)))``: 0.2% at ``α = 0.25``
with both directions at 60° from the normal, 11% at ``α = 1``, more towards grazing angles.

**The optimised single-F form.** Appendix B, until Khronos's fix of 2024 (glTF issue #2386, pull request #2392),
ended with a "simplified" implementation: ``c_diff = lerp(baseColor, 0, metallic)``,
``f0 = lerp(0.04, baseColor, metallic)``, ``F = f0 + (1 − f0)(1 − |V·H|)⁵``, ``f = (1 − F) c_diff/π + F · V · D``.
Its specular part equals the mix's exactly (the Schlick terms are linear in ``f0``), but its diffuse part is
``(1 − metallic)(1 − F) baseColor/π`` where the mix has ``(1 − metallic)(1 − fr) baseColor/π``, and
``F − fr = metallic (baseColor − 0.04)(1 − |V·H|)⁵``: the two agree at metallic 0 and 1 and differ by
``metallic (1 − metallic)(baseColor − 0.04) baseColor (1 − |V·H|)⁵ / π`` in between (for baseColor 1 and
metallic 0.5, the single-F form's diffuse term is half the mix's: 0.0764 1/sr less at normal incidence).
brdffit implements the mix, as the specification now writes it.

**Energy.** The metal is single-scattering GGX: it loses the light that scatters between microfacets and never
reflects more than it receives. The dielectric's ``fresnel_mix`` weights the diffuse base by ``1 − fr`` of each
pair's ``|V·H|``, not by the layer's directional albedo, and can: a white dielectric of roughness 0.5 reflects 1.08
times the light it receives at θi = 80° (``tests/export/test_gltf.py``). That is the specification's model.

**Extensions.** ``KHR_materials_specular`` (ratified; its "Implementation" section) with ``KHR_materials_ior``
changes only the dielectric::

    dielectric_brdf = fresnel_mix(f0_color = specularColor, ior, weight = specular, base, layer)
                    = (1 − specular · max(fr.r, fr.g, fr.b)) · base + specular · fr · layer,
                      fr = f0 + (1 − f0)(1 − |V·H|)⁵,   f0 = min(((1 − ior)/(1 + ior))² · specularColor, 1)

With the defaults (specular 1, specularColor (1, 1, 1), ior 1.5) ``fr`` is the same in every channel and this is
the core model exactly. ``ior`` is 0 or at least 1 (KHR_materials_ior); 0 gives ``f0 = min(specularColor, 1)``.

The material is fitted to a brdffit fit and written as a ``.gltf`` file by ``gltf.py``.
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
from ..physics.geometry import above_horizon, half_vector
from ..physics.microfacet import ggx_distribution, ggx_lambda
from .gltf_preview import glb_bytes, gltf_document

#: The dielectric's index of refraction in core glTF (Appendix B), and the extension's default.
DEFAULT_IOR = 1.5
#: The dielectric's reflectance at normal incidence for :data:`DEFAULT_IOR`: ``((1 − 1.5)/(1 + 1.5))² = 0.04``.
DEFAULT_F0 = ((1.0 - DEFAULT_IOR) / (1.0 + DEFAULT_IOR)) ** 2  # as ior_f0 computes it
#: The GGX ``α`` never goes below this (roughness 0.001): at ``α = 0`` the distribution is a delta, ``0/0`` at the
#: mirror direction.
MIN_ALPHA = 1e-6
#: The ``asset.generator`` of every file brdffit writes.
_GENERATOR = f"brdffit {__version__}"


# ---------------------------------------------------------------------- the BRDF
def ior_f0(ior):
    """The reflectance at normal incidence of a dielectric of index ``ior`` in air: ``((1 − ior)/(1 + ior))²``."""
    return ((1.0 - ior) / (1.0 + ior)) ** 2


def dielectric_f0(specular_color, ior):
    """The dielectric's reflectance at normal incidence (3,): ``min(((1 − ior)/(1 + ior))² · specularColor, 1)``
    (KHR_materials_specular with KHR_materials_ior; ``0.04`` per channel for the defaults)."""
    return jnp.minimum(ior_f0(ior) * jnp.asarray(specular_color), 1.0)


def material_brdf(base_color, metallic, roughness, specular, dielectric_reflectance, wi, wo):
    """The glTF BRDF (N, 3) in 1/sr, with the dielectric's ``f0`` (3,) given directly (the module docstring)."""
    visible, wi, wo = above_horizon(wi, wo)
    cos_i, cos_o = wi[:, 2:3], wo[:, 2:3]
    h = half_vector(wi, wo)
    v_dot_h = jnp.abs(jnp.sum(wo * h, axis=-1, keepdims=True))
    alpha = jnp.maximum(roughness * roughness, MIN_ALPHA)
    distribution = ggx_distribution(h[:, 2:3], alpha)
    # V = G / (4 ci co) with G = 1/(1 + Λ(wi) + Λ(wo)): height-correlated Smith (Heitz 2014, eq. 99)
    visibility = 1.0 / (4.0 * cos_i * cos_o * (1.0 + ggx_lambda(cos_i, alpha) + ggx_lambda(cos_o, alpha)))
    specular_brdf = visibility * distribution  # (N, 1)
    schlick_weight = (1.0 - v_dot_h) ** 5  # Schlick 1994: F = f0 + (1 − f0)(1 − |V·H|)⁵
    base_color = jnp.asarray(base_color)
    metal_brdf = (base_color + (1.0 - base_color) * schlick_weight) * specular_brdf
    fresnel = dielectric_reflectance + (1.0 - dielectric_reflectance) * schlick_weight  # (N, 3)
    diffuse_brdf = base_color / jnp.pi
    dielectric_brdf = (1.0 - specular * jnp.max(fresnel, axis=-1, keepdims=True)) * diffuse_brdf
    dielectric_brdf = dielectric_brdf + specular * fresnel * specular_brdf
    material = (1.0 - metallic) * dielectric_brdf + metallic * metal_brdf
    return jnp.where(visible[:, None], material, 0.0)


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
):
    """The glTF 2.0 metallic-roughness BRDF (N, 3) in 1/sr at direction pairs ``wi``, ``wo`` (N, 3), JAX.

    ``base_color`` (3,) linear RGB, ``metallic`` and ``roughness`` in [0, 1] (``α = roughness²``); ``specular``
    (in [0, 1]), ``specular_color`` (3,) (≥ 0) and ``ior`` (0 or ≥ 1) are ``KHR_materials_specular``'s and
    ``KHR_materials_ior``'s, and their defaults give the core model exactly. The model is the module docstring's:
    Appendix B's complete model ``mix(dielectric_brdf, metal_brdf, metallic)`` (not its former single-F
    shortcut), GGX with height-correlated Smith (as the Khronos Sample Viewer and Filament implement it;
    Appendix B writes the separable Smith form) and Schlick's Fresnel term in ``|V·H|``.

    Zero where either direction is at or below the horizon; finite, with finite derivatives with respect to the
    parameters, for both cosines in (0, 1] (θ = 89.9° included) and roughness down to 0.001 (``α`` is held at
    :data:`MIN_ALPHA` or above). Traceable and differentiable (``jax.grad``, ``jax.jit``).
    """
    wi, wo = jnp.asarray(wi), jnp.asarray(wo)
    reflectance = dielectric_f0(specular_color, ior)
    return material_brdf(base_color, metallic, roughness, specular, reflectance, wi, wo)


@jit
def _gltf_brdf_compiled(base_color, metallic, roughness, specular, specular_color, ior, wi, wo):
    return gltf_brdf(base_color, metallic, roughness, wi, wo, specular=specular, specular_color=specular_color, ior=ior)


# ---------------------------------------------------------------------- the material
def _unit_interval(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
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
    return tuple(float(c) for c in numbers)


@dataclass(frozen=True)
class GltfMaterial:
    """A glTF 2.0 metallic-roughness material: ``base_color`` (3 floats in [0, 1], linear RGB), ``metallic`` and
    ``roughness`` (in [0, 1]); ``specular`` (in [0, 1]) and ``specular_color`` (3 floats ≥ 0) of
    ``KHR_materials_specular`` and ``ior`` (0 or ≥ 1; 0 means ``f0 = 1``) of ``KHR_materials_ior``, each None
    when not used (its default applies: 1, (1, 1, 1), 1.5)."""

    base_color: tuple[float, float, float]
    metallic: float
    roughness: float
    specular: float | None = None
    specular_color: tuple[float, float, float] | None = None
    ior: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "base_color", _three_numbers("base_color", self.base_color, 1.0))
        object.__setattr__(self, "metallic", _unit_interval("metallic", self.metallic))
        object.__setattr__(self, "roughness", _unit_interval("roughness", self.roughness))
        if self.specular is not None:
            object.__setattr__(self, "specular", _unit_interval("specular", self.specular))
        if self.specular_color is not None:
            object.__setattr__(self, "specular_color", _three_numbers("specular_color", self.specular_color, None))
        if self.ior is not None:
            ior = self.ior
            number = not isinstance(ior, bool) and isinstance(ior, int | float | np.floating | np.integer)
            if not number or not (ior == 0 or 1.0 <= ior < math.inf):
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
        return tuple(used)

    def brdf(self, wi, wo) -> np.ndarray:
        """This material's BRDF (N, 3) in 1/sr at direction pairs ``wi``, ``wo`` (N, 3) (:func:`gltf_brdf`)."""
        with float64():
            values = _gltf_brdf_compiled(
                np.asarray(self.base_color),
                self.metallic,
                self.roughness,
                1.0 if self.specular is None else self.specular,
                np.asarray(self.specular_color or (1.0, 1.0, 1.0)),
                DEFAULT_IOR if self.ior is None else self.ior,
                np.asarray(wi, dtype=np.float64),
                np.asarray(wo, dtype=np.float64),
            )
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
        return gltf_document(self.material_object(name, extras), list(self.extensions), name, _GENERATOR)

    def to_glb(self, name: str, extras: dict[str, Any] | None = None) -> bytes:
        """The document of :meth:`to_gltf` as a binary glTF (``.glb``) file's bytes."""
        return glb_bytes(self.material_object(name, extras), list(self.extensions), name, _GENERATOR)
