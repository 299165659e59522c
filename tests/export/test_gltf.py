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
from brdffit.physics.microfacet import ggx_lambda
from brdffit.physics.renderers.gltf import DEFAULT_F0

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


def golden_gltf(
    base_color, metallic, roughness, wi, wo, specular=1.0, specular_color=(1.0, 1.0, 1.0), ior=1.5, f0=None
):
    """The glTF BRDF (3,) of one pair, as the specification and its extensions write it, in plain numpy: Schlick in
    |V·H|, fresnel_mix with the KHR_materials_specular weight and colour (``f0`` from the ior, or given), and the
    metal/dielectric mix."""
    base = np.asarray(base_color, dtype=float)
    specular_brdf, schlick = golden_specular(roughness, wi, wo)
    metal_brdf = (base + (1.0 - base) * schlick) * specular_brdf
    if f0 is None:
        f0 = np.minimum(((1.0 - ior) / (1.0 + ior)) ** 2 * np.asarray(specular_color, dtype=float), 1.0)
    fresnel = f0 + (1.0 - f0) * schlick
    dielectric_brdf = (1.0 - specular * fresnel.max()) * base / math.pi + specular * fresnel * specular_brdf
    return (1.0 - metallic) * dielectric_brdf + metallic * metal_brdf


def golden_single_f(base_color, metallic, roughness, wi, wo):
    """Appendix B's former "optimised" implementation (before glTF pull request #2392): one F of a mixed f0."""
    base = np.asarray(base_color, dtype=float)
    c_diff = (1.0 - metallic) * base
    f0 = (1.0 - metallic) * 0.04 + metallic * base
    specular_brdf, schlick = golden_specular(roughness, wi, wo)
    fresnel = f0 + (1.0 - f0) * schlick
    return (1.0 - fresnel) * c_diff / math.pi + fresnel * specular_brdf


def golden_rows(base_color, metallic, roughness, **extension):
    return np.array(
        [golden_gltf(base_color, metallic, roughness, a, b, **extension) for a, b in zip(*PAIRS, strict=True)]
    )


# ---------------------------------------------------------------------- the BRDF against its formulas
@pytest.mark.parametrize("metallic", [0.0, 1.0, 0.3])
@pytest.mark.parametrize("extension", [{}, EXTENSION], ids=["core", "extensions"])
def test_the_brdf_is_the_specifications_formula(metallic, extension):
    base, roughness = (0.8, 0.5, 0.2), 0.45
    computed = np.asarray(gltf_brdf(base, metallic, roughness, *PAIRS, **extension))
    np.testing.assert_allclose(computed, golden_rows(base, metallic, roughness, **extension), rtol=GOLDEN_RTOL)


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
    for extension in ({}, EXTENSION):
        forward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wi, wo, **extension))
        backward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wo, wi, **extension))
        np.testing.assert_allclose(forward, backward, rtol=1e-12)
    below = wo * np.array([1.0, 1.0, -1.0])
    horizon = np.column_stack([wo[:, :2] / np.linalg.norm(wo[:, :2], axis=1, keepdims=True), np.zeros(500)])
    for other in (below, horizon):
        assert np.all(np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, wi, other)) == 0.0)
        assert np.all(np.asarray(gltf_brdf((0.7, 0.4, 0.2), 0.3, 0.4, other, wi)) == 0.0)


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
    ]
    for change, message in cases:
        arguments = {"base_color": (0.5, 0.5, 0.5), "metallic": 0.0, "roughness": 0.5} | change
        with pytest.raises(BrdfInputError) as error:
            GltfMaterial(**arguments)
        assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_the_material_brdf_is_the_gltf_brdf(rng):
    wi, wo = random_directions(rng, 100), random_directions(rng, 100)
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


# ---------------------------------------------------------------------- the fit
RECOVERED = [
    GltfMaterial((0.6, 0.3, 0.1), 0.0, 0.4),  # a plastic
    GltfMaterial((0.9, 0.7, 0.4), 1.0, 0.3),  # a metal
    GltfMaterial((0.5, 0.5, 0.2), 0.3, 0.6),  # in between
    GltfMaterial((0.6, 0.3, 0.1), 0.0, 0.4, **EXTENSION),  # a coloured coat on a plastic
    GltfMaterial((0.15, 0.1, 0.05), 0.0, 0.37, specular=0.03, specular_color=(1.0, 0.9, 0.6), ior=0.0),  # flat F
]


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
