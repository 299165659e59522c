"""A capture's photographs as BRDF samples, one small dataset per texel.

For texel centre ``p`` (mm, ``Capture.texel_centres``) and a photograph with its point light at ``l`` of radiant
intensity ``I`` (per channel) and its camera at ``e``::

    wi = (l − p)/|l − p|,   wo = (e − p)/|e − p|,   f = L · |l − p|² / (I · cos θi)

(the irradiance of a point light is ``I·cos θi / d²``, and the BRDF is the radiance ``L`` it gives per irradiance;
Nicodemus et al., *Geometrical considerations and nomenclature for reflectance*, NBS Monograph 160, 1977). With a
normal map the directions are taken to the texel's own frame: its tangent-space normal ``n`` (``z > 0``), the
tangent ``t`` the plane's ``x`` made perpendicular to ``n``, ``b = n × t``; ``cos θi`` is then ``wi · n``.

A sample is dropped, not fitted, where the photograph is saturated (any channel at or above the capture's
``saturation``, in the image file's own values: a 16-bit image's integers; a 16-bit image's 65,535 always), where its
value is not finite (a rectified photograph outside the camera's view), where the light or the camera lies at or below
the texel's own horizon (a normal map), and everywhere in a texel the mask leaves out. Negative values (noise below a
camera's black level) are read as 0; with the relative loss, which divides by the value, a sample with a channel at 0
is dropped.
"""

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import map_coordinates

from ..data.samples import Samples
from ..errors import BrdfInputError
from .capture import Capture
from .images import SIXTEEN_BITS, is_sixteen_bit, read_image, read_mask, read_rows

#: The smallest cosine of a light's or camera's angle to a texel's normal that is a sample (an 89.9° grazing angle):
#: below it the cosine's rounding, not the light, decides the value.
MIN_COSINE = np.cos(np.radians(89.9))


@dataclass(frozen=True)
class Photographs:
    """The capture's photographs read, rectified onto its texel grid, at ``texels`` (T,) (flat indices, ascending;
    None: every texel, T = H·W): ``radiance`` (K, T, C) float32 (NaN where a sample is dropped), the ``mask`` (T,) and
    the normals (T, 3) or None."""

    capture: Capture
    radiance: np.ndarray
    mask: np.ndarray
    normals: np.ndarray | None
    texels: np.ndarray | None = None

    def positions(self, texels: np.ndarray) -> np.ndarray:
        """Where the texels ``texels`` (flat indices) lie in these arrays; a texel not read is a ValueError."""
        if self.texels is None:
            return texels
        positions = np.searchsorted(self.texels, texels)
        found = positions < len(self.texels)
        found[found] = self.texels[positions[found]] == np.asarray(texels)[found]
        if not np.all(found):
            raise ValueError(f"texels {np.asarray(texels)[~found][:5].tolist()} were not read")
        return positions


@dataclass(frozen=True)
class TexelSamples:
    """The samples of a run of texels (``texels``, (T,) flat indices, row by row): ``wi``, ``wo`` (T, K, 3) in each
    texel's frame, ``values`` (T, K, C) BRDF in 1/sr, ``kept`` (T, K): which samples count."""

    texels: np.ndarray
    wi: np.ndarray
    wo: np.ndarray
    values: np.ndarray
    kept: np.ndarray

    def samples(self, index: int, channels: tuple[str, ...], source: str) -> Samples:
        """The kept samples of the ``index``-th texel of the run as :class:`~brdffit.data.samples.Samples`: checked
        here as a run (finite, non-negative, above the horizon), so built directly."""
        keep = self.kept[index]
        return Samples(self.wi[index, keep], self.wo[index, keep], self.values[index, keep], channels, source=source)


def read_photographs(capture: Capture, texels: np.ndarray | None = None) -> Photographs:
    """Every photograph of ``capture`` read and rectified, with its mask and normal map (module docstring), at
    ``texels`` (flat indices; None: every texel): one photograph in memory at a time besides them, so a Dask worker
    reads its own texels of a capture no machine holds whole; an image of the wrong size or channel count is a
    one-line error naming it, whichever texels are read (none: the photographs checked)."""
    height, width = capture.shape
    n_channels = len(capture.channels)
    held = None if texels is None else np.unique(np.asarray(texels, dtype=np.int64))
    if held is not None and len(held) and not (0 <= held[0] and held[-1] < height * width):
        raise ValueError(f"texels {held[0]}…{held[-1]} of a capture of {height * width}")
    every = slice(None) if held is None else held
    radiance = np.empty((len(capture.shots), height * width if held is None else len(held), n_channels), np.float32)
    centres = capture.texel_centres(held)
    for index, shot in enumerate(capture.shots):
        # a rectified photograph's rows that hold the texels (a .npy's read alone); a raw one whole
        rows = slice(None) if held is None or not len(held) or shot.matrix is not None else _rows(held, width)
        image, shape = read_rows(shot.file, capture.scale, rows)
        image = image[..., None] if image.ndim == 2 else image
        if image.shape[-1] != n_channels:
            hint = ' (a light\'s "intensity": [1.0] makes a capture of one channel)' if image.shape[-1] == 1 else ""
            raise BrdfInputError(
                f"{shot.file}: {_channels(image.shape[-1])}; the capture has {_channels(n_channels)}{hint}"
            )
        saturated = _saturation(capture, shot.file)
        if saturated is not None:  # before rectifying: a clipped pixel then spoils every texel it is mixed into
            image = np.where(np.any(image >= saturated, axis=-1, keepdims=True), np.nan, image)
        if shot.matrix is None:
            if shape[:2] != capture.shape:
                raise BrdfInputError(
                    f"{shot.file}: {shape[0]} × {shape[1]} pixels; the capture's plane has"
                    f" {height} × {width} texels (give the camera's matrix for an unrectified photograph)"
                )
            flat = image.reshape(-1, n_channels)[every if rows.start is None else held - rows.start * width]
        else:
            flat = rectified(image, shot.matrix, centres)
        radiance[index] = np.maximum(flat, 0.0)  # NaN stays NaN: np.maximum propagates it
    normals = read_normals(capture)
    return Photographs(capture, radiance, _mask(capture)[every], None if normals is None else normals[every], held)


def _rows(texels: np.ndarray, width: int) -> slice:
    """The rows of a grid ``width`` texels wide that hold ``texels`` (flat indices, ascending), first to last."""
    return slice(int(texels[0]) // width, int(texels[-1]) // width + 1)


def _channels(count: int) -> str:
    return f"{count} channel" + ("" if count == 1 else "s")


def _saturation(capture: Capture, file) -> float | None:
    """The value at or above which a pixel of ``file`` (as read, scaled) is saturated: the capture's
    ``saturation``, given in the file's own values (a 16-bit image's integers), else for a 16-bit image its largest
    value, 65,535 (a clipped pixel); None for a float image without one."""
    if not is_sixteen_bit(file):
        return capture.saturation
    stored = SIXTEEN_BITS if capture.saturation is None else capture.saturation
    return stored * capture.scale / SIXTEEN_BITS


def rectified(image: np.ndarray, matrix: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """The values (T, C) of a raw photograph ``image`` (rows, columns, C) at the texel ``centres`` (T, 3) mm that the
    3 × 4 projection ``matrix`` maps to its pixels (OpenCV: ``u`` along a row, ``v`` down the columns, pixel centres
    at whole numbers), bilinearly; NaN outside the photograph."""
    homogeneous = np.hstack([centres, np.ones((len(centres), 1))]) @ matrix.T
    u, v = homogeneous[:, 0] / homogeneous[:, 2], homogeneous[:, 1] / homogeneous[:, 2]
    rows, columns = image.shape[:2]
    inside = (homogeneous[:, 2] > 0) & (u >= 0) & (u <= columns - 1) & (v >= 0) & (v <= rows - 1)
    values = np.stack(
        [map_coordinates(image[..., c], [v, u], order=1, mode="nearest") for c in range(image.shape[-1])], axis=-1
    )
    values[~inside] = np.nan
    return values


def _mask(capture: Capture) -> np.ndarray:
    if capture.mask is None:
        return np.ones(capture.n_texels, dtype=bool)
    mask = read_mask(capture.mask)
    if mask.shape != capture.shape:
        raise BrdfInputError(
            f"{capture.mask}: {mask.shape[0]} × {mask.shape[1]} pixels; the capture has {capture.shape[0]} ×"
            f" {capture.shape[1]} texels"
        )
    return mask.ravel()


def read_normals(capture: Capture) -> np.ndarray | None:
    """The normal map of ``capture``, (H·W, 3) unit normals with z > 0, or None without one; a bad map is a one-line
    error naming it."""
    if capture.normal_map is None:
        return None
    if is_sixteen_bit(capture.normal_map):
        raise BrdfInputError(
            f"{capture.normal_map}: a normal map holds the normals themselves (x, y, z, z > 0): give it as .exr or"
            " .npy, not as an encoded 16-bit image"
        )
    normals = read_image(capture.normal_map)
    if normals.shape != (*capture.shape, 3):
        raise BrdfInputError(
            f"{capture.normal_map}: shape {normals.shape}; a normal map is {capture.shape[0]} × {capture.shape[1]} × 3"
        )
    normals = normals.reshape(-1, 3)
    length = np.linalg.norm(normals, axis=-1)
    bad = ~(np.isfinite(length) & (length > 0) & (normals[:, 2] > 0))
    if np.any(bad):
        row, column = divmod(int(np.argmax(bad)), capture.shape[1])
        raise BrdfInputError(f"{capture.normal_map}: texel ({row}, {column}): a normal must be finite with z > 0")
    return normals / length[:, None]


def texel_samples(photographs: Photographs, texels: np.ndarray, positive: bool = False) -> TexelSamples:
    """The samples of ``texels`` (flat indices) of ``photographs`` (module docstring); ``positive``: a sample with a
    channel at or below 0 dropped too (a relative residual divides by the value: a pixel clipped to 0 by noise below
    a camera's black level would outweigh every other sample)."""
    capture = photographs.capture
    lights = np.stack([shot.light_mm for shot in capture.shots])  # (K, 3)
    cameras = np.stack([shot.camera_mm for shot in capture.shots])
    intensity = np.stack([shot.intensity for shot in capture.shots])  # (K, C)
    at = photographs.positions(texels)
    normals = None if photographs.normals is None else photographs.normals[at]
    wi, wo, squared = point_light(capture.texel_centres(texels), lights, cameras, normals)
    radiance = np.asarray(photographs.radiance[:, at, :], dtype=float).transpose(1, 0, 2)  # (T, K, C)
    cos_i = wi[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        values = radiance * (squared / np.maximum(cos_i, MIN_COSINE))[..., None] / intensity[None, :, :]
    kept = (
        np.all(np.isfinite(values) & ((values > 0) if positive else True), axis=-1)
        & (cos_i >= MIN_COSINE)
        & (wo[..., 2] >= MIN_COSINE)
        & photographs.mask[at][:, None]
    )
    return TexelSamples(texels, wi, wo, np.where(kept[..., None], values, 0.0), kept)


def point_light(
    centres: np.ndarray, lights: np.ndarray, cameras: np.ndarray, normals: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The geometry of texels at ``centres`` (T, 3) mm lit by point lights at ``lights`` (K, 3) and seen from
    ``cameras`` (K, 3): ``wi`` and ``wo`` (T, K, 3), in each texel's frame where ``normals`` (T, 3) are given
    (module docstring), and the squared distance to each light (T, K), mm². One function for the capture's samples,
    its relighting (``relight.py``) and its synthesis (``data_synth/capture.py``)."""
    to_light = lights[None, :, :] - centres[:, None, :]
    squared = np.sum(to_light**2, axis=-1)
    wi = to_light / np.sqrt(squared)[..., None]
    to_camera = cameras[None, :, :] - centres[:, None, :]
    wo = to_camera / np.linalg.norm(to_camera, axis=-1, keepdims=True)
    if normals is not None:
        wi, wo = (_in_texel_frame(w, normals) for w in (wi, wo))
    return wi, wo, squared


def _in_texel_frame(w: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Directions ``w`` (T, K, 3) in the frames of texels with ``normals`` (T, 3): tangent the plane's x made
    perpendicular to the normal, bitangent ``n × t``, normal (module docstring)."""
    x = np.array([1.0, 0.0, 0.0])
    tangent = x - normals[:, 0:1] * normals
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    bitangent = np.cross(normals, tangent)
    frame = np.stack([tangent, bitangent, normals], axis=1)  # (T, 3, 3): rows t, b, n
    return np.einsum("tij,tkj->tki", frame, w)
