"""The sphere a glTF viewer shows an exported material on, and the two files that hold them: ``.gltf`` (JSON, the
mesh's bytes in a base64 ``data:`` URI) and ``.glb`` (binary glTF: the JSON and the bytes in one container).

A glTF document holding a material alone shows nothing in a viewer: only a mesh in a scene is drawn. The preview
is a unit sphere (glTF's units: metres), its pole on glTF's up axis +y, with per-vertex normals, in the layout the
glTF 2.0 specification asks of a mesh (§3.7: triangles, counter-clockwise seen from outside; §3.6: accessors of
vertex attributes with ``min``/``max`` for ``POSITION``, 4-byte aligned; §4.4: the GLB container). An anisotropic
material (``KHR_materials_anisotropy``, which "MUST have a defined tangent space") also gets per-vertex tangents
(``TANGENT``, §3.7.2.1: unit ``xyz`` and the handedness ``w = ±1``, the bitangent ``cross(normal, tangent.xyz) · w``):
along the sphere's lines of latitude, eastwards (the direction of increasing azimuth about +y), with ``w = +1`` so that
tangent, bitangent and normal are the data's right-handed ``x``, ``y``, ``z``. The sphere has no texture coordinates,
from which a viewer could derive tangents of its own. The Khronos glTF validator finds no errors and no warnings in
either (``tests/export/test_gltf_preview.py``).
"""

import base64
import json
import struct
from functools import cache
from typing import Any, NamedTuple

import numpy as np

#: The sphere's rings of latitude between its poles, and vertices around each: 1,986 vertices, 3,968 triangles,
#: 71 KiB; smooth to the eye with per-vertex normals.
RINGS = 32
SEGMENTS = 64

# glTF 2.0's numeric codes (§5.1 accessor.componentType, §5.11 bufferView.target, §5.24 primitive.mode).
_FLOAT = 5126
_UNSIGNED_SHORT = 5123
_ARRAY_BUFFER = 34962
_ELEMENT_ARRAY_BUFFER = 34963
_TRIANGLES = 4

# The GLB container (§4.4): the header's magic "glTF", its version, and the chunk types "JSON" and "BIN\0".
_GLB_MAGIC = 0x46546C67
_GLB_VERSION = 2
_JSON_CHUNK = 0x4E4F534A
_BIN_CHUNK = 0x004E4942


class Mesh(NamedTuple):
    """A triangle mesh: ``positions`` and ``normals`` (V, 3) float32, ``indices`` (T, 3) uint16, each triangle
    counter-clockwise seen from the side its normals face; ``tangents`` (V, 4) float32, glTF's ``TANGENT``."""

    positions: np.ndarray
    normals: np.ndarray
    indices: np.ndarray
    tangents: np.ndarray


@cache
def preview_sphere(rings: int = RINGS, segments: int = SEGMENTS) -> Mesh:
    """The unit sphere, pole on +y: one vertex at each pole and ``rings − 1`` rings of ``segments`` vertices, joined
    by fans at the poles and two triangles per quad between rings (no degenerate triangles, no seam duplicates:
    the mesh carries no texture coordinates). Its normals are its positions; its tangents point east along the lines of
    latitude, ``(−sin a, 0, −cos a)`` at azimuth ``a`` (``∂position/∂a`` normalised), with ``w = +1``; at the poles,
    where east is undefined, the azimuth-0 limit ``(0, 0, −1)``, perpendicular to their normals all the same."""
    polar = np.pi * np.arange(1, rings) / rings  # the rings' polar angles from +y, radians
    azimuth = 2.0 * np.pi * np.arange(segments) / segments
    sin_polar, cos_polar = np.sin(polar)[:, None], np.cos(polar)[:, None]
    ring_points = np.stack(
        [
            sin_polar * np.cos(azimuth),
            np.broadcast_to(cos_polar, (rings - 1, segments)),
            -sin_polar * np.sin(azimuth),  # azimuth runs counter-clockwise seen from +y
        ],
        axis=-1,
    ).reshape(-1, 3)
    positions = np.concatenate([[[0.0, 1.0, 0.0]], ring_points, [[0.0, -1.0, 0.0]]])
    north, south = 0, len(positions) - 1

    def vertex(ring, segment):  # ring 0 … rings − 2, segment taken around the ring
        return 1 + ring * segments + segment % segments

    triangles = []
    for s in range(segments):
        triangles.append((north, vertex(0, s), vertex(0, s + 1)))
        for r in range(rings - 2):
            upper, upper_next = vertex(r, s), vertex(r, s + 1)
            lower, lower_next = vertex(r + 1, s), vertex(r + 1, s + 1)
            triangles += [(upper, lower, lower_next), (upper, lower_next, upper_next)]
        triangles.append((south, vertex(rings - 2, s + 1), vertex(rings - 2, s)))
    east = np.stack([-np.sin(azimuth), np.zeros(segments), -np.cos(azimuth)], axis=-1)
    tangents = np.concatenate([east[:1], np.tile(east, (rings - 1, 1)), east[:1]])
    tangents = np.concatenate([tangents, np.ones((len(tangents), 1))], axis=1)
    positions = positions.astype(np.float32)
    # float32 unit vectors: glTF asks normals of unit length, which the float64 values rounded to float32 are to 1e-7.
    indices = np.array(triangles, dtype=np.uint16)
    return Mesh(positions, positions.copy(), indices, tangents.astype(np.float32))


def _scene(
    material: dict[str, Any],
    extensions_used: list[str],
    name: str,
    generator: str,
    buffer: dict[str, Any],
    tangents: bool,
) -> dict[str, Any]:
    """The glTF document: ``material`` on the preview sphere (with its ``TANGENT`` attribute where ``tangents``), in a
    scene of one node named ``name``, ``generator`` in its ``asset``; ``buffer`` is the buffer object (its
    ``byteLength``, and its ``uri`` in a ``.gltf``)."""
    arrays = _mesh_arrays(tangents)
    sizes = [array.nbytes for array in arrays]
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).tolist()
    targets = [_ARRAY_BUFFER] * (len(arrays) - 1) + [_ELEMENT_ARRAY_BUFFER]
    positions, indices = arrays[0], arrays[-1]
    attributes = {"POSITION": 0, "NORMAL": 1} | ({"TANGENT": 2} if tangents else {})
    document: dict[str, Any] = {"asset": {"version": "2.0", "generator": generator}}
    if extensions_used:
        document["extensionsUsed"] = list(extensions_used)
    accessors = [
        {
            "bufferView": 0,
            "componentType": _FLOAT,
            "count": len(positions),
            "type": "VEC3",
            "min": positions.min(axis=0).tolist(),
            "max": positions.max(axis=0).tolist(),
        },
        {"bufferView": 1, "componentType": _FLOAT, "count": len(positions), "type": "VEC3"},
    ]
    if tangents:
        accessors.append({"bufferView": 2, "componentType": _FLOAT, "count": len(positions), "type": "VEC4"})
    accessors.append(
        {"bufferView": len(arrays) - 1, "componentType": _UNSIGNED_SHORT, "count": indices.size, "type": "SCALAR"}
    )
    document |= {
        "scene": 0,
        "scenes": [{"name": name, "nodes": [0]}],
        "nodes": [{"name": name, "mesh": 0}],
        "meshes": [
            {
                "name": "brdffit preview sphere",
                "primitives": [
                    {"attributes": attributes, "indices": len(arrays) - 1, "material": 0, "mode": _TRIANGLES}
                ],
            }
        ],
        "materials": [material],
        "accessors": accessors,
        "bufferViews": [
            {"buffer": 0, "byteOffset": offset, "byteLength": size, "target": target}
            for offset, size, target in zip(offsets, sizes, targets, strict=True)
        ],
        "buffers": [buffer],
    }
    return document


def _mesh_arrays(tangents: bool) -> list[np.ndarray]:
    """The sphere's arrays as the buffer holds them, in order: positions, normals, tangents where asked, indices."""
    mesh = preview_sphere()
    return [mesh.positions, mesh.normals, *([mesh.tangents] if tangents else []), mesh.indices]


def _mesh_bytes(tangents: bool) -> bytes:
    """The sphere's arrays (:func:`_mesh_arrays`), little-endian, each a multiple of 4 bytes long."""
    arrays = _mesh_arrays(tangents)
    data = b"".join(array.astype(array.dtype.newbyteorder("<")).tobytes() for array in arrays)
    assert len(data) % 4 == 0  # 12 or 16 bytes a vertex; 6 a triangle, an even count of which the sphere has
    return data


def gltf_document(
    material: dict[str, Any], extensions_used: list[str], name: str, generator: str, *, tangents: bool = False
) -> dict[str, Any]:
    """A ``.gltf`` document (JSON as Python objects): ``material`` (a glTF material object) on the preview sphere,
    with tangents where ``tangents``, ``extensions_used`` listed, the mesh's bytes in a base64 ``data:`` URI."""
    data = _mesh_bytes(tangents)
    buffer = {"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}
    return _scene(material, extensions_used, name, generator, buffer, tangents)


def glb_bytes(
    material: dict[str, Any], extensions_used: list[str], name: str, generator: str, *, tangents: bool = False
) -> bytes:
    """A ``.glb`` file's bytes: the document of :func:`gltf_document` with its buffer in the container's binary
    chunk (:func:`glb_container`)."""
    data = _mesh_bytes(tangents)
    return glb_container(_scene(material, extensions_used, name, generator, {"byteLength": len(data)}, tangents), data)


def glb_container(document: dict[str, Any], data: bytes) -> bytes:
    """A ``.glb`` file's bytes: ``document`` (whose one buffer has no ``uri``) and its buffer's ``data``. Chunks are
    padded to 4 bytes, the JSON with spaces and the binary with zeros (§4.4.3)."""
    text = json.dumps(document, ensure_ascii=False, allow_nan=False, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    data += b"\0" * (-len(data) % 4)
    length = 12 + 8 + len(text) + 8 + len(data)
    return b"".join(
        [
            struct.pack("<III", _GLB_MAGIC, _GLB_VERSION, length),
            struct.pack("<II", len(text), _JSON_CHUNK),
            text,
            struct.pack("<II", len(data), _BIN_CHUNK),
            data,
        ]
    )
