"""The maps of a ``gltf`` fit as a glTF binary: a quad with the maps as textures, valid for the Khronos validator
(0 errors, 0 warnings), whose textures decode to the maps within their 8-bit rounding (the anisotropy and the sheen
too); other maps say why not."""

import json
import struct

import numpy as np
import pytest
from gltf_validator import assert_valid, needs_validator

import brdffit.svbrdf as svbrdf
from brdffit.data_synth.capture import synth_capture
from brdffit.errors import BrdfInputError
from brdffit.svbrdf.gltf_maps import gltf_maps
from brdffit.svbrdf.images import srgb_decoded

pytestmark = pytest.mark.slow  # its module fixture fits a whole capture: ~35 s


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


def _image(document: dict, binary: bytes, index: int) -> np.ndarray:
    """Texture ``index`` of a .glb, decoded to values in [0, 1] (H, W, channels)."""
    from io import BytesIO

    from PIL import Image

    view = document["bufferViews"][document["images"][document["textures"][index]["source"]]["bufferView"]]
    raw = binary[view["byteOffset"] : view["byteOffset"] + view["byteLength"]]
    return np.asarray(Image.open(BytesIO(raw)), dtype=float) / 255.0


def _accessor(document: dict, binary: bytes, index: int) -> np.ndarray:
    """Accessor ``index`` of a .glb's float attributes, (count, components)."""
    accessor = document["accessors"][index]
    view = document["bufferViews"][accessor["bufferView"]]
    raw = binary[view["byteOffset"] : view["byteOffset"] + view["byteLength"]]
    return np.frombuffer(raw, "<f4").reshape(accessor["count"], -1)


def test_the_maps_glb_holds_the_maps_as_textures(gltf_fit):
    maps, _, folder = gltf_fit
    data = (folder / "material.glb").read_bytes()
    document, binary = _chunks(data)
    material = document["materials"][0]["pbrMetallicRoughness"]
    assert material["baseColorTexture"] == {"index": 0} and material["metallicRoughnessTexture"] == {"index": 1}
    exported = gltf_maps(maps)
    metallic_roughness = _image(document, binary, 1)
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


def _textured_maps() -> svbrdf.Maps:
    """Maps of a ``gltf:sheen=true`` fit made by hand, 5 × 7 texels: an anisotropy turning through every direction
    (the lobe is the same turned by π) with a strength rising across the rows, a sheen whose colour and roughness
    vary, one texel not fitted."""
    rows, columns = 5, 7
    row, column = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    rng = np.random.default_rng(3)
    n_samples = np.full((rows, columns), 24.0)
    n_samples[2, 3] = 0.0
    params = {
        "base_color": rng.uniform(0.05, 0.9, (rows, columns, 3)),
        "roughness": rng.uniform(0.1, 0.9, (rows, columns)),
        "metallic": rng.uniform(0.0, 1.0, (rows, columns)),
        "clearcoat": np.zeros((rows, columns)),
        "clearcoat_roughness": np.zeros((rows, columns)),
        "ior": np.full((rows, columns), 1.5),
        "anisotropy_strength": (row + 1) / rows * rng.uniform(0.2, 1.0, (rows, columns)),
        "anisotropy_rotation": (row * columns + column) / (rows * columns) * np.pi - np.pi / 2 + 1e-3,
        "sheen_color": rng.uniform(0.0, 1.0, (rows, columns, 3)),
        "sheen_roughness": rng.uniform(0.0, 1.0, (rows, columns)),
    }
    return svbrdf.Maps(
        "gltf", {"sheen": True}, "relative", ("r", "g", "b"), params, {"n_samples": n_samples}, 30.0, 20.0
    )


def test_anisotropy_and_sheen_maps_are_textures_that_decode_to_the_maps(tmp_path):
    """KHR_materials_anisotropy's texture (direction in red and green, strength in blue, linear) and
    KHR_materials_sheen's (sRGB colour, linear roughness in alpha) give back each fitted texel's parameters within
    the rounding the export reports, and that report is what a user measures: 8-bit steps, 0.5/255 for a linear
    value, the angle of a direction rounded to 1/255 in each of its two components (under √2/255 rad)."""
    maps = _textured_maps()
    exported = gltf_maps(maps)
    document, binary = _chunks(exported.data)
    extensions = document["materials"][0]["extensions"]
    assert set(document["extensionsUsed"]) == {"KHR_materials_anisotropy", "KHR_materials_sheen"}
    anisotropy, sheen = extensions["KHR_materials_anisotropy"], extensions["KHR_materials_sheen"]
    assert anisotropy["anisotropyStrength"] == 1.0 and anisotropy["anisotropyRotation"] == 0.0
    assert sheen["sheenColorFactor"] == [1.0, 1.0, 1.0] and sheen["sheenRoughnessFactor"] == 1.0
    fitted = maps.fitted
    texture = _image(document, binary, anisotropy["anisotropyTexture"]["index"])
    direction = texture[..., :2] * 2.0 - 1.0
    rotation = np.arctan2(direction[..., 1], direction[..., 0])
    turned = (rotation - maps.params["anisotropy_rotation"] + np.pi / 2) % np.pi - np.pi / 2
    assert np.max(np.abs(turned)[fitted]) == pytest.approx(exported.quantization["anisotropy_rotation"], abs=1e-12)
    assert exported.quantization["anisotropy_rotation"] < np.sqrt(2) / 255
    strength = texture[..., 2]
    assert np.max(np.abs(strength - maps.params["anisotropy_strength"])[fitted]) <= 0.5 / 255 + 1e-12
    assert strength[2, 3] == 0.0  # the texel not fitted is isotropic
    colour_texture = _image(document, binary, sheen["sheenColorTexture"]["index"])
    assert sheen["sheenRoughnessTexture"] == sheen["sheenColorTexture"]  # one RGBA image
    colour = srgb_decoded(colour_texture[..., :3])
    colour_error = np.max(np.abs(colour - maps.params["sheen_color"])[fitted])
    assert colour_error == pytest.approx(exported.quantization["sheen_color"], abs=1e-12)
    roughness_error = np.max(np.abs(colour_texture[..., 3] - maps.params["sheen_roughness"])[fitted])
    assert roughness_error == pytest.approx(exported.quantization["sheen_roughness"], abs=1e-12)
    assert roughness_error <= 0.5 / 255 + 1e-12
    primitive = document["meshes"][0]["primitives"][0]
    tangents = _accessor(document, binary, primitive["attributes"]["TANGENT"])
    np.testing.assert_array_equal(tangents, np.tile([1.0, 0.0, 0.0, 1.0], (4, 1)))  # +x; bitangent cross(z, x) = +y
    assert any("capture's +x" in note for note in exported.notes)
    assert not any("are isotropic" in note for note in exported.notes)  # every fitted texel is anisotropic


def test_isotropic_texels_of_an_anisotropic_glb_are_said_to_render_clamped():
    """A viewer shades every texel of a material with KHR_materials_anisotropy by the extension's clamped lobe; the
    gltf model's isotropic texels (strength below MIN_ANISOTROPY) were fitted with the core one: the notes count
    them."""
    maps = _textured_maps()
    maps.params["anisotropy_strength"][0, :3] = 0.0
    notes = gltf_maps(maps).notes
    assert any(note.startswith("3 of 34 texels are isotropic") for note in notes), notes


def test_isotropic_maps_without_a_sheen_have_no_tangents_and_no_such_textures(tmp_path):
    maps = _textured_maps()
    maps.params["anisotropy_strength"][:] = 0.0
    maps.params["sheen_color"][:] = 0.0
    document, _ = _chunks(gltf_maps(maps).data)
    assert "extensions" not in document["materials"][0] and len(document["textures"]) == 2
    assert "TANGENT" not in document["meshes"][0]["primitives"][0]["attributes"]


@needs_validator
def test_the_anisotropy_and_sheen_maps_glb_is_valid(tmp_path):
    path = tmp_path / "material.glb"
    path.write_bytes(gltf_maps(_textured_maps()).data)
    assert_valid(path)
