"""glTF's BRDF under KHR_materials_sheen (``physics/renderers/gltf.py``, ``sheen.py``): the extension's formula with
the Sample Viewer's layering, reciprocal where the viewer's scaling takes the smaller of the viewer's and the light's,
the core material to the bit without a sheen, finite values and derivatives at the edges, and the energy it keeps."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import directions_from_degrees, random_directions

from brdffit import BrdfInputError
from brdffit.export.gltf_material import GltfMaterial, gltf_brdf
from brdffit.fitting.single.caveats import ALBEDO_INCIDENCE, albedo_directions, albedo_quadrature
from brdffit.physics.renderers.sheen import albedo_quadrature as sheen_albedo_quadrature
from brdffit.physics.renderers.sheen import sheen_albedo

#: Direction pairs (θi, φi, θo, φo in degrees): off the mirror, back towards the light, grazing, the normal.
PAIRS_DEGREES = [(30, 0, 40, 180), (10, 0, 70, 90), (60, 20, 20, 250), (75, 0, 80, 30), (85, 0, 80, 200), (0, 0, 50, 0)]
PAIRS = (
    directions_from_degrees([p[0] for p in PAIRS_DEGREES], [p[1] for p in PAIRS_DEGREES]),
    directions_from_degrees([p[2] for p in PAIRS_DEGREES], [p[3] for p in PAIRS_DEGREES]),
)
SHEEN = {"sheen_color": (0.6, 0.5, 0.4), "sheen_roughness": 0.5}
COAT = {"clearcoat": 0.7, "clearcoat_roughness": 0.35}
#: The interpolated E lies within 2e-3 of the quadrature's (tests/physics/test_sheen.py): with max(sheen_color) = 0.6,
#: the base's scaling within 1.2e-3 of its own, and the BRDF within that fraction of itself.
E_RTOL = 0.6 * 2e-3


def golden_sheen(sheen_roughness, wi, wo):
    """The extension's sheen BRDF ``D · V`` (colour 1) of one pair, in plain Python from its "Implementation Notes":
    ``alpha_g = sheenRoughness²``, Charlie's distribution and visibility, the viewer's clamp of V to [0, 1]."""
    alpha = sheen_roughness * sheen_roughness
    half = (wi + wo) / np.linalg.norm(wi + wo)
    sin2_h = 1.0 - half[2] * half[2]
    distribution = (2.0 + 1.0 / alpha) * sin2_h ** (0.5 / alpha) / (2.0 * math.pi)

    def l(x):  # noqa: E743 (the extension's name)
        t = (1.0 - alpha) ** 2
        mix = lambda p0, p1: p0 * (1.0 - t) + p1 * t
        a, b, c = mix(21.5473, 25.3245), mix(3.82987, 3.32435), mix(0.19823, 0.16801)
        d, e = mix(-1.97760, -1.27393), mix(-4.32054, -4.85967)
        return a / (1.0 + b * x**c) + d * x + e

    def lam(cos_theta):
        return math.exp(l(cos_theta)) if abs(cos_theta) < 0.5 else math.exp(2.0 * l(0.5) - l(1.0 - cos_theta))

    n_dot_l, n_dot_v = float(wi[2]), float(wo[2])
    visibility = 1.0 / ((1.0 + lam(n_dot_v) + lam(n_dot_l)) * (4.0 * n_dot_v * n_dot_l))
    return distribution * min(max(visibility, 0.0), 1.0)


def golden_rows(
    base, metallic, roughness, sheen_color, sheen_roughness, albedo, clearcoat=0.0, clearcoat_roughness=0.0
):
    """The Sample Viewer's per-light layering: ``sheen + min(1 − max3(c) E(N·V), 1 − max3(c) E(N·L)) · material``,
    then the coat ``mix(…, coat, clearcoat · F_c)``; ``material`` and the coat are the core BRDF's (tested against
    Appendix B in test_gltf.py); ``albedo(μ)``: E at the sheen's roughness."""
    wi, wo = PAIRS
    material = np.asarray(gltf_brdf(base, metallic, roughness, wi, wo))
    strongest = max(sheen_color)
    rows = []
    for k in range(len(wi)):
        scaling = min(1.0 - strongest * albedo(wo[k, 2]), 1.0 - strongest * albedo(wi[k, 2]))
        rows.append(np.asarray(sheen_color) * golden_sheen(sheen_roughness, wi[k], wo[k]) + scaling * material[k])
    rows = np.array(rows)
    if clearcoat == 0:
        return rows
    coat = np.asarray(gltf_brdf((0.0, 0.0, 0.0), 0.0, clearcoat_roughness, wi, wo, specular_color=(25,) * 3))
    weight = clearcoat * (0.04 + 0.96 * (1.0 - wo[:, 2:3]) ** 5)
    return (1.0 - weight) * rows + weight * coat


@pytest.mark.parametrize("metallic", [0.0, 1.0, 0.3])
@pytest.mark.parametrize("coat", [{}, COAT], ids=["sheen", "sheen-under-a-coat"])
def test_the_sheen_is_the_extensions_formula_layered_as_the_sample_viewer_does(metallic, coat):
    base, roughness = (0.8, 0.5, 0.2), 0.45
    computed = np.asarray(gltf_brdf(base, metallic, roughness, *PAIRS, **SHEEN, **coat))
    # with E from the quadrature, the extension's definition: within the interpolation's error
    exact = lambda mu: min(sheen_albedo_quadrature(mu, SHEEN["sheen_roughness"]), 1.0)
    np.testing.assert_allclose(
        computed, golden_rows(base, metallic, roughness, **SHEEN, albedo=exact, **coat), rtol=E_RTOL
    )
    # with the interpolated E: the layering itself, to float64 rounding
    tabulated = lambda mu: float(sheen_albedo(np.array([mu]), SHEEN["sheen_roughness"])[0])
    expected = golden_rows(base, metallic, roughness, **SHEEN, albedo=tabulated, **coat)
    np.testing.assert_allclose(computed, expected, rtol=1e-12)


def test_the_sheen_is_reciprocal_as_its_scaling_takes_the_smaller_of_both_directions(rng):
    # The viewer's punctual lights take min(1 − c E(N·V), 1 − c E(N·L)) (pbr.frag), symmetric in the two: the layered
    # BRDF is reciprocal as the core material is. The extension's cheaper form, 1 − c E(N·V) alone, is not.
    wi, wo = random_directions(rng, 400), random_directions(rng, 400)
    for metallic in (0.0, 0.6):
        forward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), metallic, 0.4, wi, wo, **SHEEN))
        backward = np.asarray(gltf_brdf((0.7, 0.4, 0.2), metallic, 0.4, wo, wi, **SHEEN))
        np.testing.assert_allclose(forward, backward, rtol=1e-12)
    light, viewer = directions_from_degrees(10.0, 0.0), directions_from_degrees(80.0, 180.0)
    one_sided = [1.0 - 0.6 * float(sheen_albedo(w[:, 2], 0.5)[0]) for w in (viewer, light)]
    assert abs(one_sided[0] / one_sided[1] - 1.0) > 0.1  # measured: 0.79 against 0.98


def test_without_a_sheen_the_material_is_the_core_one():
    # a traced sheen colour of 0 (the export's compiled BRDF, a held fit's): 0 · lobe + min(1 − 0, 1 − 0) · material
    base = (0.8, 0.5, 0.2)
    core = np.asarray(gltf_brdf(base, 0.3, 0.6, *PAIRS))
    with jax.enable_x64(True):
        traced = jax.jit(lambda c, r: gltf_brdf(base, 0.3, 0.6, *PAIRS, sheen_color=c, sheen_roughness=r))
        zero = np.asarray(traced(jnp.zeros(3), jnp.float64(0.4)))
    np.testing.assert_allclose(zero, core, rtol=1e-15)  # a few ulp: the compiled program fuses its arithmetic


@pytest.mark.parametrize("sheen_roughness", [0.0, 1e-3, 0.05, 1.0])
@pytest.mark.parametrize("roughness", [0.001, 1.0])
def test_finite_values_and_gradients_at_grazing_angles_and_extreme_roughness(sheen_roughness, roughness):
    # every parameter traced (as a fit's are), directions at 89.9° and along the normal (where the half vector is the
    # normal and sin²θh is 0): values and derivatives finite, values ≥ 0
    lights = directions_from_degrees([89.9, 89.9, 89.9, 30.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    viewers = directions_from_degrees([89.9, 89.9, 0.0, 89.9, 0.0, 89.9], [180.0, 0.0, 0.0, 90.0, 0.0, 45.0])

    def brdf(parameters):
        base, metallic, rough, colour, sheen_rough = parameters
        return gltf_brdf(base, metallic, rough, lights, viewers, sheen_color=colour, sheen_roughness=sheen_rough)

    parameters = (jnp.array([0.5, 0.4, 0.3]), 0.3, roughness, jnp.array([1.0, 0.7, 0.4]), sheen_roughness)
    with jax.enable_x64(True):
        parameters = tuple(jnp.asarray(p, dtype=jnp.float64) for p in parameters)
        values = np.asarray(brdf(parameters))
        gradients = jax.grad(lambda p: jnp.sum(brdf(p)))(parameters)
    assert np.all(np.isfinite(values)) and np.all(values >= 0)
    assert all(np.all(np.isfinite(np.asarray(g))) for g in gradients), gradients


def white_albedos(metallic, roughness, n=512, **extension):
    """Directional albedos (incidences of ALBEDO_INCIDENCE) of a white glTF material, by the fit caveats' midpoint
    rule in (cos θo, φo), checked against the grid half as fine (within 1%: the grid resolves the lobes)."""
    wi, wo = albedo_directions(n)
    values = GltfMaterial((1.0, 1.0, 1.0), metallic, roughness, **extension).brdf(wi, wo)  # compiled
    fine, coarse = albedo_quadrature(values, n)
    assert np.all(np.abs(fine - coarse) <= 0.01 * fine), "the grid does not resolve the lobe"
    return fine[:, 0]


@pytest.mark.slow
@pytest.mark.parametrize("sheen_roughness", [0.1, 1.0])
def test_a_white_sheen_over_a_white_base_never_gains_energy_where_the_base_does_not(sheen_roughness):
    # Albedo scaling (Conty Estevez & Kulla 2017): lit at θi, the sheen reflects E(cos θi) and the base at most
    # (1 − E(cos θi)) of its own albedo, so a full white sheen over a base that keeps ≤ 1 keeps ≤ 1 (measured: 0.99 at
    # most, at 80° over the roughest white dielectric). The 0.5% margin is ALBEDO_LIMIT's (caveats.py), for the
    # quadrature. A white dielectric of roughness 0.5, which Appendix B's fresnel_mix makes reflect 1.08 at 80°
    # (test_gltf.py), reflects less under the sheen (measured: 1.03 to 1.05).
    sheen = {"sheen_color": (1.0, 1.0, 1.0), "sheen_roughness": sheen_roughness}
    for metallic, roughness in ((1.0, 1.0), (1.0, 0.5), (0.0, 1.0)):
        albedos = white_albedos(metallic, roughness, **sheen)
        assert np.all(albedos <= 1.005), dict(zip(ALBEDO_INCIDENCE, albedos, strict=True))
    assert np.all(white_albedos(0.0, 0.5, **sheen) < white_albedos(0.0, 0.5)[-1])


def test_the_material_writes_the_extension_only_when_a_sheen_colour_is_not_0_and_checks_its_factors():
    bare = GltfMaterial((0.5, 0.1, 0.15), 0.0, 0.8, sheen_roughness=0.5)  # a roughness alone: no sheen
    assert bare.extensions == () and "extensions" not in bare.material_object("bare")
    velvet = GltfMaterial((0.5, 0.1, 0.15), 0.0, 0.8, sheen_color=(0.5, 0.45, 0.0), sheen_roughness=0.5)
    assert velvet.extensions == ("KHR_materials_sheen",)
    assert velvet.material_object("velvet")["extensions"] == {
        "KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.45, 0.0], "sheenRoughnessFactor": 0.5}
    }
    assert velvet.to_gltf("velvet")["extensionsUsed"] == ["KHR_materials_sheen"]
    for factors, named in (
        ({"sheen_color": (1.2, 0.0, 0.0)}, "sheen_color"),
        ({"sheen_roughness": 1.5}, "sheen_rough"),
    ):
        with pytest.raises(BrdfInputError, match=f"^{named}") as caught:
            GltfMaterial((0.5, 0.5, 0.5), 0.0, 0.5, **factors)
        assert "\n" not in str(caught.value) and "[0, 1]" in str(caught.value)
