"""A capture of a spatially varying material: ``capture.json`` and the photographs it names, checked before any fit.

A flat sample lies in the plane z = 0 (normal +z, x to the right, y towards the images' top row, millimetres,
centred at the origin) and is photographed under point lights; ``capture.json`` says where::

    {"brdffit_capture": 1,
     "plane": {"width_mm": 100.0, "height_mm": 100.0, "texels": [256, 256]},
     "channels": ["r", "g", "b"],
     "images": [{"file": "img_000.exr",
                 "light": {"position_mm": [120.0, -40.0, 300.0], "intensity": [1.0, 1.0, 1.0]},
                 "camera": {"position_mm": [0.0, 0.0, 400.0]}}]}

``texels`` is ``[rows, columns]`` (H × W); a light's ``intensity`` is one number (every channel's) or one per channel.
Optional keys: ``channels`` (default ``r, g, b`` for three intensities or one number, ``value`` for a list of one),
``mask`` (an image, nonzero where texels are fitted), ``normal_map`` (an H × W × 3 image of tangent-space normals,
``z > 0``, to fit a sample that is not flat), ``saturation`` (a pixel value, in the image file's own values, at or above
which a photograph is saturated: that texel's sample of that image is dropped, not fitted), ``scale`` (what a 16-bit
image's 65,535 stands for; default 1) and, per image, ``"camera": {"matrix": [[...], [...], [...]]}`` (a 3 × 4 OpenCV
pinhole projection ``K [R | t]`` of the plane's millimetres to the photograph's pixels) for a raw, unrectified
photograph, rectified on reading (``texels.py``). Everything else in the file is refused by name (a misspelt key would
be silently ignored otherwise).

Every problem is one line naming the file and what is allowed (:class:`~brdffit.errors.BrdfInputError`), raised by
:func:`read_capture` before any image is read: a light or camera on or below the plane, an intensity with the wrong
number of channels, a missing image; the images' sizes are checked as they are read (``images.py``).
"""

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._files import read_json_file
from ..errors import BrdfInputError

#: The capture file's name inside a capture folder, and the format version it holds.
CAPTURE_FILE = "capture.json"
VERSION = 1
#: The keys a capture, its plane, an image, its light and its camera may have.
CAPTURE_KEYS = {"brdffit_capture", "plane", "channels", "images", "mask", "normal_map", "saturation", "scale"}
PLANE_KEYS = {"width_mm", "height_mm", "texels"}
IMAGE_KEYS = {"file", "light", "camera"}
LIGHT_KEYS = {"position_mm", "intensity"}
CAMERA_KEYS = {"position_mm", "matrix"}


@dataclass(frozen=True, eq=False)
class Shot:
    """One photograph of a capture: its file, the point light (``light_mm``, (3,) mm; radiant ``intensity`` (C,),
    in any unit: the albedos come out in units of radiance per that unit), and the camera: its centre
    (``camera_mm``, (3,) mm) and, for an unrectified photograph, its 3 × 4 projection ``matrix`` (else None)."""

    file: Path
    light_mm: np.ndarray
    intensity: np.ndarray
    camera_mm: np.ndarray
    matrix: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Capture:
    """A capture (module docstring): its ``folder``, the plane's size (``width_mm``, ``height_mm``) and texel grid
    (``shape``, (H, W)), the ``channels``, the ``shots``, and the optional ``mask`` and ``normal_map`` files,
    ``saturation`` level and 16-bit ``scale``."""

    folder: Path
    width_mm: float
    height_mm: float
    shape: tuple[int, int]
    channels: tuple[str, ...]
    shots: tuple[Shot, ...]
    mask: Path | None = None
    normal_map: Path | None = None
    saturation: float | None = None
    scale: float = 1.0

    @property
    def file(self) -> Path:
        """The capture's ``capture.json``."""
        return self.folder / CAPTURE_FILE

    @property
    def n_texels(self) -> int:
        return self.shape[0] * self.shape[1]

    def texel_centres(self, texels: np.ndarray | None = None) -> np.ndarray:
        """The centres (T, 3) of ``texels`` (flat indices; None: all H·W, row by row) in mm (:func:`texel_centres`)."""
        return texel_centres(self.width_mm, self.height_mm, self.shape, texels)

    def resolved(self) -> "Capture":
        """This capture with every file's path absolute: what a Dask worker, started in another folder, opens."""
        shots = tuple(replace(shot, file=shot.file.resolve()) for shot in self.shots)
        mask, normal_map = (None if path is None else path.resolve() for path in (self.mask, self.normal_map))
        return replace(self, folder=self.folder.resolve(), shots=shots, mask=mask, normal_map=normal_map)


def texel_centres(
    width_mm: float, height_mm: float, shape: tuple[int, int], texels: np.ndarray | None = None
) -> np.ndarray:
    """The centres (T, 3) in mm of ``texels`` (flat indices, row by row; None: all H·W) of a ``width_mm`` ×
    ``height_mm`` plane cut into ``shape`` (H, W): texel (r, c) at ``x = (c + ½)·width/W − width/2``,
    ``y = height/2 − (r + ½)·height/H``, ``z = 0``."""
    rows, columns = shape
    row, column = np.divmod(np.arange(rows * columns) if texels is None else np.asarray(texels), columns)
    x = (column + 0.5) * width_mm / columns - width_mm / 2
    y = height_mm / 2 - (row + 0.5) * height_mm / rows
    return np.stack([x, y, np.zeros(np.shape(x))], axis=-1)


def capture_file(path: str | os.PathLike) -> Path:
    """The ``capture.json`` of ``path``: the file itself, or the folder holding it."""
    path = Path(path)
    return path / CAPTURE_FILE if path.is_dir() else path


def read_capture(path: str | os.PathLike) -> Capture:
    """The capture of ``path`` (a capture folder or its ``capture.json``), every field checked (module docstring);
    each image must exist, but is not read."""
    file = capture_file(path)
    return _capture(file, read_json_file(file, "a capture file"))


def _capture(file: Path, document: Any) -> Capture:
    where = _Where(file)
    if not isinstance(document, dict) or "brdffit_capture" not in document:
        raise where.error("", 'not a capture file (no "brdffit_capture" key)')
    where.known(document, "", CAPTURE_KEYS)
    if document["brdffit_capture"] != VERSION:
        raise where.error("brdffit_capture", f"{document['brdffit_capture']!r}: this brdffit reads version {VERSION}")
    plane = where.mapping(document, "plane", PLANE_KEYS)
    width, height = (where.positive(plane, key, "plane.") for key in ("width_mm", "height_mm"))
    texels = plane.get("texels")
    if not (
        isinstance(texels, list)
        and len(texels) == 2
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in texels)
    ):
        raise where.error("plane.texels", f"{texels!r}: must be [rows, columns], two whole numbers ≥ 1")
    images = document.get("images")
    if not isinstance(images, list) or not images:
        raise where.error("images", "must be a list of at least one image")
    first_light = _light(where, images[0], 0)
    first_intensity = where.vector(first_light, "intensity", "images[0].light.", None)
    given_one = not isinstance(first_light["intensity"], list)  # a number: every channel's, r, g, b unless named
    channels = _channels(where, document.get("channels"), 3 if given_one else len(first_intensity), given_one)
    shots = tuple(_shot(where, image, index, len(channels)) for index, image in enumerate(images))
    saturation = document.get("saturation")
    if saturation is not None:
        saturation = where.positive(document, "saturation", "")
    scale = where.positive(document, "scale", "") if "scale" in document else 1.0
    optional = {key: _image_file(where, document, key) for key in ("mask", "normal_map")}
    return Capture(
        file.parent, width, height, (texels[0], texels[1]), channels, shots, saturation=saturation, scale=scale,
        **optional,
    )  # fmt: skip


def _channels(where: "_Where", names: Any, count: int, any_count: bool) -> tuple[str, ...]:
    """The channels ``names`` gives, or by ``count`` (3: r, g, b; 1: value); ``any_count``: the intensity is one
    number, which holds for any number of named channels."""
    if names is not None and any_count:
        count = len(names) if isinstance(names, list) else count
    if names is None:
        if count not in (1, 3):
            raise where.error("channels", f"missing: name the {count} channels the intensities have")
        return ("value",) if count == 1 else ("r", "g", "b")
    if not (isinstance(names, list) and names and all(isinstance(name, str) and name for name in names)):
        raise where.error("channels", f"{names!r}: must be a list of channel names")
    if len(set(names)) != len(names):
        raise where.error("channels", f"{names!r}: a channel is named twice")
    if len(names) != count:
        raise where.error("channels", f"{len(names)} channels, but images[0].light.intensity has {count} values")
    return tuple(names)


def _light(where: "_Where", image: Any, index: int) -> dict:
    if not isinstance(image, dict):
        raise where.error(f"images[{index}]", "must be an object with file, light and camera")
    return where.mapping(image, "light", LIGHT_KEYS, f"images[{index}].")


def _shot(where: "_Where", image: Any, index: int, n_channels: int) -> Shot:
    prefix = f"images[{index}]."
    light = _light(where, image, index)
    where.known(image, prefix, IMAGE_KEYS)
    file = _image_file(where, image, "file", prefix)
    if file is None:
        raise where.error(f"{prefix}file", "missing: the image's file name")
    position = where.vector(light, "position_mm", f"{prefix}light.", 3)
    if not position[2] > 0.0:
        raise where.error(
            f"{prefix}light.position_mm", f"z = {position[2]:g} mm: the light must be above the sample's plane (z > 0)"
        )
    intensity = where.vector(light, "intensity", f"{prefix}light.", None)
    if len(intensity) == 1 and n_channels > 1:
        intensity = np.full(n_channels, intensity[0])
    if len(intensity) != n_channels:
        raise where.error(f"{prefix}light.intensity", f"{len(intensity)} values for {n_channels} channels")
    if not np.all(intensity > 0.0):
        raise where.error(f"{prefix}light.intensity", "every value must be > 0")
    camera = where.mapping(image, "camera", CAMERA_KEYS, prefix)
    matrix = None
    if "matrix" in camera:
        matrix = _matrix(where, camera["matrix"], f"{prefix}camera.matrix")
        centre = _centre_of(matrix)
        if "position_mm" in camera and not np.allclose(
            where.vector(camera, "position_mm", prefix, 3), centre, atol=1e-3
        ):
            raise where.error(f"{prefix}camera.position_mm", f"differs from the matrix's centre {np.round(centre, 3)}")
    else:
        centre = where.vector(camera, "position_mm", f"{prefix}camera.", 3)
    if not centre[2] > 0.0:
        raise where.error(
            f"{prefix}camera", f"z = {centre[2]:g} mm: the camera must be above the sample's plane (z > 0)"
        )
    return Shot(file, position, intensity, centre, matrix)


def _matrix(where: "_Where", value: Any, name: str) -> np.ndarray:
    try:
        matrix = np.array(value, dtype=float)
    except (TypeError, ValueError):
        matrix = np.zeros(0)
    if matrix.shape != (3, 4) or not np.all(np.isfinite(matrix)):
        raise where.error(name, "must be a 3 × 4 projection matrix of finite numbers (three rows of four)")
    if abs(np.linalg.det(matrix[:, :3])) < 1e-12 * max(float(np.abs(matrix[:, :3]).max()), 1e-300) ** 3:
        raise where.error(name, "its left 3 × 3 block is singular: not a camera's projection")
    return matrix


def _centre_of(matrix: np.ndarray) -> np.ndarray:
    """The centre (mm) of the camera whose projection is ``matrix = [M | p]``: ``−M⁻¹ p`` (Hartley and Zisserman,
    *Multiple View Geometry*, 2nd ed., §6.2.4)."""
    return -np.linalg.solve(matrix[:, :3], matrix[:, 3])


def _image_file(where: "_Where", mapping: dict, key: str, prefix: str = "") -> Path | None:
    name = mapping.get(key)
    if name is None:
        return None
    if not isinstance(name, str) or not name:
        raise where.error(f"{prefix}{key}", f"{name!r}: must be a file name")
    path = where.file.parent / name
    if not path.is_file():
        raise BrdfInputError(f"{where.file}: {prefix}{key}: {path}: no such file")
    return path


@dataclass(frozen=True)
class _Where:
    """Error lines about the capture file ``file``."""

    file: Path

    def error(self, key: str, what: str) -> BrdfInputError:
        return BrdfInputError(f"{self.file}: {key + ': ' if key else ''}{what}")

    def known(self, mapping: dict, prefix: str, keys: set[str]) -> None:
        unknown = sorted(set(mapping) - keys)
        if unknown:
            raise self.error(f"{prefix}{unknown[0]}", f"unknown key; allowed: {', '.join(sorted(keys))}")

    def mapping(self, parent: dict, key: str, keys: set[str], prefix: str = "") -> dict:
        value = parent.get(key)
        if not isinstance(value, dict):
            raise self.error(f"{prefix}{key}", "missing, or not an object")
        self.known(value, f"{prefix}{key}.", keys)
        return value

    def positive(self, mapping: dict, key: str, prefix: str) -> float:
        value = mapping.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise self.error(f"{prefix}{key}", f"{value!r}: must be a number > 0")
        return float(value)

    def vector(self, mapping: dict, key: str, prefix: str, length: int | None) -> np.ndarray:
        value = mapping.get(key)
        if isinstance(value, int | float) and not isinstance(value, bool) and length is None:
            value = [value]
        ok = (
            isinstance(value, list)
            and value
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        )
        if not ok or (length is not None and len(value or ()) != length):
            size = f"{length} numbers" if length else "a number or a list of numbers"
            raise self.error(f"{prefix}{key}", f"{value!r}: must be {size}")
        return np.array(value, dtype=float)
