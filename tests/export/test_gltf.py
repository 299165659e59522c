"""The glTF export: the glTF BRDF against its formulas written out by hand, its edges and energy; the fit that gives
a glTF material's parameters back; approximate exports that say how far they lie (and a retro-reflector that says
it cannot be one); the ``.gltf`` document and its atomic write."""

import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import directions_from_degrees, random_directions
from paths import TAPE

from brdffit import BrdfInputError, FitResult, fit, load_samples
from brdffit._version import __version__
from brdffit.export.approximate import dense_grid
from brdffit.export.gltf import EXTENSION_GAIN, fit_gltf, fit_material, write_gltf
from brdffit.export.gltf_material import GltfMaterial, gltf_brdf
from brdffit.fitting.single.caveats import ALBEDO_INCIDENCE, albedo_directions, albedo_quadrature
from brdffit.physics.geometry import in_turned_frame
from brdffit.physics.microfacet import ggx_lambda
from brdffit.physics.renderers.gltf import DEFAULT_F0, MIN_ANISOTROPY

#: Direction pairs (θi, φi, θo, φo in degrees) for golden values: near the mirror, off it, the exact mirror, grazing.
PAIRS_DEGREES = [(30, 0, 40, 180), (10, 0, 70, 90), (60, 20, 20, 250), (45, 0, 45, 180), (75, 0, 65, 160)]
PAIRS = (
    directions_from_degrees([p[0] for p in PAIRS_DEGREES], [p[1] for p in PAIRS_DEGREES]),
    directions_from_degrees([p[2] for p in PAIRS_DEGREES], [p[3] for p in PAIRS_DEGREES]),
)
#: Relative tolerance of a float64 computation against the same formula arranged differently: a few hundred ulp.
#: The roughnesses are ≥ 0.3 (α² ≥ 0.0081), so that GGX's 1 − (N·H)², computed in two ways, stays ≪ 1e-12 of α².
GOLDEN_RTOL = 1e-12
EXTENSION = {"specular": 0.6, "specular_color": (1.0, 0.7, 0.4), "ior": 1.8}
#: KHR_materials_clearcoat's and KHR_materials_anisotropy's factors (the coat's roughness ≥ 0.3, as GOLDEN_RTOL asks).
COAT = {"clearcoat": 0.7, "clearcoat_roughness": 0.35}
ANISOTROPY = {"anisotropy_strength": 0.7, "anisotropy_rotation": 0.6}
#: Pairs near the mirror at grazing angles, along and across the tangent of ANISOTROPY and between: where
#: N·L · N·V < 1/4, the anisotropic visibility's clamp to 1 binds.
GRAZING_DEGREES = [(75, 214.4, 75, 34.4), (70, 124.4, 80, 304.4), (80, 0, 78, 170), (65, 90, 72, 265)]
GRAZING = (
    directions_from_degrees([p[0] for p in GRAZING_DEGREES], [p[1] for p in GRAZING_DEGREES]),
    directions_from_degrees([p[2] for p in GRAZING_DEGREES], [p[3] for p in GRAZING_DEGREES]),
)


def golden_specular(roughness, wi, wo):
    """``specular_brdf = V · D`` of one pair (GGX D in Appendix B's form, the Sample Viewer's height-correlated
    visibility) and the Schlick weight ``(1 − |V·H|)⁵``, in plain numpy."""
    n_dot_l, n_dot_v = wi[2], wo[2]
    half = (wi + wo) / np.linalg.norm(wi + wo)
    n_dot_h, v_dot_h = half[2], abs(float(np.dot(wo, half)))
    alpha = roughness * roughness
    alpha2 = alpha * alpha
    distribution = alpha2 / (math.pi * (n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0) ** 2)
    visibility = 0.5 / (
        n_dot_l * math.sqrt(n_dot_v * n_dot_v * (1.0 - alpha2) + alpha2)
        + n_dot_v * math.sqrt(n_dot_l * n_dot_l * (1.0 - alpha2) + alpha2)
    )
    return visibility * distribution, (1.0 - v_dot_h) ** 5


def golden_anisotropic_specular(roughness, strength, rotation, wi, wo):
    """KHR_materials_anisotropy's ``V · D`` of one pair, in plain numpy from the extension's text: the tangent the
    data's +x turned counter-clockwise by ``rotation`` radians, the bitangent ``n × t``; ``α_t = mix(α, 1, s²)``,
    ``α_b = α`` (floored at 0.001, the Sample Viewer's ``clamp(alphaRoughness, 0.001, 1.0)``); Burley's D; the sample
    implementation's V, clamped to [0, 1]."""
    normal = np.array([0.0, 0.0, 1.0])
    tangent = np.array([math.cos(rotation), math.sin(rotation), 0.0])
    bitangent = np.cross(normal, tangent)
    alpha = roughness * roughness
    alpha_t = alpha * (1.0 - strength**2) + 1.0 * strength**2
    alpha_b = min(max(alpha, 0.001), 1.0)
    half = (wi + wo) / np.linalg.norm(wi + wo)
    n_dot_h = max(float(half @ normal), 0.001)
    t_dot_h, b_dot_h = float(half @ tangent), float(half @ bitangent)
    denominator = (t_dot_h / alpha_t) ** 2 + (b_dot_h / alpha_b) ** 2 + n_dot_h**2
    distribution = 1.0 / (math.pi * alpha_t * alpha_b * denominator**2)
    n_dot_l, n_dot_v = float(wi @ normal), float(wo @ normal)
    ggx_v = n_dot_l * np.linalg.norm([alpha_t * (tangent @ wo), alpha_b * (bitangent @ wo), n_dot_v])
    ggx_l = n_dot_v * np.linalg.norm([alpha_t * (tangent @ wi), alpha_b * (bitangent @ wi), n_dot_l])
    visibility = min(max(0.5 / (ggx_v + ggx_l), 0.0), 1.0)
    return visibility * distribution


def golden_gltf(
    base_color,
    metallic,
    roughness,
    wi,
    wo,
    specular=1.0,
    specular_color=(1.0, 1.0, 1.0),
    ior=1.5,
    f0=None,
    clearcoat=0.0,
    clearcoat_roughness=0.0,
    anisotropy_strength=0.0,
    anisotropy_rotation=0.0,
):
    """The glTF BRDF (3,) of one pair, as the specification and its extensions write it, in plain numpy: Schlick in
    |V·H|, fresnel_mix with the KHR_materials_specular weight and colour (``f0`` from the ior, or given), and the
    metal/dielectric mix; KHR_materials_anisotropy's lobe for both layers where its strength is not 0; and
    KHR_materials_clearcoat's ``mix(material, clearcoat_brdf, clearcoat · clearcoat_fresnel)``, the coat's Fresnel
    term Schlick's in |V·N| with the ior's ``f0`` (the Sample Viewer's; the extension's text fixes 1.5)."""
    base = np.asarray(base_color, dtype=float)
    specular_brdf, schlick = golden_specular(roughness, wi, wo)
    if anisotropy_strength > 0:
        specular_brdf = golden_anisotropic_specular(roughness, anisotropy_strength, anisotropy_rotation, wi, wo)
    metal_brdf = (base + (1.0 - base) * schlick) * specular_brdf
    if f0 is None:
        f0 = np.minimum(((1.0 - ior) / (1.0 + ior)) ** 2 * np.asarray(specular_color, dtype=float), 1.0)
    fresnel = f0 + (1.0 - f0) * schlick
    dielectric_brdf = (1.0 - specular * fresnel.max()) * base / math.pi + specular * fresnel * specular_brdf
    material = (1.0 - metallic) * dielectric_brdf + metallic * metal_brdf
    if clearcoat == 0:
        return material
    coat_f0 = ((1.0 - ior) / (1.0 + ior)) ** 2
    clearcoat_fresnel = coat_f0 + (1.0 - coat_f0) * (1.0 - abs(float(wo[2]))) ** 5
    clearcoat_brdf, _ = golden_specular(clearcoat_roughness, wi, wo)
    weight = clearcoat * clearcoat_fresnel
    return (1.0 - weight) * material + weight * clearcoat_brdf


def golden_single_f(base_color, metallic, roughness, wi, wo):
    """Appendix B's former "optimised" implementation (before glTF pull request #2392): one F of a mixed f0."""
    base = np.asarray(base_color, dtype=float)
    c_diff = (1.0 - metallic) * base
    f0 = (1.0 - metallic) * 0.04 + metallic * base
    specular_brdf, schlick = golden_specular(roughness, wi, wo)
    fresnel = f0 + (1.0 - f0) * schlick
    return (1.0 - fresnel) * c_diff / math.pi + fresnel * specular_brdf


def golden_rows(base_color, metallic, roughness, pairs=PAIRS, **extension):
    return np.array(
        [golden_gltf(base_color, metallic, roughness, a, b, **extension) for a, b in zip(*pairs, strict=True)]
    )


# ---------------------------------------------------------------------- the BRDF against its formulas
@pytest.mark.parametrize("metallic", [0.0, 1.0, 0.3])
@pytest.mark.parametrize("extension", [{}, EXTENSION], ids=["core", "extensions"])
def test_the_brdf_is_the_specifications_formula(metallic, extension):
    base, roughness = (0.8, 0.5, 0.2), 0.45
    computed = np.asarray(gltf_brdf(base, metallic, roughness, *PAIRS, **extension))
    np.testing.assert_allclose(computed, golden_rows(base, metallic, roughness, **extension), rtol=GOLDEN_RTOL)


@pytest.mark.parametrize("metallic", [0.0, 1.0, 0.3])
@pytest.mark.parametrize(
    "extension",
    [COAT, ANISOTROPY, COAT | ANISOTROPY, COAT | ANISOTROPY | EXTENSION],
    ids=["clearcoat", "anisotropy", "both", "all"],
)
def test_the_clear_coat_and_the_anisotropy_are_their_extensions_formulas(metallic, extension):
    base, roughness = (0.8, 0.5, 0.2), 0.45
    for pairs in (PAIRS, GRAZING):
        computed = np.asarray(gltf_brdf(base, metallic, roughness, *pairs, **extension))
        expected = golden_rows(base, metallic, roughness, pairs, **extension)
        np.testing.assert_allclose(computed, expected, rtol=GOLDEN_RTOL)


def test_the_anisotropic_visibility_is_clamped_where_the_sample_viewer_clamps_it():
    # The grazing pairs are where the clamp binds: their unclamped V exceeds 1, and the lobe is cut to V = 1 there.
    strength, rotation = ANISOTROPY["anisotropy_strength"], ANISOTROPY["anisotropy_rotation"]
    alpha = 0.45**2

    def unclamped(alpha_t, alpha_b):  # the sample implementation's V before its clamp
        light, viewer = (in_turned_frame(w, rotation) for w in GRAZING)
        stretched = [np.linalg.norm(w * [alpha_t, alpha_b, 1.0], axis=1) for w in (light, viewer)]
        return 0.5 / (light[:, 2] * stretched[1] + viewer[:, 2] * stretched[0])

    assert np.all(unclamped(alpha + (1 - alpha) * strength**2, alpha) > 1.0)
    # The core form has no clamp: where the strength reaches its threshold (1e-6, below which it is none, as a
    # material without the extension) the BRDF of a white metal jumps by the clamp's factor, min(1, 1/V).
    white = (1.0, 1.0, 1.0)
    at_the_threshold = np.asarray(gltf_brdf(white, 1.0, 0.45, *GRAZING, anisotropy_strength=MIN_ANISOTROPY))
    below = np.asarray(gltf_brdf(white, 1.0, 0.45, *GRAZING, anisotropy_strength=0.999 * MIN_ANISOTROPY))
    core = np.asarray(gltf_brdf(white, 1.0, 0.45, *GRAZING))
    np.testing.assert_allclose(below, core, rtol=1e-14)
    jump = np.minimum(1.0, 1.0 / unclamped(alpha, alpha))
    np.testing.assert_allclose(at_the_threshold / core, np.broadcast_to(jump[:, None], core.shape), rtol=1e-5)
    assert np.all(jump < 0.6)  # measured: 0.21 to 0.59 at these pairs (roughness 0.45)


def test_the_tangent_is_the_data_x_turned_counter_clockwise_by_the_rotation(rng):
    # Turning both directions and the rotation together about the normal changes nothing; turning the directions
    # alone does: the lobe has a direction, +x turned by anisotropy_rotation towards +y.
    wi, wo = random_directions(rng, 500), random_directions(rng, 500)
    turn = 0.9
    values = np.asarray(gltf_brdf((0.6, 0.5, 0.4), 0.5, 0.3, wi, wo, **ANISOTROPY))
    turned = [np.asarray(in_turned_frame(w, -turn)) for w in (wi, wo)]  # each direction turned by +0.9 rad
    moved = ANISOTROPY | {"anisotropy_rotation": ANISOTROPY["anisotropy_rotation"] + turn}
    np.testing.assert_allclose(np.asarray(gltf_brdf((0.6, 0.5, 0.4), 0.5, 0.3, *turned, **moved)), values, rtol=1e-12)
    assert np.max(np.abs(np.asarray(gltf_brdf((0.6, 0.5, 0.4), 0.5, 0.3, *turned, **ANISOTROPY)) / values - 1)) > 0.1
    # a half turn is the same lobe (anisotropy_rotation is an axis's: the model's domain is (−π/2, π/2])
    half_turn = ANISOTROPY | {"anisotropy_rotation": ANISOTROPY["anisotropy_rotation"] - math.pi}
    np.testing.assert_allclose(
        np.asarray(gltf_brdf((0.6, 0.5, 0.4), 0.5, 0.3, wi, wo, **half_turn)), values, rtol=1e-12
    )
    # stretched along the tangent: a viewer off the mirror direction by 10° along t sees more than one across it
    rotation = ANISOTROPY["anisotropy_rotation"]
    light = directions_from_degrees(45.0, math.degrees(rotation) + 180.0)
    along = directions_from_degrees(55.0, math.degrees(rotation))
    across = directions_from_degrees(45.0, math.degrees(rotation) + math.degrees(math.atan(math.tan(math.radians(10)))))
    assert float(np.asarray(gltf_brdf((0, 0, 0), 1.0, 0.3, light, along, **ANISOTROPY))[0, 0]) > 2 * float(
        np.asarray(gltf_brdf((0, 0, 0), 1.0, 0.3, light, across, **ANISOTROPY))[0, 0]
    )


def test_without_their_weights_the_extensions_are_the_core_model():
    base = (0.9, 0.6, 0.3)
    core = np.asarray(gltf_brdf(base, 0.3, 0.6, *PAIRS))
    # clearcoat 0 (a traced 0: gltf_material's compiled BRDF) is the core material to the bit: (1 − 0)·m + 0·coat
    uncoated = np.asarray(GltfMaterial(base, 0.3, 0.6, clearcoat_roughness=0.2).brdf(*PAIRS))
    np.testing.assert_array_equal(uncoated, np.asarray(GltfMaterial(base, 0.3, 0.6).brdf(*PAIRS)))
    # no anisotropy, whatever the rotation: the same lobe, the x and y components turned (rounding)
    for rotation in (0.0, 1.0, -1.4):
        round_lobe = gltf_brdf(
            base, 0.3, 0.6, *PAIRS, anisotropy_strength=jnp.asarray(0.0), anisotropy_rotation=rotation
        )
        np.testing.assert_allclose(np.asarray(round_lobe), core, rtol=1e-14)


def test_the_extensions_defaults_give_the_core_model_exactly():
    base = (0.9, 0.6, 0.3)
    core = np.asarray(gltf_brdf(base, 0.3, 0.6, *PAIRS))
    defaults = np.asarray(gltf_brdf(base, 0.3, 0.6, *PAIRS, specular=1.0, specular_color=(1, 1, 1), ior=1.5))
    np.testing.assert_array_equal(core, defaults)
    # and the core model is Appendix B's with f0 = 0.04 written as a number, not computed from the ior
    assert DEFAULT_F0 == pytest.approx(0.04, rel=1e-15)
    np.testing.assert_allclose(core, golden_rows(base, 0.3, 0.6, f0=np.full(3, 0.04)), rtol=GOLDEN_RTOL)


def test_ior_zero_makes_the_specular_colour_the_reflectance_at_normal_incidence():
    # KHR_materials_ior: ior = 0 gives f0 = 1, so with KHR_materials_specular f0 = specularColor.
    colour = (0.9, 0.5, 0.2)
    computed = np.asarray(gltf_brdf((0.3, 0.3, 0.3), 0.0, 0.5, *PAIRS, specular=0.4, specular_color=colour, ior=0.0))
    expected = golden_rows((0.3, 0.3, 0.3), 0.0, 0.5, specular=0.4, specular_color=colour, ior=0.0)
    np.testing.assert_allclose(computed, expected, rtol=GOLDEN_RTOL)


def test_the_former_single_f_form_equals_the_mix_only_at_metallic_0_and_1():
    base, roughness = np.array([1.0, 0.5, 0.04]), 0.5
    for metallic in (0.0, 1.0):
        mix = golden_rows(base, metallic, roughness)
        single = np.array([golden_single_f(base, metallic, roughness, a, b) for a, b in zip(*PAIRS, strict=True)])
        np.testing.assert_allclose(single, mix, rtol=GOLDEN_RTOL)
    # In between they differ in the diffuse term alone, by m (1 − m)(baseColor − 0.04) baseColor (1 − |V·H|)⁵ / π
    # below the mix (the module docstring); 0 where baseColor is 0.04.
    metallic = 0.3
    mix = np.asarray(gltf_brdf(base, metallic, roughness, *PAIRS))
    single = np.array([golden_single_f(base, metallic, roughness, a, b) for a, b in zip(*PAIRS, strict=True)])
    halves = PAIRS[0] + PAIRS[1]
    v_dot_h = np.abs(np.sum(PAIRS[1] * halves / np.linalg.norm(halves, axis=1, keepdims=True), axis=1))
    lost = metallic * (1 - metallic) * (base - 0.04) * base * (1.0 - (1.0 - v_dot_h[:, None]) ** 5) / math.pi
    np.testing.assert_allclose(mix - single, lost, rtol=1e-9, atol=1e-15)
    assert np.all(lost[:, 0] > 0.05)  # base colour 1: 0.21 · 0.96 (1 − (1 − |V·H|)⁵)/π, up to 0.064 1/sr
    # At normal incidence, base colour 1 and metallic 0.5 the single-F diffuse term is half the mix's.
    up = np.array([[0.0, 0.0, 1.0]])
    white_mix = float(np.asarray(gltf_brdf((1.0, 1.0, 1.0), 0.5, 1.0, up, up))[0, 0])
    white_single = float(golden_single_f(np.ones(3), 0.5, 1.0, up[0], up[0])[0])
    assert white_mix - white_single == pytest.approx(0.5 * 0.96 / (2 * math.pi), rel=1e-12)  # 0.0764 1/sr


def test_appendix_b_separable_smith_is_darker_by_the_product_of_the_lambdas():
    # The module docstring's numbers: G1(L) G1(V) / G_correlated = 1 − Λ(L)Λ(V)/((1 + Λ(L))(1 + Λ(V))).
    for alpha, darker in ((0.25, 0.00184), (1.0, 1.0 / 9.0)):
        lam = float(ggx_lambda(0.5, alpha))  # both directions at 60° from the normal
        separable, correlated = 1.0 / (1.0 + lam) ** 2, 1.0 / (1.0 + 2.0 * lam)
        assert 1.0 - separable / correlated == pytest.approx(lam * lam / (1.0 + lam) ** 2, rel=1e-12)
        assert 1.0 - separable / correlated == pytest.approx(darker, abs=1e-5)


# ---------------------------------------------------------------------- edges
def test_reciprocal_and_zero_below_the_horizon(rng):
    wi, wo = random_directions(rng, 500), random_directions(rng, 500)
    for extension in ({}, EXTENSION, ANISOTROPY, ANISOTROPY | {"anisotropy_strength": 1.0}):
        forward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wi, wo, **extension))
        backward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wo, wi, **extension))
        np.testing.assert_allclose(forward, backward, rtol=1e-12)
    below = wo * np.array([1.0, 1.0, -1.0])
    horizon = np.column_stack([wo[:, :2] / np.linalg.norm(wo[:, :2], axis=1, keepdims=True), np.zeros(500)])
    for other in (below, horizon):
        assert np.all(np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wi, other)) == 0.0)
        assert np.all(np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, other, wi)) == 0.0)


def test_the_clear_coat_is_not_reciprocal_by_its_fresnel_term_of_the_viewer(rng):
    # KHR_materials_clearcoat weights the coat by Schlick's term in N·V: swapping light and viewer changes the weight
    # (and nothing else), so f(wi, wo) − f(wo, wi) is that change times (coat − material), as written out.
    wi, wo = random_directions(rng, 300), random_directions(rng, 300)
    base, metallic, roughness = (0.7, 0.4, 0.2), 0.3, 0.4
    forward = np.asarray(gltf_brdf(base, metallic, roughness, wi, wo, **COAT))
    backward = np.asarray(gltf_brdf(base, metallic, roughness, wo, wi, **COAT))
    material = np.asarray(gltf_brdf(base, metallic, roughness, wi, wo))  # reciprocal
    coat = np.asarray(gltf_brdf((0.0, 0.0, 0.0), 0.0, COAT["clearcoat_roughness"], wi, wo, specular_color=(25,) * 3))
    schlick = lambda w: 0.04 + 0.96 * (1.0 - w[:, 2:3]) ** 5
    expected = COAT["clearcoat"] * (schlick(wo) - schlick(wi)) * (coat - material)
    np.testing.assert_allclose(forward - backward, expected, rtol=1e-9, atol=1e-12 * np.max(forward))
    # e.g. light at 10°, viewer at 80° across the mirror (the viewer's Schlick term 0.41, the light's 0.04): 20%, 15%
    # and 5% less than the other way round, the brighter the base, the more
    light, viewer = directions_from_degrees(10.0, 0.0), directions_from_degrees(80.0, 180.0)
    ratio = np.asarray(gltf_brdf(base, 0.0, 0.5, light, viewer, **COAT)) / np.asarray(
        gltf_brdf(base, 0.0, 0.5, viewer, light, **COAT)
    )
    np.testing.assert_allclose(ratio, [[0.801, 0.849, 0.951]], atol=1e-3)


def test_finite_values_and_gradients_at_grazing_angles_and_small_roughness():
    grazing = directions_from_degrees([89.9, 89.9, 89.9, 30.0], [0.0, 0.0, 0.0, 0.0])
    viewers = directions_from_degrees([89.9, 89.9, 0.0, 89.9], [180.0, 0.0, 0.0, 90.0])

    def total(parameters):
        base, metallic, roughness, specular, colour, ior = parameters
        values = gltf_brdf(
            base, metallic, roughness, grazing, viewers, specular=specular, specular_color=colour, ior=ior
        )
        return jnp.sum(values)

    for roughness in (0.02, 0.001, 1.0):
        parameters = (jnp.array([0.5, 0.4, 0.3]), 0.3, roughness, 0.7, jnp.array([1.0, 0.8, 0.6]), 1.6)
        assert np.all(np.isfinite(np.asarray(gltf_brdf(parameters[0], 0.3, roughness, grazing, viewers))))
        gradients = jax.grad(total)(parameters)
        assert all(np.all(np.isfinite(np.asarray(g))) for g in gradients)
    # the mirror pair at θ = 89.9° with roughness 0.02 is a sharp, large peak, but finite
    peak = np.asarray(gltf_brdf((0.5, 0.5, 0.5), 1.0, 0.02, grazing[:1], viewers[:1]))
    assert np.all(np.isfinite(peak)) and np.all(peak > 1e3)


@pytest.mark.parametrize("strength", [0.0, 0.5 * MIN_ANISOTROPY, MIN_ANISOTROPY, 0.3, 1.0])
@pytest.mark.parametrize("roughness", [0.001, 0.02, 1.0])
def test_the_extensions_are_finite_with_finite_gradients_at_grazing_angles(strength, roughness):
    # every parameter traced (as the fit's are), the coat from smooth to rough, the anisotropy on either side of its
    # threshold: values and derivatives finite at 89.9° (the directions of the test above)
    grazing = directions_from_degrees([89.9, 89.9, 89.9, 30.0, 89.9], [0.0, 0.0, 0.0, 0.0, 45.0])
    viewers = directions_from_degrees([89.9, 89.9, 0.0, 89.9, 89.9], [180.0, 0.0, 0.0, 90.0, 225.0])

    def total(parameters):
        base, metallic, rough, coat, coat_roughness, anisotropy, rotation = parameters
        values = gltf_brdf(
            base,
            metallic,
            rough,
            grazing,
            viewers,
            clearcoat=coat,
            clearcoat_roughness=coat_roughness,
            anisotropy_strength=anisotropy,
            anisotropy_rotation=rotation,
        )
        return jnp.sum(values)

    for coat_roughness in (0.0, 0.001, 1.0):
        parameters = (jnp.array([0.5, 0.4, 0.3]), 0.3, roughness, 0.8, coat_roughness, strength, 0.7)
        parameters = tuple(jnp.asarray(p, dtype=jnp.float64) for p in parameters)
        assert np.isfinite(float(total(parameters)))
        gradients = jax.grad(total)(parameters)
        assert all(np.all(np.isfinite(np.asarray(g))) for g in gradients), (coat_roughness, gradients)


def white_albedos(metallic, roughness, n=512, **extension):
    """Directional albedos (incidences of ALBEDO_INCIDENCE) of a white glTF material, by the fit caveats' midpoint
    rule in (cos θo, φo), checked against the grid half as fine (within 1%: the grid resolves the lobe)."""
    wi, wo = albedo_directions(n)
    values = np.asarray(gltf_brdf((1.0, 1.0, 1.0), metallic, roughness, wi, wo, **extension))
    fine, coarse = albedo_quadrature(values, n)
    assert np.all(np.abs(fine - coarse) <= 0.01 * fine), "the grid does not resolve the lobe"
    return fine[:, 0]


@pytest.mark.parametrize("roughness", [0.5, 0.75, 1.0])
def test_a_white_metal_loses_energy_and_never_gains(roughness):
    # Single-scattering GGX (the metal, and the layer alone: ior 0 makes fr = 1) loses the light that scatters more
    # than once between microfacets: below 1 at every incidence, more so the rougher (0.92, 0.63, 0.31 at normal
    # incidence). The 0.5% margin is ALBEDO_LIMIT's (caveats.py), for the quadrature.
    metal = white_albedos(1.0, roughness)
    layer = white_albedos(0.0, roughness, specular=1.0, specular_color=(1.0, 1.0, 1.0), ior=0.0)
    np.testing.assert_allclose(layer, metal, rtol=1e-12)
    assert np.all(metal <= 1.005), dict(zip(ALBEDO_INCIDENCE, metal, strict=True))


def test_the_dielectric_fresnel_mix_gains_energy_at_grazing_incidence():
    # Not brdffit's doing: Appendix B's fresnel_mix weights the diffuse base by 1 − fr of each pair's |V·H|, not by
    # the layer's directional albedo, so a white dielectric reflects more than it receives where the specular lobe's
    # Fresnel term is large and the diffuse term loses less: measured (n = 256 and 512 agree to 1e-4):
    # 1.011 at θi = 60° and 1.082 at 80° for roughness 0.5; 1.013 at 80° for 0.75; below 1 for roughness 1.
    # (The specification points to Kulla & Conty 2017's albedo scaling for an energy-conserving coupling.)
    smooth = white_albedos(0.0, 0.5)
    assert np.all(smooth[:2] <= 1.0)  # θi = 0°, 30°
    np.testing.assert_allclose(smooth[2:], [1.011, 1.082], atol=0.002)
    assert white_albedos(0.0, 0.75)[-1] == pytest.approx(1.013, abs=0.002)
    assert np.all(white_albedos(0.0, 1.0) <= 1.0)
    assert np.all(white_albedos(0.5, 0.5) <= 1.0)  # half metal: the metal's loss outweighs the gain


def test_the_clear_coat_gains_energy_at_grazing_incidence_as_its_fresnel_term_is_the_viewers():
    # KHR_materials_clearcoat weights the coat by the viewer's Schlick term: for one viewer, the light it receives
    # from the whole hemisphere (∫ f cos θi dωi) is a mix of the base's and the coat's, as the extension says; for
    # one light, what leaves (∫ f cos θo dωo, the directional albedo the fit's caveats measure) is not: light at a
    # grazing incidence meets the base's full weight and, towards grazing viewers, the coat's large one. Measured
    # (n = 256 and 512 agree to 1e-4): a white dielectric of roughness 0.5 under a full coat of roughness 0.3
    # reflects 1.23 at θi = 80° (1.08 bare; test_the_dielectric_fresnel_mix_gains_energy_at_grazing_incidence).
    full_coat = {"clearcoat": 1.0, "clearcoat_roughness": 0.3}
    coated = white_albedos(0.0, 0.5, **full_coat)
    np.testing.assert_allclose(coated, [0.955, 0.957, 1.012, 1.227], atol=0.002)
    # the viewer's side: the same quadrature with the roles swapped (the grid's "incidence" is now the viewer's)
    wi, wo = albedo_directions(512)
    values = np.asarray(gltf_brdf((1.0, 1.0, 1.0), 0.0, 0.5, wo, wi, **full_coat))
    seen = albedo_quadrature(values, 512)[0][:, 0]
    bare = white_albedos(0.0, 0.5)
    assert np.all(seen <= np.maximum(bare, 1.0) + 0.005), (seen, bare)


@pytest.mark.parametrize("strength", [0.5, 1.0])
def test_the_anisotropic_metal_never_gains_energy(strength):
    # Single scattering, and the visibility's clamp only takes light away: a white anisotropic metal's albedo stays
    # below 1 at every incidence (the lobe stretched along +x, the light's azimuth: its widest).
    albedos = white_albedos(1.0, 0.5, anisotropy_strength=strength, anisotropy_rotation=0.0)
    assert np.all(albedos <= 1.005), albedos


# ---------------------------------------------------------------------- the material
def test_the_material_checks_its_factors_with_one_line_naming_them():
    cases = [
        ({"base_color": (1.2, 0.5, 0.5)}, "base_color=(1.2, 0.5, 0.5) is not allowed"),
        ({"base_color": (0.5, 0.5)}, "base_color=(0.5, 0.5) is not allowed"),
        ({"metallic": -0.1}, "metallic=-0.1 is not allowed; give a number in [0, 1]"),
        ({"roughness": float("nan")}, "roughness=nan is not allowed"),
        ({"specular": 2.0}, "specular=2.0 is not allowed"),
        ({"specular_color": (1.0, -1.0, 0.0)}, "specular_color=(1.0, -1.0, 0.0) is not allowed"),
        ({"ior": 0.5}, "ior=0.5 is not allowed; give 0 or a finite number ≥ 1"),
        ({"clearcoat": 1.5}, "clearcoat=1.5 is not allowed; give a number in [0, 1]"),
        ({"clearcoat_roughness": -0.2}, "clearcoat_roughness=-0.2 is not allowed; give a number in [0, 1]"),
        ({"anisotropy_strength": True}, "anisotropy_strength=True is not allowed; give a number in [0, 1]"),
        ({"anisotropy_rotation": math.inf}, "anisotropy_rotation=inf is not allowed; give a finite number (radians)"),
    ]
    for change, message in cases:
        arguments = {"base_color": (0.5, 0.5, 0.5), "metallic": 0.0, "roughness": 0.5} | change
        with pytest.raises(BrdfInputError) as error:
            GltfMaterial(**arguments)
        assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_the_material_brdf_is_the_gltf_brdf(rng):
    wi, wo = random_directions(rng, 100), random_directions(rng, 100)
    layered = GltfMaterial((0.8, 0.5, 0.2), 0.3, 0.45, **EXTENSION, **COAT, **ANISOTROPY)
    expected = gltf_brdf((0.8, 0.5, 0.2), 0.3, 0.45, wi, wo, **EXTENSION, **COAT, **ANISOTROPY)
    np.testing.assert_allclose(layered.brdf(wi, wo), np.asarray(expected), rtol=1e-14)
    material = GltfMaterial((0.8, 0.5, 0.2), 0.3, 0.45, **EXTENSION)
    # compiled (material.brdf) and traced op by op (gltf_brdf): the same operations, rounded by XLA's fusions
    np.testing.assert_allclose(
        material.brdf(wi, wo), np.asarray(gltf_brdf((0.8, 0.5, 0.2), 0.3, 0.45, wi, wo, **EXTENSION)), rtol=1e-14
    )
    core = GltfMaterial((0.8, 0.5, 0.2), 0.3, 0.45)
    np.testing.assert_allclose(core.brdf(wi, wo), np.asarray(gltf_brdf((0.8, 0.5, 0.2), 0.3, 0.45, wi, wo)), rtol=1e-14)


def test_the_document_is_gltf_with_extensions_only_when_used():
    core = GltfMaterial((0.8, 0.5, 0.2), 0.0, 0.45).to_gltf("plastic", extras={"brdffit": {"rmse": 0.01}})
    json.dumps(core, allow_nan=False)  # strict JSON
    assert core["asset"] == {"version": "2.0", "generator": f"brdffit {__version__}"}
    assert "extensionsUsed" not in core and "extensionsRequired" not in core
    (material,) = core["materials"]
    assert material["name"] == "plastic" and "extensions" not in material
    assert material["extras"] == {"brdffit": {"rmse": 0.01}}
    factors = material["pbrMetallicRoughness"]
    assert factors == {"baseColorFactor": [0.8, 0.5, 0.2, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.45}

    extended = GltfMaterial((0.8, 0.5, 0.2), 0.0, 0.45, **EXTENSION).to_gltf("coated")
    assert extended["extensionsUsed"] == ["KHR_materials_specular", "KHR_materials_ior"]
    extensions = extended["materials"][0]["extensions"]
    assert extensions == {
        "KHR_materials_specular": {"specularFactor": 0.6, "specularColorFactor": [1.0, 0.7, 0.4]},
        "KHR_materials_ior": {"ior": 1.8},
    }
    assert "extras" not in extended["materials"][0]
    only_specular = GltfMaterial((0.8, 0.5, 0.2), 0.0, 0.45, specular=0.5).to_gltf("weak")
    assert only_specular["extensionsUsed"] == ["KHR_materials_specular"]
    # the coat and the anisotropy where their weights are not 0, each with both its factors
    layered = GltfMaterial((0.8, 0.5, 0.2), 1.0, 0.45, **COAT, **ANISOTROPY).to_gltf("brushed, lacquered")
    assert layered["extensionsUsed"] == ["KHR_materials_clearcoat", "KHR_materials_anisotropy"]
    assert layered["materials"][0]["extensions"] == {
        "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.35},
        "KHR_materials_anisotropy": {"anisotropyStrength": 0.7, "anisotropyRotation": 0.6},
    }
    assert layered["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] == 2  # the lobe's direction on the mesh
    unused = GltfMaterial((0.8, 0.5, 0.2), 0.0, 0.45, clearcoat_roughness=0.3, anisotropy_rotation=1.0)
    assert unused.extensions == () and "extensions" not in unused.material_object("none")
    faint = GltfMaterial((0.8, 0.5, 0.2), 0.0, 0.45, anisotropy_strength=0.5 * MIN_ANISOTROPY)
    assert faint.anisotropy_strength == 0.0 and faint.extensions == ()  # none, as the BRDF takes it


# ---------------------------------------------------------------------- the fit
RECOVERED = [
    GltfMaterial((0.6, 0.3, 0.1), 0.0, 0.4),  # a plastic
    GltfMaterial((0.9, 0.7, 0.4), 1.0, 0.3),  # a metal
    GltfMaterial((0.5, 0.5, 0.2), 0.3, 0.6),  # in between
    GltfMaterial((0.6, 0.3, 0.1), 0.0, 0.4, **EXTENSION),  # a coloured coat on a plastic
    GltfMaterial((0.15, 0.1, 0.05), 0.0, 0.37, specular=0.03, specular_color=(1.0, 0.9, 0.6), ior=0.0),  # flat F
]


@pytest.mark.slow
@pytest.mark.parametrize("truth", RECOVERED, ids=["plastic", "metal", "between", "coat", "flat-fresnel"])
def test_the_fit_gives_a_gltf_materials_parameters_back(truth):
    wi, wo = dense_grid()
    material, notes = fit_material(wi, wo, truth.brdf(wi, wo), "log")
    assert material.extensions == truth.extensions, notes
    expected = [*truth.base_color, truth.metallic, truth.roughness]
    found = [*material.base_color, material.metallic, material.roughness]
    if truth.extensions:
        expected += [truth.specular, *truth.specular_color, truth.ior]
        found += [material.specular, *material.specular_color, material.ior]
    np.testing.assert_allclose(found, expected, atol=1e-3)


def test_a_grey_fit_gives_a_grey_material():
    wi, wo = dense_grid()
    truth = GltfMaterial((0.4, 0.4, 0.4), 0.0, 0.5)
    material, _ = fit_material(wi, wo, truth.brdf(wi, wo)[:, :1], "l2")
    assert material.base_color[0] == material.base_color[1] == material.base_color[2]
    np.testing.assert_allclose([material.base_color[0], material.roughness], [0.4, 0.5], atol=1e-3)


def test_fit_material_refuses_values_it_cannot_fit():
    wi, wo = dense_grid((2, 3, 4))
    with pytest.raises(BrdfInputError, match=r"^values has shape \(24, 2\); give \(N, 3\)"):
        fit_material(wi, wo, np.ones((24, 2)))
    with pytest.raises(BrdfInputError, match="'lsq' is not a loss"):
        fit_material(wi, wo, np.ones((24, 3)), "lsq")


def result_of(model: str, params: dict, channels=("r", "g", "b"), **options) -> FitResult:
    """A result with known parameters, without fitting."""
    return FitResult(model, options, tuple(channels), params, "log", 0.0, 0.0, 0, 0, True)


#: Cook-Torrance with glTF's own lobe (GGX, height-correlated Smith, Schlick with f0 0.04, ks 1, m = roughness²):
#: it differs from glTF's dielectric only by the diffuse term's (1 − F), at most F·kd/π.
GLTF_LIKE_COOK_TORRANCE = {"kd": [0.3, 0.26, 0.18], "ks": [1.0, 1.0, 1.0], "m": 0.09, "f0": 0.04}


def test_a_cook_torrance_ggx_smith_fit_exports_with_a_small_error():
    options = {"fresnel": "schlick", "distribution": "ggx", "shadowing": "smith-correlated"}
    material, approximation = fit_gltf(result_of("cook-torrance", GLTF_LIKE_COOK_TORRANCE, **options))
    # measured: rmse 1.4% of the BRDF's rms over the hemisphere and the plane of incidence (0.6% over the hemisphere
    # alone: the (1 − F) of glTF's diffuse term differs most at grazing mirror pairs), directional albedo within 0.92%
    assert approximation.relative_rmse < 0.02 and approximation.albedo_error < 0.015
    assert material.extensions == () and material.metallic < 0.01
    np.testing.assert_allclose(material.roughness, 0.3, atol=0.005)
    np.testing.assert_allclose(material.base_color, [0.3, 0.26, 0.18], rtol=0.05)


#: Ngan et al. 2005's Ward fit of MERL's pickled oak (the shipped example's truth).
OAK = {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}


def test_write_gltf_writes_the_document_with_the_approximation_atomically(tmp_path):
    path = tmp_path / "oak.gltf"
    path.write_text("an older file")
    material, approximation, notes = write_gltf(result_of("ward", OAK), path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["oak.gltf"]  # no temporary file left
    document = json.loads(path.read_text(encoding="utf-8"))
    assert document == json.loads(json.dumps(material.to_gltf("oak", document["materials"][0]["extras"])))
    extras = document["materials"][0]["extras"]["brdffit"]
    assert extras["approximation"] == approximation.to_dict()
    assert extras["source"] == {
        "model": "ward",
        "model_options": {},
        "channels": ["r", "g", "b"],
        "loss": "log",
        "params": OAK,
    }
    assert extras["notes"] == notes and extras["version"] == __version__
    factors = document["materials"][0]["pbrMetallicRoughness"]
    assert all(0.0 <= value <= 1.0 for value in factors["baseColorFactor"])
    assert 0.0 <= factors["metallicFactor"] <= 1.0 and 0.0 <= factors["roughnessFactor"] <= 1.0
    # Ward has no Fresnel term; glTF's dielectric rises to 1 at grazing angles unless KHR_materials_specular and
    # KHR_materials_ior flatten it (ior 0: f0 = the specular colour). measured: rmse 0.0199 1/sr (43%) against
    # 0.0370 without the extensions; the lobe comes out as Ward's (roughness² ≈ α, specular ≈ rho_s).
    assert (
        set(document["extensionsUsed"])
        == set(material.extensions)
        == {
            "KHR_materials_specular",
            "KHR_materials_ior",
        }
    )
    assert notes[0].startswith("KHR_materials_specular and KHR_materials_ior used")
    assert f"at least {EXTENSION_GAIN:.0%}" in notes[0]
    np.testing.assert_allclose(material.roughness**2, OAK["alpha"], rtol=0.1)
    np.testing.assert_allclose(material.base_color, OAK["rho_d"], rtol=0.1)


def test_write_gltf_refuses_bad_input_with_one_line_and_writes_nothing(tmp_path):
    path = tmp_path / "kept.gltf"
    path.write_text("kept")
    two_channels = result_of("lambert", {"rho_d": [0.5, 0.4]}, channels=("c0", "c1"))
    failures = [
        (two_channels, path, "result has 2 channels (c0, c1); a glTF material takes three"),
        (result_of("lambert", {"rho_d": [0.5, 0.4, 0.3]}), tmp_path / "missing" / "oak.gltf", "the folder"),
        ({"model": "ward"}, path, "result must be a FitResult, not dict"),
    ]
    for result, where, message in failures:
        with pytest.raises(BrdfInputError) as error:
            write_gltf(result, where)
        assert message in str(error.value) and "\n" not in str(error.value)
    assert path.read_text() == "kept" and sorted(p.name for p in tmp_path.iterdir()) == ["kept.gltf"]


def test_xyz_channels_are_converted_and_compared_in_xyz():
    # A grey Lambertian in XYZ (D65 white: x, y, z ∝ 0.9505, 1, 1.089) is a grey material in linear sRGB.
    xyz = result_of("lambert", {"rho_d": [0.9505 * 0.4, 0.4, 1.089 * 0.4]}, channels=("x", "y", "z"))
    material, approximation = fit_gltf(xyz)
    np.testing.assert_allclose(material.base_color, [0.4, 0.4, 0.4], atol=2e-3)
    assert approximation.albedo_channel in ("x", "y", "z") and approximation.relative_rmse < 0.05


def test_a_retro_reflector_says_it_cannot_be_a_gltf_material(tmp_path):
    # The real tape: its 2-lobe Lafortune fit sends light back towards the light, which no glTF material does.
    tape = fit(load_samples(TAPE, quantity="cosine-weighted-out"), "lafortune", lobes=2)
    material, approximation, notes = write_gltf(tape, tmp_path / "tape.gltf")
    # measured: rmse 1.40 1/sr, 101% of the BRDF's rms; directional albedo within 54% (θi = 80°)
    assert approximation.relative_rmse > 0.5
    assert notes[0].startswith("one channel (value): the material is grey")
    assert any("retro-reflective" in note and "no glTF material can reproduce it" in note for note in notes)
    assert any("misses most of this BRDF's shape" in note for note in notes)
    assert material.base_color[0] == material.base_color[1] == material.base_color[2]
