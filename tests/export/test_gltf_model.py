"""The ``gltf`` fit model: glTF's own material fitted, so its glTF export writes the fitted numbers unchanged and a
viewer evaluates exactly the fit; its held index freed; its parameters on the command line."""

import json

import numpy as np
import pytest
from conftest import random_directions
from gltf_validator import assert_valid, needs_validator

from brdffit import Samples, fit
from brdffit.cli import main
from brdffit.data.load import save_samples
from brdffit.export.gltf import write_gltf
from brdffit.export.gltf_material import GltfMaterial

#: A red plastic with a clear-coat-like index and a copper-like metal (base colours of real materials, linear sRGB).
PLASTIC = GltfMaterial((0.8, 0.3, 0.1), 0.0, 0.35, ior=1.7)
COPPER = GltfMaterial((0.95, 0.64, 0.54), 1.0, 0.2)
#: The data's relative noise: 1%, as a gonioreflectometer's.
NOISE = 0.01


def measured(material: GltfMaterial, rng, n: int = 2000, noise: float = NOISE) -> Samples:
    """``material`` at ``n`` random pairs (up to 84° from the normal), with relative Gaussian noise."""
    wi, wo = random_directions(rng, n, min_cos=0.1), random_directions(rng, n, min_cos=0.1)
    values = material.brdf(wi, wo) * (1.0 + noise * rng.standard_normal((n, 3)))
    return Samples.from_arrays(wi, wo, values, channels=("r", "g", "b"))


def test_a_metal_is_recovered_and_its_gltf_export_is_the_fit_exactly(rng, tmp_path):
    result = fit(measured(COPPER, rng), "gltf")
    assert result.params["metallic"] == 1.0  # put onto its end: a metal, not 0.99999999
    # 1% noise on 2,000 samples × 3 channels: the parameters within a few standard errors (~0.1%).
    assert result.params["roughness"] == pytest.approx(0.2, rel=5e-3)
    np.testing.assert_allclose(result.params["base_color"], COPPER.base_color, rtol=5e-3)
    assert result.warnings == []
    material, approximation, notes = write_gltf(result, tmp_path / "copper.gltf")
    assert "exact: the fitted glTF material, its numbers unchanged" in notes
    assert material.base_color == tuple(result.params["base_color"]) and material.ior is None
    assert (material.metallic, material.roughness) == (result.params["metallic"], result.params["roughness"])
    # The material's BRDF is the fit's, evaluated by the same function: equal but for the order of float64 sums.
    assert approximation.relative_rmse < 1e-12
    stored = json.loads((tmp_path / "copper.gltf").read_text())["materials"][0]["pbrMetallicRoughness"]
    assert stored["baseColorFactor"][:3] == list(result.params["base_color"])


def test_a_freed_index_is_fitted_and_written_as_khr_materials_ior(rng, tmp_path):
    samples = measured(PLASTIC, rng)
    held = fit(samples, "gltf")
    freed = fit(samples, "gltf", fixed={"ior": None})
    assert held.params["ior"] == 1.5 and held.fixed == {"ior": 1.5}
    assert freed.params["ior"] == pytest.approx(1.7, rel=1e-2) and freed.fixed == {}
    assert freed.params["metallic"] < 5e-3  # a dielectric, but for the noise
    assert freed.cost < 0.5 * held.cost  # 4% against 6.7% at normal incidence: the data see the index
    material, _, _ = write_gltf(freed, tmp_path / "plastic.gltf")
    assert material.ior == freed.params["ior"] and material.extensions == ("KHR_materials_ior",)


@needs_validator
def test_the_exact_export_is_valid_gltf(rng, tmp_path):
    freed = fit(measured(PLASTIC, rng, n=500), "gltf", fixed={"ior": None})
    for name in ("plastic.gltf", "plastic.glb"):
        write_gltf(freed, tmp_path / name)
        assert_valid(tmp_path / name)


def test_the_command_line_fits_and_exports_it(rng, tmp_path, capsys):
    samples = measured(COPPER, rng, n=500)
    path = tmp_path / "copper.csv"
    save_samples(samples, path)
    assert main(["fit", str(path), "--model", "gltf", "-o", str(tmp_path / "fit.json")]) == 0
    result = json.loads((tmp_path / "fit.json").read_text())
    assert list(result["params"]) == ["roughness", "metallic", "ior", "base_color"]
    assert main(["export", str(tmp_path / "fit.json"), "--to", "gltf", "-o", str(tmp_path / "copper.gltf")]) == 0
    assert "exact" in capsys.readouterr().out
    material = json.loads((tmp_path / "copper.gltf").read_text())["materials"][0]["pbrMetallicRoughness"]
    assert material["baseColorFactor"][:3] == result["params"]["base_color"]
    assert main(["fit", str(path), "--model", "gltf", "--fix", "kd=0", "-o", str(tmp_path / "x.json")]) == 2
    assert "gltf has no parameter 'kd'" in capsys.readouterr().err
