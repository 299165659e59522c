"""The ``gltf`` fit model: glTF's own material fitted, so its glTF export writes the fitted numbers unchanged and a
viewer evaluates exactly the fit; its held index and anisotropy freed; a clear coat recovered at the best cost random
starts find; the checks of a freed anisotropy; its parameters on the command line."""

import json
import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from catalogue import gltf_params
from conftest import random_directions
from gltf_validator import assert_valid, needs_validator

from brdffit import FitWarning, Samples, data_synth, fit, get_model, load_result
from brdffit.cli import main
from brdffit.data.load import save_samples
from brdffit.export.gltf import write_gltf
from brdffit.export.gltf_material import GltfMaterial
from brdffit.fitting.single.caveats import as_fitted, caveats
from brdffit.physics.geometry import spherical_to_direction

#: A red plastic with a clear-coat-like index and a copper-like metal (base colours of real materials, linear sRGB).
PLASTIC = GltfMaterial((0.8, 0.3, 0.1), 0.0, 0.35, ior=1.7)
COPPER = GltfMaterial((0.95, 0.64, 0.54), 1.0, 0.2)
#: A blue paint under a glossy clear coat (KHR_materials_clearcoat), and a brushed aluminium: a metal stretched along
#: its tangent turned by 0.5 rad (KHR_materials_anisotropy).
PAINT = GltfMaterial((0.2, 0.3, 0.6), 0.0, 0.5, clearcoat=0.8, clearcoat_roughness=0.12)
BRUSHED = GltfMaterial((0.91, 0.92, 0.92), 1.0, 0.25, anisotropy_strength=0.6, anisotropy_rotation=0.5)
#: A velvet: a grey sheen (KHR_materials_sheen) of roughness 0.5 over a rough red dielectric.
VELVET = GltfMaterial((0.5, 0.1, 0.15), 0.0, 0.8, sheen_color=(0.5, 0.5, 0.5), sheen_roughness=0.5)
#: The data's relative noise: 1%, as a gonioreflectometer's.
NOISE = 0.01
#: Two fits that end at one minimum agree to the solver's stopping tolerance on the cost's relative change (1e-8 per
#: step, and a few steps' worth): a random start that finds a lower cost by more than 1e-6 found another minimum.
SAME_MINIMUM = 1e-6
#: The anisotropy freed: neither held at 0.
FREE_ANISOTROPY = {"anisotropy_strength": None, "anisotropy_rotation": None}


def params_of(material: GltfMaterial) -> dict:
    """The ``gltf`` model's parameters of ``material`` (its index 1.5 where it has none), ``gltf:sheen=true``'s where
    it has a sheen."""
    return gltf_params(
        material.roughness,
        material.metallic,
        base_color=list(material.base_color),
        ior=1.5 if material.ior is None else material.ior,
        clearcoat=material.clearcoat,
        clearcoat_roughness=material.clearcoat_roughness,
        strength=material.anisotropy_strength,
        rotation=material.anisotropy_rotation,
        sheen_color=list(material.sheen_color) if any(material.sheen_color) else None,
        sheen_roughness=material.sheen_roughness,
    )


def measured(material: GltfMaterial, rng, n: int = 2000, noise: float = NOISE) -> Samples:
    """``material`` at ``n`` random pairs (up to 84° from the normal), with relative Gaussian noise."""
    wi, wo = random_directions(rng, n, min_cos=0.1), random_directions(rng, n, min_cos=0.1)
    values = material.brdf(wi, wo) * (1.0 + noise * rng.standard_normal((n, 3)))
    return Samples.from_arrays(wi, wo, values, channels=("r", "g", "b"))


def measured_lobes(material: GltfMaterial, noise: float = NOISE, seed: int = 1) -> Samples:
    """``material`` at 1,500 pairs uniform in solid angle and 1,500 near the mirror (the lobes, every azimuth), with
    relative Gaussian noise (``seed``), as ``test_mitsuba_own_models.py`` measures Mitsuba's materials."""
    wi, wo = data_synth.uniform_random(1500, seed=5)
    near_wi, near_wo = data_synth.near_specular(6, 1500, spread=20.0, seed=6)
    wi, wo = np.vstack([wi, near_wi]), np.vstack([wo, near_wo])
    clean = material.brdf(wi, wo)
    noisy = clean * (1.0 + noise * np.random.default_rng(seed).standard_normal(clean.shape))
    return Samples.from_arrays(wi, wo, noisy, channels=("r", "g", "b"))


def random_start(rng, anisotropy: bool = False) -> dict:
    """A start anywhere in the box of the parameters the fit moves (the held ones at their defaults)."""
    start = gltf_params(*rng.uniform(0.02, 0.98, 2), base_color=[float(x) for x in rng.uniform(0.02, 0.98, 3)])
    start |= dict(zip(("clearcoat", "clearcoat_roughness"), rng.uniform(0.02, 0.98, 2), strict=True))
    if anisotropy:
        start |= {"anisotropy_strength": rng.uniform(0.02, 0.98), "anisotropy_rotation": rng.uniform(-1.5, 1.5)}
    return {name: value if name == "base_color" else float(value) for name, value in start.items()}


@pytest.mark.slow
def test_a_metal_is_recovered_and_its_gltf_export_is_the_fit_exactly(rng, tmp_path):
    # A bare metal, its coat held at 0 (--fix clearcoat=0) as a user who knows it has none holds it: free, the coat
    # takes a little of the noise of the few bright samples near the mirror that the loss weighs most (measured:
    # clearcoat 0.08, the base colour 0.65% off in b; the cost 5% lower than the truth's).
    result = fit(measured(COPPER, rng), "gltf", fixed={"clearcoat": 0.0})
    assert result.params["metallic"] == 1.0  # put onto its end: a metal, not 0.99999999
    # 1% noise on 2,000 samples × 3 channels: the parameters within a few standard errors (~0.1%).
    assert result.params["roughness"] == pytest.approx(0.2, rel=5e-3)
    np.testing.assert_allclose(result.params["base_color"], COPPER.base_color, rtol=5e-3)
    assert result.warnings == []
    material, approximation, notes = write_gltf(result, tmp_path / "copper.gltf")
    assert "exact: the fitted glTF material, its numbers unchanged" in notes
    assert material.base_color == tuple(result.params["base_color"]) and material.ior is None
    assert material.extensions == ()  # no coat, no anisotropy: core glTF
    assert (material.metallic, material.roughness) == (result.params["metallic"], result.params["roughness"])
    # The material's BRDF is the fit's, evaluated by the same function: equal but for the order of float64 sums.
    assert approximation.relative_rmse < 1e-12
    stored = json.loads((tmp_path / "copper.gltf").read_text())["materials"][0]["pbrMetallicRoughness"]
    assert stored["baseColorFactor"][:3] == list(result.params["base_color"])


@pytest.mark.slow
def test_a_freed_index_is_fitted_and_written_as_khr_materials_ior(rng, tmp_path):
    samples = measured(PLASTIC, rng)
    held = fit(samples, "gltf")
    freed = fit(samples, "gltf", fixed={"ior": None})
    other_holds = {"anisotropy_strength": 0.0, "anisotropy_rotation": 0.0}
    assert held.params["ior"] == 1.5 and held.fixed == {"ior": 1.5} | other_holds
    assert freed.params["ior"] == pytest.approx(1.7, rel=1e-2) and freed.fixed == other_holds
    assert freed.params["metallic"] < 5e-3  # a dielectric, but for the noise
    # 4% against 6.7% at normal incidence: the data see the index. Held at 1.5, a coat at the base's roughness
    # stands in for part of the higher reflectance (measured: clearcoat 0.11), but in N·V, not |V·H|: cost 29× higher.
    assert freed.cost < 0.5 * held.cost
    assert freed.params["clearcoat"] < 0.01  # no coat, but for the noise (measured: 0.0025)
    material, _, _ = write_gltf(freed, tmp_path / "plastic.gltf")
    assert material.ior == freed.params["ior"]
    # the noise's coat is written as fitted: the export is the fit
    expected = ("KHR_materials_ior", "KHR_materials_clearcoat") if material.clearcoat > 0 else ("KHR_materials_ior",)
    assert material.extensions == expected


@pytest.mark.slow
def test_a_clear_coated_paint_is_recovered_and_exported_with_its_coat(tmp_path):
    samples = measured_lobes(PAINT)
    result = fit(samples, "gltf")
    assert result.converged and result.warnings == []
    # 3,000 pairs × 3 channels at 1% noise: measured within 0.05% (colour, roughness, coat and its roughness); the
    # tolerances ten times that and more.
    np.testing.assert_allclose(result.params["base_color"], PAINT.base_color, rtol=5e-3)
    assert result.params["roughness"] == pytest.approx(PAINT.roughness, rel=5e-3)
    assert result.params["clearcoat"] == pytest.approx(PAINT.clearcoat, rel=0.02)
    assert result.params["clearcoat_roughness"] == pytest.approx(PAINT.clearcoat_roughness, rel=0.01)
    assert result.params["metallic"] < 5e-3
    material, approximation, notes = write_gltf(result, tmp_path / "paint.gltf")
    assert "exact: the fitted glTF material, its numbers unchanged" in notes
    assert material.extensions == ("KHR_materials_clearcoat",) and not material.needs_tangents
    assert (material.clearcoat, material.clearcoat_roughness) == (
        result.params["clearcoat"],
        result.params["clearcoat_roughness"],
    )
    assert approximation.relative_rmse < 1e-12  # one function evaluates both: float64 sums' order
    document = json.loads((tmp_path / "paint.gltf").read_text())
    assert document["extensionsUsed"] == ["KHR_materials_clearcoat"]
    assert document["materials"][0]["extensions"] == {
        "KHR_materials_clearcoat": {
            "clearcoatFactor": result.params["clearcoat"],
            "clearcoatRoughnessFactor": result.params["clearcoat_roughness"],
        }
    }
    assert "TANGENT" not in document["meshes"][0]["primitives"][0]["attributes"]
    # The exported material at the data's directions: the data but for their noise (1%).
    relative = np.abs(material.brdf(samples.wi, samples.wo) / samples.values - 1.0)
    assert np.median(relative) < 0.01, np.median(relative)


@pytest.mark.slow
def test_a_freed_anisotropy_is_recovered_and_exported_with_the_mesh_tangents_it_needs(tmp_path):
    samples = measured_lobes(BRUSHED)
    held = fit(samples, "gltf")  # round: the default holds the anisotropy at 0
    freed = fit(samples, "gltf", fixed=FREE_ANISOTROPY)
    assert freed.converged and freed.warnings == []
    assert freed.fixed == {"ior": 1.5}
    assert freed.cost < 0.01 * held.cost  # measured: 11,000× lower; the round lobe misses the stretched one
    # measured within 0.05% (strength, roughness, colour) and 0.01° (rotation); the tolerances ten times that and more
    assert freed.params["anisotropy_strength"] == pytest.approx(BRUSHED.anisotropy_strength, rel=0.01)
    assert freed.params["anisotropy_rotation"] == pytest.approx(BRUSHED.anisotropy_rotation, abs=math.radians(0.5))
    assert freed.params["roughness"] == pytest.approx(BRUSHED.roughness, rel=0.01)
    np.testing.assert_allclose(freed.params["base_color"], BRUSHED.base_color, rtol=5e-3)
    material, approximation, notes = write_gltf(freed, tmp_path / "brushed.glb")
    assert material.anisotropy_rotation == freed.params["anisotropy_rotation"]
    assert "KHR_materials_anisotropy" in material.extensions and material.needs_tangents
    assert approximation.relative_rmse < 1e-12
    (tangents,) = [note for note in notes if note.startswith("anisotropic (KHR_materials_anisotropy)")]
    assert "TANGENT" in tangents and "the data's +x" in tangents
    document = material.to_gltf("brushed")
    primitive = document["meshes"][0]["primitives"][0]
    assert primitive["attributes"] == {"POSITION": 0, "NORMAL": 1, "TANGENT": 2}
    assert document["accessors"][2]["type"] == "VEC4"
    assert document["materials"][0]["extensions"]["KHR_materials_anisotropy"] == {
        "anisotropyStrength": freed.params["anisotropy_strength"],
        "anisotropyRotation": freed.params["anisotropy_rotation"],
    }


def test_a_freed_anisotropy_is_checked_as_an_anisotropic_models():
    """The model says it is isotropic, as it is with its default holds; a fit whose anisotropy is not at the held 0 is
    checked as the anisotropic model it is (``caveats.as_fitted``): its albedo on the whole grid, and in-plane data
    named as unable to determine the anisotropy."""
    model = get_model("gltf")
    paint = model.dictionary.to_params(params_of(PAINT))
    brushed = model.dictionary.to_params(params_of(BRUSHED))
    assert model.isotropic and as_fitted(model, paint) is model
    anisotropic = as_fitted(model, brushed)
    assert not anisotropic.isotropic and anisotropic.lobe == model.lobe and anisotropic.held == model.held
    # An isotropic model's albedo at normal incidence is an integral along one azimuth, +x (caveats._axial_quadrature),
    # as if the lobe were round: an anisotropic lobe is α_t/α_b = 6.4 times wider along its tangent than across it,
    # and the one azimuth sees neither its mean (measured: 0.555 for 0.797, 30% low, at the tangent's 0.5 rad; along
    # the tangent it would be too high).
    from brdffit.fitting.single.caveats import _albedo_estimates

    shortcut = np.asarray(_albedo_estimates(model, brushed, 128)[0])
    checked = np.asarray(_albedo_estimates(anisotropic, brushed, 128)[0])
    assert abs(shortcut[0, 0] / checked[0, 0] - 1.0) > 0.2 and np.all(checked < 1.0)  # a metal of reflectance ≤ 0.92
    in_plane = data_synth.synthesize("gltf", params_of(BRUSHED), *data_synth.in_plane(4, 45))
    default_holds = frozenset({"ior", "anisotropy_strength", "anisotropy_rotation"})
    lines = caveats(model, in_plane, brushed, held=frozenset({"ior"}))
    assert any(
        "the data cannot determine its anisotropy (anisotropy_strength, anisotropy_rotation)" in line for line in lines
    ), lines
    assert not any("exceeds 1" in line for line in lines)  # the albedo seen whole
    assert not any("plane of incidence" in line for line in caveats(model, in_plane, paint, held=default_holds))


@pytest.mark.slow
def test_a_sheen_is_recovered_and_exported_as_khr_materials_sheen(tmp_path):
    samples = measured_lobes(VELVET)
    with warnings.catch_warnings():  # without a sheen, the base's roughness runs to its end (1) after the grazing light
        warnings.simplefilter("ignore", FitWarning)
        held = fit(samples, "gltf")
    freed = fit(samples, "gltf", sheen=True)
    assert held.model_options == {"sheen": False} and freed.model_options == {"sheen": True}
    assert "sheen_color" not in held.params
    assert freed.converged and freed.warnings == []
    assert freed.fixed == {"ior": 1.5, "anisotropy_strength": 0.0, "anisotropy_rotation": 0.0}
    assert freed.cost < 0.01 * held.cost  # measured: 350× lower; a base alone misses the sheen's grazing lobe
    # 3,000 pairs × 3 channels at 1% noise: measured within 0.2% (sheen colour and roughness, base colour and
    # roughness); the tolerances "a few %" as the issue asks, ten times that
    np.testing.assert_allclose(freed.params["sheen_color"], VELVET.sheen_color, rtol=0.02)
    assert freed.params["sheen_roughness"] == pytest.approx(VELVET.sheen_roughness, rel=0.02)
    np.testing.assert_allclose(freed.params["base_color"], VELVET.base_color, rtol=0.02)
    assert freed.params["roughness"] == pytest.approx(VELVET.roughness, rel=0.02)
    assert freed.params["metallic"] < 0.01 and freed.params["clearcoat"] < 0.01
    material, approximation, notes = write_gltf(freed, tmp_path / "velvet.gltf")
    assert "exact: the fitted glTF material, its numbers unchanged" in notes
    assert "KHR_materials_sheen" in material.extensions and not material.needs_tangents
    assert material.sheen_color == tuple(freed.params["sheen_color"])
    assert material.sheen_roughness == freed.params["sheen_roughness"]
    assert approximation.relative_rmse < 1e-12  # one function evaluates both: float64 sums' order
    document = json.loads((tmp_path / "velvet.gltf").read_text())
    assert "KHR_materials_sheen" in document["extensionsUsed"]
    assert document["materials"][0]["extensions"]["KHR_materials_sheen"] == {
        "sheenColorFactor": freed.params["sheen_color"],
        "sheenRoughnessFactor": freed.params["sheen_roughness"],
    }
    # held, no sheen is written: the extension only where the material uses it
    assert "KHR_materials_sheen" not in write_gltf(held, tmp_path / "bare.gltf")[0].extensions
    # The exported material at the data's directions: the data but for their noise (1%).
    relative = np.abs(material.brdf(samples.wi, samples.wo) / samples.values - 1.0)
    assert np.median(relative) < 0.01, np.median(relative)


@pytest.mark.parametrize(("theta_i", "named"), [(5.0, True), (45.0, False)])
def test_a_sheen_from_one_incidence_near_the_normal_is_named_as_undetermined(theta_i, named):
    """Lit along the normal, an isotropic material is one curve of θo, which a sheen and the base trace alike
    (``caveats._sheen_undetermined``: at 5° the fitted sheen colour is off by up to 60%); one incidence at 45°, an
    in-plane scan included, determines it (measured: within 1%)."""
    model = get_model("gltf", sheen=True)
    _, wo = data_synth.in_plane(1, 45)
    light = np.asarray(spherical_to_direction(np.radians(theta_i), 0.0))
    samples = data_synth.synthesize("gltf", params_of(VELVET), np.tile(light, (len(wo), 1)), wo, sheen=True)
    velvet = model.dictionary.to_params(params_of(VELVET))
    holds = frozenset({"ior", "anisotropy_strength", "anisotropy_rotation"})
    lines = [line for line in caveats(model, samples, velvet, held=holds) if "sheen" in line]
    expected = "the data cannot tell sheen_roughness and sheen_color from the base"
    assert (len(lines) == 1 and expected in lines[0]) if named else lines == [], lines
    # held, the sheen is no question the data must answer
    assert not any("sheen" in line for line in caveats(model, samples, velvet, held=holds | {"sheen_color"}))


@needs_validator
def test_the_exact_export_is_valid_gltf(rng, tmp_path):
    freed = fit(measured(PLASTIC, rng, n=500), "gltf", fixed={"ior": None})
    for name in ("plastic.gltf", "plastic.glb"):
        write_gltf(freed, tmp_path / name)
        assert_valid(tmp_path / name)
    # A coated, anisotropic one. The validator (2.0.0-dev.3.10) knows both extensions (it checks their factors'
    # ranges) but not that KHR_materials_anisotropy uses the mesh's tangents: it reports them as an info, not a
    # warning, UNUSED_MESH_TANGENT ("the material has no normal texture"), which the extension's MUST overrules.
    # A velvet under a coat, its sheen written as KHR_materials_sheen (the validator checks its factors' ranges).
    for stem, truth, options, extension in (
        ("brushed", BRUSHED, {"fixed": FREE_ANISOTROPY}, "KHR_materials_anisotropy"),
        ("velvet", VELVET, {"sheen": True}, "KHR_materials_sheen"),
    ):
        fitted = fit(measured_lobes(truth), "gltf", **options)
        result = replace(fitted, params=fitted.params | {"clearcoat": 0.3})
        for name in (f"{stem}.gltf", f"{stem}.glb"):
            material, _, _ = write_gltf(result, tmp_path / name)
            assert material.extensions == ("KHR_materials_clearcoat", extension)
            assert_valid(tmp_path / name)


@pytest.mark.heavy
@pytest.mark.parametrize(
    ("name", "free"), [("paint", {}), ("brushed", FREE_ANISOTROPY)], ids=["clear-coat", "anisotropy-freed"]
)
def test_the_default_fit_reaches_the_best_cost_of_10_random_starts(name, free):
    truth = {"paint": PAINT, "brushed": BRUSHED}[name]
    samples = measured_lobes(truth)
    result = fit(samples, "gltf", fixed=free)
    rng = np.random.default_rng(7)
    with warnings.catch_warnings():  # a random start may end anywhere, implausible values and all: said, not raised
        warnings.simplefilter("ignore", FitWarning)
        starts = [random_start(rng, anisotropy=bool(free)) for _ in range(10)]
        costs = [fit(samples, "gltf", start=start, fixed=free).cost for start in starts]
    assert result.cost <= min(costs) * (1.0 + SAME_MINIMUM), (result.cost, sorted(costs))


@pytest.mark.slow
def test_the_command_line_fits_and_exports_it(rng, tmp_path, capsys):
    samples = measured(COPPER, rng, n=500)
    path = tmp_path / "copper.csv"
    save_samples(samples, path)
    assert main(["fit", str(path), "--model", "gltf", "-o", str(tmp_path / "fit.json")]) == 0
    result = json.loads((tmp_path / "fit.json").read_text())
    assert list(result["params"]) == list(gltf_params(0.5, 0.5, base_color=[0.5]))  # the model's names, in its order
    assert main(["export", str(tmp_path / "fit.json"), "--to", "gltf", "-o", str(tmp_path / "copper.gltf")]) == 0
    assert "exact" in capsys.readouterr().out
    material = json.loads((tmp_path / "copper.gltf").read_text())["materials"][0]["pbrMetallicRoughness"]
    assert material["baseColorFactor"][:3] == result["params"]["base_color"]
    assert main(["fit", str(path), "--model", "gltf", "--fix", "kd=0", "-o", str(tmp_path / "x.json")]) == 2
    assert "gltf has no parameter 'kd'" in capsys.readouterr().err
    # A result file written before the model had a sheen loads with none (its holds' values) and exports as it was.
    older = dict(result)
    older["params"] = {name: value for name, value in result["params"].items() if not name.startswith("sheen_")}
    (tmp_path / "older.json").write_text(json.dumps(older))
    assert load_result(tmp_path / "older.json").params == result["params"]
    assert main(["export", str(tmp_path / "older.json"), "--to", "gltf", "-o", str(tmp_path / "older.gltf")]) == 0
    assert "exact" in capsys.readouterr().out
