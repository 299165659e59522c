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

**KHR_materials_clearcoat** (ratified; its "Extending Materials" and "Implementation" sections) layers a clear coat
over the whole material, with Appendix B's specular BRDF at the coat's own roughness::

    coated_material = fresnel_coat(normal, ior, weight = clearcoat, base = material, layer = specular_brdf(α_c))
                    = (1 − clearcoat · F_c) · material + clearcoat · F_c · V_c · D_c,   α_c = clearcoatRoughness²
    F_c             = f0_c + (1 − f0_c)(1 − N·V)⁵

The coat's Fresnel term is Schlick's in ``N·V``, the viewer's direction alone, not ``|V·H|``: the extension's
"Discussion" chooses it so that the simple mix conserves energy ("we compute the microfacet Fresnel term with NdotV
instead of VdotH"), and the Khronos glTF Sample Viewer does the same (``pbr.frag``: ``clearcoatFresnel =
F_Schlick(clearcoatF0, clearcoatF90, clampedDot(clearcoatNormal, v))``, then ``mix(color, clearcoat_brdf,
clearcoatFactor * clearcoatFresnel)`` per light: the base, diffuse and specular alike, is attenuated by
``1 − clearcoat · F_c``, and the layer ``getPunctualRadianceClearCoat`` is ``V·D`` alone; earlier Sample Viewers
multiplied it by a second Schlick term in ``V·H``). The coated material is therefore **not reciprocal**: swapping
light and viewer changes ``F_c`` (``tests/export/test_gltf.py`` checks by how much). Its energy is conserved as the
viewer sees it (for one viewer, the light arriving from the whole hemisphere is a mix of what the base and the coat
reflect), not as the light does: light arriving at a grazing angle meets the base's full weight and, towards grazing
viewers, the coat's large one; a white dielectric of roughness 0.5 under a full coat of roughness 0.3 reflects 1.23
times the light it receives at θi = 80° (1.08 bare). Where the extension's text and the Sample Viewer differ, brdffit
follows the Sample Viewer (``material_info.glsl``, ``getClearCoatInfo``): the coat's ``f0_c = ((ior − 1)/(ior + 1))²``
takes the material's ``KHR_materials_ior`` index, where the extension fixes ``ior = 1.5`` for the coat; the two agree
while ``ior`` is 1.5 (core glTF, and the ``gltf`` model's default).

**KHR_materials_anisotropy** (ratified) stretches the base's GGX lobe (metal and dielectric layer alike; the coat
stays isotropic) along a direction ``t`` in the surface: the mesh's tangent turned counter-clockwise (towards the
bitangent) by ``anisotropyRotation`` radians; here the tangent is the data's ``+x``, so ``t = (cos r, sin r, 0)``,
``b = n × t = (−sin r, cos r, 0)``. With ``s = anisotropyStrength``::

    α_t = mix(α, 1, s²) = α + (1 − α) s²,   α_b = α                     (the extension's "Anisotropy")
    D   = 1 / (π α_t α_b ((h·t)²/α_t² + (h·b)²/α_b² + (h·n)²)²)           (Burley 2012, addenda; Heitz 2014, eq. 85)
    V   = min(1, 0.5 / (N·L |(α_t t·V, α_b b·V, N·V)| + N·V |(α_t t·L, α_b b·L, N·L)|))

``V`` is Heitz's height-correlated Smith term for the anisotropic GGX (2014, eq. 99 with the anisotropic ``Λ``),
``G/(4 N·L N·V)``, as the extension's sample implementation (non-normative) and the Sample Viewer (``brdf.glsl``,
``V_GGX_anisotropic``, ``BRDF_specularGGXAnisotropy``) write it: **clamped to 1**, with ``α_b`` floored at 0.001 and
``N·H`` at 0.001 (the viewer's). The viewer runs that code for a material with the extension only; brdffit evaluates
it where ``anisotropy_strength`` is :data:`MIN_ANISOTROPY` (10⁻⁶) or more (the export writes the extension exactly
then), and the core form elsewhere. The clamp binds where ``N·L · N·V ≲ 1/4`` near the mirror (both directions beyond
60°): there a smooth lobe is cut to ``4 N·L N·V`` of its unclamped value (27% at 75°), so the BRDF jumps where the
strength reaches its threshold. With ``α_t = α_b = α`` and no floor or clamp the anisotropic form is the core one (GGX's
``D`` and Smith's ``Λ`` see the slopes through ``α(φ)`` alone), so one evaluation serves both (:func:`_ggx_lobe`).

**KHR_materials_sheen** (ratified; its "Implementation Notes", non-normative) lays a sheen over the material, under
the coat ("If clearcoat (KHR_materials_clearcoat) is active at the same time, clearcoat is layered on top of sheen"),
combined by albedo scaling (Conty Estevez & Kulla 2017) as the Sample Viewer does for each light (``pbr.frag``:
``l_albedoSheenScaling = min(1.0 - max3(sheenColor) * albedoSheenScalingLUT(NdotV, sheenRoughness), 1.0 - max3(…) *
albedoSheenScalingLUT(NdotL, …))``, then ``l_color = l_sheen + l_color * l_albedoSheenScaling``)::

    sheened = sheen_color · D_s · V_s + min(1 − max(sheen_color) E(N·V), 1 − max(sheen_color) E(N·L)) · material

with the Charlie lobe ``D_s · V_s`` and its directional albedo ``E`` of ``sheen.py``. Taking the smaller of both
directions' scalings keeps the material **reciprocal** (the extension's cheaper ``1 − max(sheen_color) E(N·V)``
alone, which the viewer applies to its environment light, would not be). The coat is then laid over the sheened
material as above.

Sources: the extensions' READMEs in KhronosGroup/glTF (``extensions/2.0/Khronos/KHR_materials_clearcoat``,
``KHR_materials_anisotropy``, ``KHR_materials_sheen``); the Sample Viewer's shaders in KhronosGroup/glTF-Sample-Viewer
(``source/Renderer/shaders``: ``brdf.glsl``, ``punctual.glsl``, ``material_info.glsl``, ``pbr.frag``). The
``gltf`` fit model (``gltf_model.py``) and the glTF export (``export/gltf_material.py``) both evaluate it here.
"""

import math

from ..._jax import jnp
from ..geometry import above_horizon, half_vector, in_turned_frame
from ..microfacet import ggx_anisotropic_distribution
from .sheen import sheen_albedo, sheen_lobe

#: The dielectric's index of refraction in core glTF (Appendix B), and the extension's default.
DEFAULT_IOR = 1.5
#: The dielectric's reflectance at normal incidence for :data:`DEFAULT_IOR`: ``((1 − 1.5)/(1 + 1.5))² = 0.04``.
DEFAULT_F0 = ((1.0 - DEFAULT_IOR) / (1.0 + DEFAULT_IOR)) ** 2  # as ior_f0 computes it
#: The GGX ``α`` never goes below this (roughness 0.001): at ``α = 0`` the distribution is a delta, ``0/0`` at the
#: mirror direction.
MIN_ALPHA = 1e-6
#: The Sample Viewer's floors in its anisotropic GGX (``BRDF_specularGGXAnisotropy``): ``α_b`` and ``N·H``.
ANISOTROPIC_MIN_ALPHA = 0.001
ANISOTROPIC_MIN_COS_H = 0.001
#: The Sample Viewer's (and the extension's sample code's) ceiling on the anisotropic visibility ``V``.
ANISOTROPIC_MAX_VISIBILITY = 1.0
#: An anisotropy strength below this is none: the core form is evaluated, as a viewer does for a material without the
#: extension. A fit's logistic map reaches 0 only in the limit (a strength held at 0 is 10⁻¹² to the solver), and its
#: result puts a strength this close to 0 onto 0 (``Lobe.meaningful_ends``), which the export writes as no extension;
#: ``α_t`` differs from ``α`` by less than 10⁻¹² there, so only the visibility's clamp tells the two forms apart.
MIN_ANISOTROPY = 1e-6


def ior_f0(ior):
    """The reflectance at normal incidence of a dielectric of index ``ior`` in air: ``((1 − ior)/(1 + ior))²``."""
    return ((1.0 - ior) / (1.0 + ior)) ** 2


def dielectric_f0(specular_color, ior):
    """The dielectric's reflectance at normal incidence (3,): ``min(((1 − ior)/(1 + ior))² · specularColor, 1)``
    (KHR_materials_specular with KHR_materials_ior; ``0.04`` per channel for the defaults)."""
    return jnp.minimum(ior_f0(ior) * jnp.asarray(specular_color), 1.0)


def material_brdf(
    base_color,
    metallic,
    roughness,
    specular,
    dielectric_reflectance,
    wi,
    wo,
    *,
    clearcoat=0.0,
    clearcoat_roughness=0.0,
    coat_reflectance=DEFAULT_F0,
    anisotropy_strength=0.0,
    anisotropy_rotation=0.0,
    sheen_color=0.0,
    sheen_roughness=0.0,
):
    """The glTF BRDF (N, 3) in 1/sr, with the dielectric's ``f0`` (3,) given directly (the module docstring).

    ``clearcoat``, ``clearcoat_roughness`` (KHR_materials_clearcoat, in [0, 1]) with the coat's ``f0``
    ``coat_reflectance``; ``anisotropy_strength`` in [0, 1] and ``anisotropy_rotation`` in radians from the data's
    ``+x`` (KHR_materials_anisotropy); ``sheen_color`` (3,) (or one number for all channels) and ``sheen_roughness``
    in [0, 1] (KHR_materials_sheen). Each extension is left out of the computation where its weight is the number
    0 (the export's fits of the core material), and gives the core model exactly at 0 in any case."""
    visible, wi, wo = above_horizon(wi, wo)
    h = half_vector(wi, wo)
    v_dot_h = jnp.abs(jnp.sum(wo * h, axis=-1, keepdims=True))
    alpha = jnp.maximum(roughness * roughness, MIN_ALPHA)
    if _is_zero(anisotropy_strength):
        specular_brdf = _ggx_lobe(wi, wo, h, alpha, alpha)
    else:
        # One evaluation serves both forms: the anisotropic one with α_t = α_b = α is the core lobe (GGX's D and
        # Smith's Λ depend on the slopes through α(φ) alone), which the Sample Viewer's floors and clamp then leave be.
        anisotropic = anisotropy_strength >= MIN_ANISOTROPY
        alpha_t = jnp.maximum(
            roughness * roughness * (1.0 - anisotropy_strength**2) + anisotropy_strength**2, MIN_ALPHA
        )
        alpha_b = jnp.clip(roughness * roughness, ANISOTROPIC_MIN_ALPHA, 1.0)
        turned = (in_turned_frame(w, anisotropy_rotation) for w in (wi, wo, h))
        specular_brdf = _ggx_lobe(
            *turned,
            jnp.where(anisotropic, alpha_t, alpha),
            jnp.where(anisotropic, alpha_b, alpha),
            min_cos_h=jnp.where(anisotropic, ANISOTROPIC_MIN_COS_H, 0.0),
            max_visibility=jnp.where(anisotropic, ANISOTROPIC_MAX_VISIBILITY, math.inf),
        )
    schlick_weight = (1.0 - v_dot_h) ** 5  # Schlick 1994: F = f0 + (1 − f0)(1 − |V·H|)⁵
    base_color = jnp.asarray(base_color)
    metal_brdf = (base_color + (1.0 - base_color) * schlick_weight) * specular_brdf
    fresnel = dielectric_reflectance + (1.0 - dielectric_reflectance) * schlick_weight  # (N, 3)
    diffuse_brdf = base_color / jnp.pi
    dielectric_brdf = (1.0 - specular * jnp.max(fresnel, axis=-1, keepdims=True)) * diffuse_brdf
    dielectric_brdf = dielectric_brdf + specular * fresnel * specular_brdf
    material = (1.0 - metallic) * dielectric_brdf + metallic * metal_brdf
    if not _is_zero(sheen_color):
        material = _with_sheen(material, jnp.asarray(sheen_color), sheen_roughness, wi, wo, h)
    if not _is_zero(clearcoat):
        coat_alpha = jnp.maximum(clearcoat_roughness * clearcoat_roughness, MIN_ALPHA)
        coat_brdf = _ggx_lobe(wi, wo, h, coat_alpha, coat_alpha)
        # fresnel_coat's weight: Schlick in N·V, the viewer's direction (the extension's Discussion; the Sample Viewer)
        coat_weight = clearcoat * (coat_reflectance + (1.0 - coat_reflectance) * (1.0 - wo[:, 2:3]) ** 5)
        material = (1.0 - coat_weight) * material + coat_weight * coat_brdf
    return jnp.where(visible[:, None], material, 0.0)


def _with_sheen(material, sheen_color, sheen_roughness, wi, wo, h):
    """``material`` (N, 3) under KHR_materials_sheen's sheen of ``sheen_color`` (3,) or (), layered by albedo scaling
    as the Sample Viewer does for a light (``sheen.py`` has the lobe and ``E``)::

        sheen_color · D · V + min(1 − max(sheen_color) · E(N·V, r), 1 − max(sheen_color) · E(N·L, r)) · material
    """
    cos_i, cos_o = wi[:, 2], wo[:, 2]
    lobe = sheen_lobe(cos_i, cos_o, h[:, 2], sheen_roughness)[:, None]
    strongest = jnp.max(sheen_color)  # max3(sheenColor)
    scaling = jnp.minimum(
        1.0 - strongest * sheen_albedo(cos_o, sheen_roughness), 1.0 - strongest * sheen_albedo(cos_i, sheen_roughness)
    )
    return sheen_color * lobe + scaling[:, None] * material


def _is_zero(weight) -> bool:
    """Whether ``weight`` is the number 0 (not an array a program traces): its term is then skipped, not computed."""
    if isinstance(weight, tuple | list):
        return all(_is_zero(value) for value in weight)
    return isinstance(weight, int | float) and weight == 0


def _ggx_lobe(wi, wo, h, alpha_t, alpha_b, *, min_cos_h=0.0, max_visibility=math.inf):
    """``V · D`` (N, 1) of GGX with roughness ``alpha_t`` along the frame's ``x`` and ``alpha_b`` along its ``y``, the
    directions (N, 3) given in that frame: Appendix B's ``specular_brdf`` where the two are one ``α``, the
    anisotropic one of KHR_materials_anisotropy otherwise (the module docstring). ``D`` is Heitz's (2014, eq. 85) at
    ``N·H`` floored at ``min_cos_h``; ``V = G/(4 N·L N·V)`` with height-correlated Smith ``G = 1/(1 + Λ(L) + Λ(V))``
    (Heitz 2014, eq. 99), written as the Sample Viewer writes it,
    ``0.5 / (N·L |(α_t V_x, α_b V_y, N·V)| + N·V |(α_t L_x, α_b L_y, N·L)|)``, at most ``max_visibility``."""
    cos_h = jnp.maximum(h[:, 2], min_cos_h)
    distribution = ggx_anisotropic_distribution(h[:, 0], h[:, 1], cos_h, alpha_t, alpha_b)

    def stretched(w):  # |(α_t w_x, α_b w_y, w_z)|: w_z sqrt(1 + α(φ)² tan²θ), Smith's Λ = (that / w_z − 1)/2
        return jnp.sqrt((alpha_t * w[:, 0]) ** 2 + (alpha_b * w[:, 1]) ** 2 + w[:, 2] ** 2)

    visibility = 0.5 / (wi[:, 2] * stretched(wo) + wo[:, 2] * stretched(wi))
    return (jnp.minimum(visibility, max_visibility) * distribution)[:, None]
