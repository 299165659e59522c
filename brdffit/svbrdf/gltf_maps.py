"""The maps of a ``gltf`` fit as a glTF 2.0 binary (``.glb``): a quad the size of the sample with the maps as its
material's textures, which a glTF viewer shows as the material scanned.

glTF's metallic-roughness material takes textures for exactly the parameters brdffit's ``gltf`` model fits
(``physics/renderers/gltf_model.py``), each texture's value multiplied by a factor of 1 (glTF 2.0 §3.9.2):

* ``base_color``: ``baseColorTexture``, sRGB-encoded as the specification requires;
* ``roughness`` and ``metallic``: ``metallicRoughnessTexture``'s green and blue channels, linear;
* ``clearcoat`` and ``clearcoat_roughness`` (where any texel has a coat): ``KHR_materials_clearcoat``'s
  ``clearcoatTexture`` (red) and ``clearcoatRoughnessTexture`` (green), linear;
* ``ior``: ``KHR_materials_ior``'s one number (glTF has no texture for it): the maps' median, with a note when the
  texels' values differ;
* ``anisotropy_strength`` and ``anisotropy_rotation`` (where any texel is anisotropic): ``KHR_materials_anisotropy``'s
  ``anisotropyTexture``, linear: red and green the lobe's direction ``(cos r, sin r)`` in [-1, 1] (stored as
  ``(d + 1)/2``) in the tangent-bitangent plane, blue the strength; the quad then carries glTF's ``TANGENT``
  attribute, ``(1, 0, 0, 1)``: the tangent is the capture's ``+x`` and the bitangent ``cross(normal, tangent)``
  its ``+y``, the frame the ``gltf`` model's rotation is measured in (``physics/renderers/gltf.py``);
* ``sheen_color`` and ``sheen_roughness`` (a ``gltf:sheen=true`` fit where any texel has a sheen):
  ``KHR_materials_sheen``'s ``sheenColorTexture`` (red, green, blue, sRGB-encoded as the extension requires) and
  ``sheenRoughnessTexture`` (alpha, linear), one RGBA image.

Textures are 8-bit PNG images inside the file (the only depth glTF viewers read alike), so each value is rounded to
1/255 (the colours in sRGB's steps; the rotation to the angle of its rounded direction): the export says how far that
moves each map (``GltfMaps.quantization``). A texel that was not fitted is black (base colour 0), rough (roughness
1), isotropic and without a sheen.

The quad lies in glTF's x-y plane (metres, the capture's frame: x to the right, y up), facing +z, where a viewer's
default camera looks; texture coordinate (0, 0) is the images' top left (§3.8.4), texel (0, 0).
"""

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path
from .._version import __version__
from ..errors import Argument, BrdfInputError
from ..export.gltf_preview import glb_container
from ..physics.renderers.gltf import MIN_ANISOTROPY
from .images import png_bytes, srgb_decoded, srgb_encoded
from .maps import GLB_FILE, Maps

_FLOAT, _UNSIGNED_SHORT = 5126, 5123
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_LINEAR, _CLAMP_TO_EDGE = 9729, 33071


@dataclass
class GltfMaps:
    """A ``.glb`` of ``maps`` (:func:`gltf_maps`): its ``data`` (bytes), the ``notes`` a user must read, and the
    largest change 8-bit textures make to each exported map (``quantization``: name → absolute difference)."""

    data: bytes
    notes: list[str] = field(default_factory=list)
    quantization: dict[str, float] = field(default_factory=dict)


def gltf_maps(maps: Maps, name: str = "brdffit maps") -> GltfMaps:
    """The ``.glb`` of the maps of a ``gltf`` fit (module docstring); anything else is refused in one line."""
    if maps.model != "gltf":
        raise BrdfInputError(
            f"the maps of a {maps.model} fit do not map onto glTF's material texel by texel: fit the capture with ",
            Argument("model", "gltf"),
            " (or export one texel's parameters)",
        )
    if len(maps.channels) != 3:
        raise BrdfInputError(f"glTF's textures are RGB; these maps have {len(maps.channels)} channel(s)")
    if not maps.fitted.any():
        raise BrdfInputError("no texel was fitted: there is no material to export")
    fitted, notes = maps.fitted, []
    base = np.where(fitted[..., None], maps.params["base_color"], 0.0)
    roughness = np.where(fitted, maps.params["roughness"], 1.0)
    metallic = np.where(fitted, maps.params["metallic"], 0.0)
    zeros = np.zeros(maps.shape)
    images = {
        "base_color": png_bytes(srgb_encoded(base)),
        "metallic_roughness": png_bytes(np.stack([zeros, roughness, metallic], -1)),
    }
    quantization = {
        "base_color": _largest(srgb_decoded(np.round(srgb_encoded(base) * 255) / 255), base),
        "roughness": _largest(np.round(roughness * 255) / 255, roughness),
        "metallic": _largest(np.round(metallic * 255) / 255, metallic),
    }
    coat = np.where(fitted, maps.params["clearcoat"], 0.0)
    material: dict[str, Any] = {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0},
            "metallicRoughnessTexture": {"index": 1},
        },
    }
    extensions: dict[str, Any] = {}
    if np.any(coat > 0):
        coat_roughness = np.where(fitted, maps.params["clearcoat_roughness"], 0.0)
        index = len(images)
        images["clearcoat"] = png_bytes(np.stack([coat, coat_roughness, zeros], -1))
        extensions["KHR_materials_clearcoat"] = {
            "clearcoatFactor": 1.0,
            "clearcoatTexture": {"index": index},
            "clearcoatRoughnessFactor": 1.0,
            "clearcoatRoughnessTexture": {"index": index},
        }
        quantization["clearcoat"] = _largest(np.round(coat * 255) / 255, coat)
        quantization["clearcoat_roughness"] = _largest(np.round(coat_roughness * 255) / 255, coat_roughness)
    ior = maps.params["ior"][fitted]
    median_ior = float(np.median(ior)) if ior.size else 1.5
    if ior.size and np.ptp(ior) > 1e-9:
        notes.append(
            f"ior varies over the texels ({ior.min():.4g}–{ior.max():.4g}); glTF holds one: the median,"
            f" {median_ior:.4g}"
        )
    if abs(median_ior - 1.5) > 1e-12:
        extensions["KHR_materials_ior"] = {"ior": median_ior}
    anisotropic = _anisotropy(maps, images, extensions, quantization, notes)
    _sheen(maps, images, extensions, quantization)
    if extensions:
        material["extensions"] = extensions
    return GltfMaps(_glb(maps, material, images, sorted(extensions), anisotropic), notes, quantization)


def _anisotropy(maps: Maps, images: dict, extensions: dict, quantization: dict, notes: list[str]) -> bool:
    """``KHR_materials_anisotropy``'s texture of ``maps`` added to ``images``, ``extensions`` and its rounding to
    ``quantization`` (module docstring), with its notes; whether there is one (a texel of strength at least
    ``MIN_ANISOTROPY``, below which the ``gltf`` model is isotropic)."""
    fitted = maps.fitted
    strength = np.where(fitted, maps.params.get("anisotropy_strength", np.zeros(maps.shape)), 0.0)
    if not np.any(strength >= MIN_ANISOTROPY):
        return False
    rotation = np.where(fitted, maps.params["anisotropy_rotation"], 0.0)
    direction = np.stack([np.cos(rotation), np.sin(rotation)], -1)
    index = len(images)
    images["anisotropy"] = png_bytes(np.concatenate([(direction + 1.0) / 2.0, strength[..., None]], -1))
    extensions["KHR_materials_anisotropy"] = {
        "anisotropyStrength": 1.0,
        "anisotropyRotation": 0.0,
        "anisotropyTexture": {"index": index},
    }
    rounded = np.round((direction + 1.0) / 2.0 * 255) / 255 * 2.0 - 1.0
    turned = np.arctan2(rounded[..., 1], rounded[..., 0]) - rotation
    quantization["anisotropy_strength"] = _largest(np.round(strength * 255) / 255, strength)
    quantization["anisotropy_rotation"] = float(np.max(np.abs((turned + np.pi / 2) % np.pi - np.pi / 2)))
    notes.append(
        "anisotropic (KHR_materials_anisotropy): the texture's directions are turned from the mesh's tangent, which"
        " the quad has along the capture's +x; on another mesh the tangents must lie where the capture's +x lay"
    )
    isotropic = int(np.sum(fitted & (strength < MIN_ANISOTROPY)))
    if isotropic:
        notes.append(
            f"{isotropic} of {int(fitted.sum())} texels are isotropic, fitted with glTF's core lobe; a viewer shades"
            " them with the extension's, whose visibility is clamped to 1: where light and view both lie beyond 60°"
            " near the mirror they render darker than their fit (27% of it at 75°)"
        )
    return True


def _sheen(maps: Maps, images: dict, extensions: dict, quantization: dict) -> None:
    """``KHR_materials_sheen``'s texture of ``maps`` (one RGBA image) added to ``images``, ``extensions`` and its
    rounding to ``quantization``, where a fitted texel has a sheen (module docstring)."""
    fitted, sheen = maps.fitted, maps.params.get("sheen_color")
    if sheen is None or not np.any(sheen[fitted] > 0):
        return
    color = np.where(fitted[..., None], sheen, 0.0)
    roughness = np.where(fitted, maps.params["sheen_roughness"], 0.0)
    index = len(images)
    images["sheen"] = png_bytes(np.concatenate([srgb_encoded(color), roughness[..., None]], -1))
    extensions["KHR_materials_sheen"] = {
        "sheenColorFactor": [1.0, 1.0, 1.0],
        "sheenColorTexture": {"index": index},
        "sheenRoughnessFactor": 1.0,
        "sheenRoughnessTexture": {"index": index},
    }
    quantization["sheen_color"] = _largest(srgb_decoded(np.round(srgb_encoded(color) * 255) / 255), color)
    quantization["sheen_roughness"] = _largest(np.round(roughness * 255) / 255, roughness)


def write_glb(folder: str | os.PathLike, maps: Maps) -> dict[str, Any]:
    """The maps of a ``gltf`` fit as ``folder/material.glb`` (:func:`gltf_maps`), atomically, and what the maps'
    ``maps.json`` says of it: the file, its notes and its textures' rounding; or why it was not written (a map glTF
    cannot hold texel by texel)."""
    try:
        exported = gltf_maps(maps)
    except BrdfInputError as error:
        return {"file": None, "not_written": str(error)}
    Path(folder).mkdir(parents=True, exist_ok=True)
    with atomic_path(Path(folder) / GLB_FILE) as temporary:
        temporary.write_bytes(exported.data)
    return {"file": GLB_FILE, "notes": exported.notes, "quantization": exported.quantization}


def _largest(rounded: np.ndarray, values: np.ndarray) -> float:
    return float(np.max(np.abs(rounded - values), initial=0.0))


def _accessors(positions: np.ndarray, tangents: bool) -> list[dict[str, Any]]:
    """The quad's accessors, one per buffer view in order: positions (with their bounds, §3.6.2.4), normals, texture
    coordinates, tangents where ``tangents``, indices."""
    bounds = {"min": positions.min(axis=0).tolist(), "max": positions.max(axis=0).tolist()}
    kinds = [("VEC3", _FLOAT), ("VEC3", _FLOAT), ("VEC2", _FLOAT)] + [("VEC4", _FLOAT)] * tangents
    accessors: list[dict[str, Any]] = [
        {"bufferView": view, "componentType": component, "count": 4, "type": kind}
        for view, (kind, component) in enumerate(kinds)
    ]
    accessors[0] |= bounds
    accessors.append({"bufferView": len(kinds), "componentType": _UNSIGNED_SHORT, "count": 6, "type": "SCALAR"})
    return accessors


def _glb(
    maps: Maps, material: dict[str, Any], images: dict[str, bytes], extensions: list[str], tangents: bool = False
) -> bytes:
    """The quad (module docstring) with ``material`` and its PNG ``images`` (in texture order) in one buffer, and
    per-vertex tangents along ``+x`` where ``tangents`` (an anisotropic material's)."""
    half_width, half_height = maps.width_mm / 2000.0, maps.height_mm / 2000.0  # metres
    positions = np.array(
        [[-half_width, half_height, 0], [-half_width, -half_height, 0], [half_width, -half_height, 0],
         [half_width, half_height, 0]], dtype="<f4",
    )  # fmt: skip
    normals = np.tile(np.array([0.0, 0.0, 1.0], dtype="<f4"), (4, 1))
    coordinates = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], dtype="<f4")
    tangent = np.tile(np.array([1.0, 0.0, 0.0, 1.0], dtype="<f4"), (4, 1))  # w = 1: bitangent cross(z, x) = +y
    indices = np.array([0, 1, 2, 0, 2, 3, 0, 0], dtype="<u2")  # two triangles, counter-clockwise seen from +z; padded
    arrays = [positions, normals, coordinates] + [tangent] * tangents
    pieces = [array.tobytes() for array in arrays] + [indices.tobytes()]
    pieces += [image + b"\0" * (-len(image) % 4) for image in images.values()]
    offsets = np.concatenate([[0], np.cumsum([len(piece) for piece in pieces])[:-1]]).tolist()
    lengths = [len(piece) for piece in pieces[: len(arrays)]] + [12] + list(map(len, images.values()))
    views = [
        {"buffer": 0, "byteOffset": offset, "byteLength": length}
        for offset, length in zip(offsets, lengths, strict=True)
    ]
    for view, target in zip(views, [_ARRAY_BUFFER] * len(arrays) + [_ELEMENT_ARRAY_BUFFER], strict=False):
        view["target"] = target
    attributes = {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2} | ({"TANGENT": 3} if tangents else {})
    document: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": f"brdffit {__version__}"},
        **({"extensionsUsed": extensions} if extensions else {}),
        "scene": 0,
        "scenes": [{"name": material["name"], "nodes": [0]}],
        "nodes": [{"name": material["name"], "mesh": 0}],
        "meshes": [
            {
                "name": "the sample",
                "primitives": [{"attributes": attributes, "indices": len(arrays), "material": 0}],
            }
        ],
        "materials": [material],
        "accessors": _accessors(positions, tangents),
        "bufferViews": views,
        "buffers": [{"byteLength": sum(len(piece) for piece in pieces)}],
        "images": [
            {"name": name, "bufferView": len(arrays) + 1 + index, "mimeType": "image/png"}
            for index, name in enumerate(images)
        ],
        "samplers": [{"magFilter": _LINEAR, "minFilter": _LINEAR, "wrapS": _CLAMP_TO_EDGE, "wrapT": _CLAMP_TO_EDGE}],
        "textures": [{"sampler": 0, "source": index} for index in range(len(images))],
    }
    return glb_container(document, b"".join(pieces))
