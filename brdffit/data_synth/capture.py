"""Synthetic captures of spatially varying materials, made from known maps: for tests, examples and benchmarks.

A material's maps blend two parameter sets, ``first`` and ``second``, by a smooth field ``t(x, y)`` in [0, 1] (a sum
of two slanted waves; a roughness, exponent or index blends in its logarithm, an albedo linearly), so every texel
is a plausible material and neighbours differ a little. The sample is photographed by a camera overhead under
``n_images`` point lights on a dome (a Fibonacci spiral over zenith angles :data:`LIGHT_ZENITHS`, the first light
near the camera's mirror direction of the sample's centre) at :data:`LIGHT_DISTANCE_MM`; each photograph's
radiance ``L = f · I · cos θi / d²`` (``brdffit/svbrdf/texels.py``'s geometry) gets seeded multiplicative noise.

::

    truth = synth_capture("capture/", "ward", shape=(64, 64), n_images=32, noise=0.01, seed=0)

writes ``capture/capture.json``, the photographs (``img_000.npy`` …, or ``.exr``) and ``capture/truth.npz`` (the
maps' true parameters, named as a maps folder's ``params.npz``), and returns the true maps.
"""

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from brdffit._files import atomic_path, write_text_atomic
from brdffit.errors import BrdfInputError
from brdffit.physics.models.registry import model_for
from brdffit.svbrdf.capture import CAPTURE_FILE, VERSION, texel_centres
from brdffit.svbrdf.images import write_exr
from brdffit.svbrdf.maps import flat_params
from brdffit.svbrdf.relight import stacked_params, texel_brdf
from brdffit.svbrdf.texels import point_light

#: A glTF dielectric and Mitsuba principled plastic, without coat, anisotropy or sheen: the first of their pairs.
_GLTF = {"base_color": [0.6, 0.3, 0.15], "roughness": 0.35, "metallic": 0.0, "ior": 1.5, "clearcoat": 0.0,
         "clearcoat_roughness": 0.1, "anisotropy_strength": 0.0, "anisotropy_rotation": 0.0}  # fmt: skip
_PRINCIPLED = {"base_color": [0.7, 0.3, 0.15], "roughness": 0.3, "metallic": 0.0, "specular": 0.5,
               "spec_tint": 0.0, "anisotropic": 0.0, "sheen": 0.0, "sheen_tint": 0.0, "clearcoat": 0.0,
               "clearcoat_gloss": 1.0}  # fmt: skip
#: Two materials per model that a capture's maps blend, where the user gives none.
MATERIALS: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {
    "lambert": ({"rho_d": [0.6, 0.35, 0.2]}, {"rho_d": [0.15, 0.3, 0.55]}),
    "ward": (
        {"rho_d": [0.45, 0.3, 0.2], "rho_s": [0.06, 0.06, 0.06], "alpha": 0.12},
        {"rho_d": [0.12, 0.22, 0.35], "rho_s": [0.15, 0.15, 0.15], "alpha": 0.3},
    ),
    "gltf": (_GLTF, _GLTF | {"base_color": [0.9, 0.75, 0.4], "roughness": 0.6, "metallic": 1.0}),
    "principled": (_PRINCIPLED, _PRINCIPLED | {"base_color": [0.2, 0.4, 0.7], "roughness": 0.6}),
    "cook-torrance": (
        {"kd": [0.45, 0.3, 0.2], "ks": [0.5, 0.5, 0.5], "m": 0.15, "f0": 0.04},
        {"kd": [0.12, 0.22, 0.35], "ks": [0.9, 0.9, 0.9], "m": 0.35, "f0": 0.04},
    ),
}
#: Parameters blended in their logarithm (scales: a roughness, an exponent, an index).
LOG_BLENDED = ("alpha", "alpha_x", "alpha_y", "alpha_u", "alpha_v", "m", "n", "roughness", "eta", "k")
#: The lights' dome: distance from the sample's centre (mm) and the range of zenith angles (degrees).
LIGHT_DISTANCE_MM = 300.0
LIGHT_ZENITHS = (2.0, 70.0)
#: The camera's height above the sample's centre (mm).
CAMERA_HEIGHT_MM = 400.0
FORMATS = ("npy", "exr")


def blend_field(shape: tuple[int, int]) -> np.ndarray:
    """The smooth field ``t`` (H, W) in [0, 1] a synthetic capture blends its two materials by."""
    rows, columns = shape
    v, u = np.meshgrid((np.arange(rows) + 0.5) / rows, (np.arange(columns) + 0.5) / columns, indexing="ij")
    wave = np.sin(2.0 * np.pi * (0.8 * u + 0.3 * v)) + 0.6 * np.cos(2.0 * np.pi * (0.4 * u - 0.9 * v) + 0.7)
    return (wave + 1.6) / 3.2


def blended_maps(model: str, first: dict[str, Any], second: dict[str, Any], shape: tuple[int, int]):
    """The true maps (name → (H, W) or (H, W, C), as :func:`brdffit.svbrdf.maps.flat_params` names them) of
    ``first`` blended into ``second`` by :func:`blend_field`."""
    t = blend_field(shape)
    a, b = flat_params(first), flat_params(second)
    if a.keys() != b.keys():
        raise BrdfInputError(f"the two materials of a {model} capture name different parameters: {sorted(a)}")
    maps = {}
    for name in a:
        low, high = np.asarray(a[name], dtype=float), np.asarray(b[name], dtype=float)
        weight = t.reshape(*shape, *([1] * low.ndim))
        if name in LOG_BLENDED and np.all(low > 0) and np.all(high > 0):
            maps[name] = np.exp(np.log(low) + (np.log(high) - np.log(low)) * weight)
        else:
            maps[name] = low + (high - low) * weight
    return maps


def light_positions(n_images: int) -> np.ndarray:
    """The lights (n_images, 3) in mm: a Fibonacci spiral over the dome's zenith angles (module docstring)."""
    index = np.arange(n_images)
    low, high = np.cos(np.radians(LIGHT_ZENITHS[1])), np.cos(np.radians(LIGHT_ZENITHS[0]))
    cos_zenith = high - (high - low) * (index + 0.5) / n_images
    azimuth = index * np.pi * (3.0 - np.sqrt(5.0))
    sin_zenith = np.sqrt(1.0 - cos_zenith**2)
    unit = np.stack([sin_zenith * np.cos(azimuth), sin_zenith * np.sin(azimuth), cos_zenith], axis=-1)
    return LIGHT_DISTANCE_MM * unit


def write_capture(
    folder: str | os.PathLike,
    brdf: Callable[[np.ndarray, np.ndarray], np.ndarray],
    lights_mm: np.ndarray,
    *,
    shape: tuple[int, int],
    size_mm: float = 100.0,
    camera_mm=(0.0, 0.0, CAMERA_HEIGHT_MM),
    noise: float = 0.01,
    seed: int = 0,
    image_format: str = "npy",
) -> None:
    """Write ``capture.json`` and one photograph per light of ``lights_mm`` (n, 3) into ``folder``: a ``size_mm``
    square sample of ``shape`` texels whose BRDF ``brdf(wi, wo) -> (H·W, C)`` gives each texel's value at its own
    pair (texel ``t`` at ``wi[t]``, ``wo[t]``, row by row), seen by a camera at ``camera_mm``; each radiance
    ``f · cos θi / d²`` (intensity 1) with multiplicative noise ``noise`` seeded by ``seed``."""
    if image_format not in FORMATS:
        raise BrdfInputError(f"image format {image_format!r}; use {' or '.join(FORMATS)}")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    centres = texel_centres(size_mm, size_mm, shape)
    camera = np.asarray(camera_mm, dtype=float)
    rng = np.random.default_rng(seed)
    images = []
    for index, light in enumerate(np.asarray(lights_mm, dtype=float)):
        wi, wo, squared = (array[:, 0] for array in point_light(centres, light[None], camera[None]))
        radiance = np.asarray(brdf(wi, wo)) * (wi[:, 2] / squared)[:, None]
        radiance *= 1.0 + noise * rng.standard_normal(radiance.shape)
        image = np.maximum(radiance, 0.0).reshape(*shape, -1).astype(np.float32)
        name = f"img_{index:03d}.{image_format}"
        if image_format == "npy":
            np.save(folder / name, image)
        else:
            write_exr(folder / name, image)
        images.append(
            {
                "file": name,
                "light": {"position_mm": light.tolist(), "intensity": [1.0] * image.shape[-1]},
                "camera": {"position_mm": camera.tolist()},
            }
        )
    capture = {
        "brdffit_capture": VERSION,
        "plane": {"width_mm": size_mm, "height_mm": size_mm, "texels": list(shape)},
        "images": images,
    }
    write_text_atomic(folder / CAPTURE_FILE, json.dumps(capture, indent=1) + "\n")


def synth_capture(
    folder: str | os.PathLike,
    model: str = "ward",
    first: dict[str, Any] | None = None,
    second: dict[str, Any] | None = None,
    *,
    shape: tuple[int, int] = (32, 32),
    size_mm: float = 100.0,
    n_images: int = 32,
    noise: float = 0.01,
    seed: int = 0,
    image_format: str = "npy",
    **model_options: Any,
) -> dict[str, np.ndarray]:
    """Write a capture of ``model``'s maps blending ``first`` and ``second`` (default :data:`MATERIALS`) into
    ``folder`` (module docstring): ``shape`` texels over a ``size_mm`` square, ``n_images`` photographs with
    multiplicative noise ``noise`` (0.01 is 1%, seeded by ``seed``), as ``image_format`` (``npy`` or ``exr``);
    returns the true maps, also written to ``truth.npz``."""
    if first is None or second is None:
        if model not in MATERIALS:
            raise BrdfInputError(f"give the two materials of a {model} capture; built in: {', '.join(MATERIALS)}")
        first, second = MATERIALS[model]
    built = model_for(model, first, **model_options)
    maps = blended_maps(model, first, second, shape)
    flat = {name: values.reshape(-1, *values.shape[2:]) for name, values in maps.items()}
    stacked = stacked_params(built, flat, np.arange(shape[0] * shape[1]))
    folder = Path(folder)
    write_capture(
        folder,
        lambda wi, wo: texel_brdf(built, stacked, wi, wo),
        light_positions(n_images),
        shape=shape,
        size_mm=size_mm,
        noise=noise,
        seed=seed,
        image_format=image_format,
    )
    with atomic_path(folder / "truth.npz") as temporary, open(temporary, "wb") as stream:
        np.savez(stream, **maps)
    return maps
