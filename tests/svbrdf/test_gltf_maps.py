"""The maps of a ``gltf`` fit as a glTF binary: a quad with the maps as textures, valid for the Khronos validator
(0 errors, 0 warnings), whose textures decode to the maps within their 8-bit rounding; other maps say why not."""

import json
import struct

import numpy as np
import pytest
from gltf_validator import assert_valid, needs_validator

import brdffit.svbrdf as svbrdf
from brdffit.data_synth.capture import synth_capture
from brdffit.errors import BrdfInputError
from brdffit.svbrdf.gltf_maps import gltf_maps


@pytest.fixture(scope="module")
def gltf_fit(tmp_path_factory):
    """A 6 × 6 capture of glTF materials (a red dielectric blended into a gold-coloured metal), fitted by ``gltf``
    with the coat held at none: 24 photographs do not determine one (free, it turns into a full-strength mirror
    between their directions and the base colour makes up for its 4%: 3.9% off the truth, where held 0.19%)."""
    folder = tmp_path_factory.mktemp("gltf-capture")
    truth = synth_capture(folder / "capture", "gltf", shape=(6, 6), n_images=24, noise=0.01, seed=2)
    maps = svbrdf.fit(folder / "capture", "gltf", output=folder / "maps", progress=False, fixed={"clearcoat": 0.0})
    return maps, truth, folder / "maps"


def _chunks(data: bytes) -> tuple[dict, bytes]:
    """A .glb's JSON document and binary chunk."""
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20 : 20 + json_length])
    binary_length = struct.unpack_from("<I", data, 20 + json_length)[0]
    return document, data[28 + json_length : 28 + json_length + binary_length]


def test_the_maps_glb_holds_the_maps_as_textures(gltf_fit):
    maps, _, folder = gltf_fit
    data = (folder / "material.glb").read_bytes()
    document, binary = _chunks(data)
    material = document["materials"][0]["pbrMetallicRoughness"]
    assert material["baseColorTexture"] == {"index": 0} and material["metallicRoughnessTexture"] == {"index": 1}
    from io import BytesIO

    from PIL import Image

    def image(index):
        view = document["bufferViews"][document["images"][index]["bufferView"]]
        raw = binary[view["byteOffset"] : view["byteOffset"] + view["byteLength"]]
        return np.asarray(Image.open(BytesIO(raw)), dtype=float) / 255.0

    exported = gltf_maps(maps)
    metallic_roughness = image(1)
    fitted = maps.fitted
    assert np.max(np.abs(metallic_roughness[..., 1] - maps.params["roughness"])[fitted]) <= 0.5 / 255 + 1e-12
    assert np.max(np.abs(metallic_roughness[..., 2] - maps.params["metallic"])[fitted]) <= 0.5 / 255 + 1e-12
    assert exported.quantization["roughness"] <= 0.5 / 255 + 1e-12
    described = json.loads((folder / "maps.json").read_text())
    assert described["glb"]["file"] == "material.glb" and maps.exports["glb"] == described["glb"]


def test_maps_read_back_and_written_elsewhere_claim_no_glb(gltf_fit, tmp_path):
    """Maps read from a folder do not carry its .glb: written into another folder, their maps.json names none, and
    the files written are the maps' own."""
    _, _, folder = gltf_fit
    again = svbrdf.read_maps(folder)
    assert again.exports == {"glb": None, "mitsuba": None}
    written = svbrdf.write_maps(tmp_path / "copy", again, textures=False)
    assert sorted(path.name for path in written) == ["maps.json", "params.npz"]
    assert json.loads((tmp_path / "copy" / "maps.json").read_text())["glb"] is None


@needs_validator
def test_the_maps_glb_is_valid(gltf_fit):
    _, _, folder = gltf_fit
    assert_valid(folder / "material.glb")


def test_the_maps_recover_the_gltf_truth(gltf_fit):
    """Base colour, roughness and metallic within 3% (median) of the truth (measured 0.19–0.50%): the maps a viewer
    then shows are the sample's."""
    maps, truth, _ = gltf_fit
    for name in ("base_color", "roughness", "metallic"):
        error = np.median(np.abs(maps.params[name] - truth[name]) / truth[name])
        assert error < 0.03, (name, error)


def test_maps_of_another_model_have_no_glb(tmp_path):
    maps = svbrdf.Maps("ward", {}, "relative", ("r", "g", "b"), {}, {"n_samples": np.ones((2, 2))}, 10.0, 10.0)
    with pytest.raises(BrdfInputError, match="the maps of a ward fit do not map onto glTF's material"):
        gltf_maps(maps)
