"""The glTF 2.0 metallic-roughness BRDF: what a glTF viewer renders, in JAX.

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

The ``gltf`` fit model (``gltf_model.py``) and the glTF export (``export/gltf_material.py``) both evaluate it
here.
"""

from ..._jax import jnp
from ..geometry import above_horizon, half_vector
from ..microfacet import ggx_distribution, ggx_lambda

#: The dielectric's index of refraction in core glTF (Appendix B), and the extension's default.
DEFAULT_IOR = 1.5
#: The dielectric's reflectance at normal incidence for :data:`DEFAULT_IOR`: ``((1 − 1.5)/(1 + 1.5))² = 0.04``.
DEFAULT_F0 = ((1.0 - DEFAULT_IOR) / (1.0 + DEFAULT_IOR)) ** 2  # as ior_f0 computes it
#: The GGX ``α`` never goes below this (roughness 0.001): at ``α = 0`` the distribution is a delta, ``0/0`` at the
#: mirror direction.
MIN_ALPHA = 1e-6


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
