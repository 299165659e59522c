"""The glTF files viewers open: the preview sphere's geometry, the ``.glb`` container read back byte by byte, and the
Khronos glTF validator's verdict (0 errors, 0 warnings) on every kind of material brdffit writes, as ``.gltf`` and
``.glb``, from the Python API and from the command line."""

import base64
import json
import struct
from collections import Counter

import numpy as np
import pytest
from catalogue import parametrize_cases
from gltf_validator import assert_valid, needs_validator

from brdffit import BrdfInputError, FitResult
from brdffit.export.gltf import write_gltf
from brdffit.export.gltf_material import GltfMaterial
from brdffit.export.gltf_preview import preview_sphere
from brdffit.export.targets import export_format

#: The materials brdffit writes, one of each kind :func:`brdffit.export.gltf._material_of` makes: core glTF (a
#: dielectric and a metal), with KHR_materials_specular alone (f0 ≤ 0.04), with an index of refraction (f0 up to
#: that of ior 4) and with ``ior = 0`` (f0 = the specular colour, beyond ior 4), and at the factors' ends (0 and 1);
#: and those a ``gltf`` fit maps exactly: under a clear coat (KHR_materials_clearcoat), anisotropic
#: (KHR_materials_anisotropy, the sphere with its tangents), and both with an index; a velvet (KHR_materials_sheen),
#: and a sheen at its factors' ends (colour 1 and 0, roughness 1) under a coat.
MATERIALS = {
    "dielectric": GltfMaterial((0.5, 0.4, 0.3), 0.0, 0.35),
    "metal": GltfMaterial((0.95, 0.64, 0.54), 1.0, 0.2),
    "specular": GltfMaterial((0.2, 0.2, 0.2), 0.0, 0.5, specular=0.7, specular_color=(1.0, 0.5, 0.25)),
    "specular-ior": GltfMaterial((0.1, 0.3, 0.2), 0.0, 0.1, specular=0.9, specular_color=(1.0, 0.8, 0.6), ior=2.3),
    "ior-zero": GltfMaterial((0.14, 0.09, 0.05), 0.0, 0.38, specular=0.04, specular_color=(0.9, 0.9, 0.9), ior=0.0),
    "ends": GltfMaterial((0.0, 1.0, 0.0), 0.0, 1.0),
    "clearcoat": GltfMaterial((0.2, 0.3, 0.6), 0.0, 0.5, clearcoat=0.8, clearcoat_roughness=0.12),
    "anisotropic": GltfMaterial((0.91, 0.92, 0.92), 1.0, 0.25, anisotropy_strength=0.6, anisotropy_rotation=-1.2),
    "coat-anisotropy-ior": GltfMaterial(
        (0.6, 0.2, 0.05), 0.4, 0.3, ior=1.6, clearcoat=1.0, clearcoat_roughness=0.0, anisotropy_strength=1.0
    ),
    "sheen": GltfMaterial((0.5, 0.1, 0.15), 0.0, 0.8, sheen_color=(0.5, 0.45, 0.4), sheen_roughness=0.5),
    "sheen-ends-coat": GltfMaterial(
        (0.3, 0.3, 0.3),
        0.0,
        0.6,
        clearcoat=0.5,
        clearcoat_roughness=0.2,
        sheen_color=(1.0, 1.0, 0.0),
        sheen_roughness=1.0,
    ),
}


def test_the_preview_sphere_is_closed_outward_facing_and_has_unit_normals():
    mesh = preview_sphere()
    positions, triangles = mesh.positions.astype(np.float64), mesh.indices.astype(np.int64)
    assert mesh.positions.dtype == mesh.normals.dtype == np.float32 and mesh.indices.dtype == np.uint16
    assert triangles.min() == 0 and triangles.max() == len(positions) - 1  # every vertex used, uint16 enough
    # On the unit sphere, normals along the positions; glTF asks unit normals (its validator: within 5e-4).
    np.testing.assert_allclose(np.linalg.norm(positions, axis=1), 1.0, atol=1e-6)  # float32's rounding: 6e-8
    np.testing.assert_array_equal(mesh.normals, mesh.positions)
    # Counter-clockwise seen from outside (glTF's front faces), no degenerate triangle.
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    facing = np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c)
    assert facing.min() > 0
    # Closed: every edge shared by exactly two triangles, once in each direction (consistent winding).
    directed = Counter((int(t[k]), int(t[(k + 1) % 3])) for t in triangles for k in range(3))
    assert set(directed.values()) == {1} and all((j, i) in directed for i, j in directed)
    # Its pole on glTF's up axis +y; the bounding box is the unit cube's.
    np.testing.assert_allclose(positions[0], [0.0, 1.0, 0.0])
    np.testing.assert_allclose(positions.min(axis=0), -1.0, atol=1e-3)
    np.testing.assert_allclose(positions.max(axis=0), 1.0, atol=1e-3)


def test_the_preview_spheres_tangents_point_east_with_a_right_handed_frame():
    # glTF's TANGENT: unit xyz, w = ±1 (the validator checks both); here perpendicular to the normals, along the lines
    # of latitude towards increasing azimuth (counter-clockwise seen from +y), and w = +1: the bitangent
    # cross(normal, tangent) · w points north where the normal points out, as the data's y = z × x.
    mesh = preview_sphere()
    assert mesh.tangents.dtype == np.float32 and mesh.tangents.shape == (len(mesh.positions), 4)
    tangents, normals = mesh.tangents[:, :3].astype(np.float64), mesh.normals.astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(tangents, axis=1), 1.0, atol=1e-6)
    np.testing.assert_array_equal(mesh.tangents[:, 3], 1.0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", tangents, normals), 0.0, atol=1e-6)
    up = np.array([0.0, 1.0, 0.0])
    east = np.cross(up, normals)  # the direction of increasing azimuth about +y (0 at the poles)
    ring = np.linalg.norm(east, axis=1) > 1e-6
    np.testing.assert_allclose(tangents[ring], east[ring] / np.linalg.norm(east[ring], axis=1)[:, None], atol=1e-6)
    bitangents = np.cross(normals, tangents)
    assert np.all(bitangents[ring] @ up > 0)  # north


def _glb_parts(data: bytes) -> tuple[dict, bytes]:
    """The JSON chunk (parsed) and the binary chunk of a ``.glb`` file, checking the container's layout (glTF 2.0
    §4.4): header magic, version and length; chunk lengths multiples of 4; JSON padded with spaces, BIN with zeros."""
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    json_length, json_type = struct.unpack_from("<II", data, 12)
    assert json_type == 0x4E4F534A and json_length % 4 == 0
    text = data[20 : 20 + json_length]
    bin_length, bin_type = struct.unpack_from("<II", data, 20 + json_length)
    assert bin_type == 0x004E4942 and bin_length % 4 == 0
    binary = data[28 + json_length : 28 + json_length + bin_length]
    assert 28 + json_length + bin_length == len(data)
    assert text.rstrip(b" ") == text.strip() and text.decode("utf-8").strip().endswith("}")
    return json.loads(text), binary


@pytest.mark.parametrize("kind", ["specular-ior", "anisotropic"])
def test_the_glb_holds_the_gltf_document_and_its_buffer_bytes(kind):
    material = MATERIALS[kind]
    document = material.to_gltf("coat", {"note": "kept"})
    packed, binary = _glb_parts(material.to_glb("coat", {"note": "kept"}))
    uri = document["buffers"][0].pop("uri")
    assert uri.startswith("data:application/octet-stream;base64,")
    assert packed == document  # the same document, less the URI
    embedded = base64.b64decode(uri.split(",", 1)[1])
    assert binary[: len(embedded)] == embedded and set(binary[len(embedded) :]) <= {0}
    # The buffer holds the sphere as the accessors describe it, its tangents where the material needs them.
    mesh = preview_sphere()
    views, attributes = document["bufferViews"], document["meshes"][0]["primitives"][0]["attributes"]
    accessors = document["accessors"]
    index_view = views[accessors[document["meshes"][0]["primitives"][0]["indices"]]["bufferView"]]
    positions = np.frombuffer(embedded, "<f4", count=3 * len(mesh.positions), offset=views[0]["byteOffset"])
    indices = np.frombuffer(embedded, "<u2", count=mesh.indices.size, offset=index_view["byteOffset"])
    np.testing.assert_array_equal(positions.reshape(-1, 3), mesh.positions)
    np.testing.assert_array_equal(indices.reshape(-1, 3), mesh.indices)
    assert ("TANGENT" in attributes) == material.needs_tangents
    if material.needs_tangents:
        view = views[accessors[attributes["TANGENT"]]["bufferView"]]
        tangents = np.frombuffer(embedded, "<f4", count=mesh.tangents.size, offset=view["byteOffset"])
        np.testing.assert_array_equal(tangents.reshape(-1, 4), mesh.tangents)
        assert view["byteLength"] == mesh.tangents.nbytes
    assert document["materials"][0]["extras"] == {"note": "kept"}
    assert document["extensionsUsed"] == list(material.extensions)
    assert document["meshes"][0]["primitives"][0]["material"] == 0 and document["scenes"][0]["nodes"] == [0]


@needs_validator
@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_the_khronos_validator_finds_no_error_and_no_warning(tmp_path, kind):
    material = MATERIALS[kind]
    gltf, glb = tmp_path / f"{kind}.gltf", tmp_path / f"{kind}.glb"
    gltf.write_text(json.dumps(material.to_gltf(kind, {"brdffit": {"model": "ward"}})), encoding="utf-8")
    glb.write_bytes(material.to_glb(kind, {"brdffit": {"model": "ward"}}))
    for path in (gltf, glb):
        issues = assert_valid(path)
        # measured with gltf-validator 2.0.0-dev.3.10: no infos or hints either (no unused object, no missing
        # bufferView target), but for an anisotropic material's tangents, which that validator counts as unused
        # (UNUSED_MESH_TANGENT: it knows KHR_materials_anisotropy's factors, not that the extension "MUST have a
        # defined tangent space"); a newer validator may add infos, which this does not hold against it.
        assert issues["numErrors"] == issues["numWarnings"] == 0


@pytest.mark.heavy
@needs_validator
@parametrize_cases()
def test_every_models_export_is_valid(tmp_path, model, options, params):
    # The materials above cover every kind brdffit writes; this writes each catalogued model's own (1–10 s each).
    result = FitResult(model, options, ("r", "g", "b"), params, "log", 0.0, 0.0, 0, 0, True)
    material, _, _ = write_gltf(result, tmp_path / "fit.glb")
    (tmp_path / "fit.gltf").write_text(json.dumps(material.to_gltf("fit")), encoding="utf-8")
    for path in (tmp_path / "fit.glb", tmp_path / "fit.gltf"):
        assert_valid(path)


def test_the_format_follows_the_file_name_and_a_contradiction_is_one_line():
    assert export_format("gltf") == "gltf"
    assert export_format("gltf", None, "oak.glb") == "glb"
    assert export_format("gltf", None, "OAK.GLB") == "glb"
    assert export_format("gltf", None, "oak.json") == "gltf"  # another suffix: the target's first format
    assert export_format("gltf", "glb", "oak.bin") == "glb"
    assert export_format("mitsuba", None, "oak.mitsuba.py") == "dict"
    for to, kind, path, message in [
        ("gltf", "glb", "oak.gltf", "format=glb writes .glb files, not oak.gltf (a gltf file's name); name it oak.glb"),
        ("mitsuba", "xml", "a.mitsuba.py", "format=xml writes .xml files, not a.mitsuba.py (a dict file's name)"),
        ("gltf", "xml", "oak.gltf", "format=xml does not apply to target gltf; it writes gltf, glb"),
    ]:
        with pytest.raises(BrdfInputError) as error:
            export_format(to, kind, path)
        assert message in str(error.value) and "\n" not in str(error.value)
