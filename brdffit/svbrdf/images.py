"""The images of a capture and of its maps, read and written: OpenEXR, 16-bit PNG and TIFF, NumPy ``.npy``.

Read (:func:`read_image`): an image is an (H, W) or (H, W, C) array of linear values as float64.

* ``.exr`` (OpenEXR, any pixel type): its ``RGB``/``RGBA`` (or ``R``, ``G``, ``B``) channels, or its single channel
  (``Y``, or any one);
* ``.npy``: the array as it is (float or integer);
* ``.png``, ``.tif``, ``.tiff``: 16-bit greyscale or RGB (an alpha channel is left out), whose 65,535 stands for the
  capture's ``scale`` (default 1); read by pypng and tifffile (the ``svbrdf`` extra); an 8-bit image is refused,
  being sRGB-encoded and too coarse for a fit.

Written (atomically): :func:`write_exr` (float32, lossless ZIP compression, linear) and :func:`write_png` (8-bit,
a preview).
"""

import io
import os
from pathlib import Path

import numpy as np

from .._files import atomic_path, reading
from ..errors import BrdfInputError, needs

#: The suffixes :func:`read_image` reads.
IMAGE_SUFFIXES = (".exr", ".npy", ".png", ".tif", ".tiff")
#: What a 16-bit image's largest value stands for, before the capture's ``scale``.
SIXTEEN_BITS = 65535.0


def is_sixteen_bit(path: str | os.PathLike) -> bool:
    """Whether ``path`` is read as a 16-bit image (PNG or TIFF), whose values the capture's ``scale`` scales."""
    return Path(path).suffix.lower() in (".png", ".tif", ".tiff")


def read_mask(path: str | os.PathLike) -> np.ndarray:
    """A mask image as (H, W) booleans, true where any channel is nonzero (NaN counts as 0): any format
    :func:`read_image` reads, and PNG or TIFF of any depth (an 8-bit mask is exact)."""
    path = Path(path)
    if is_sixteen_bit(path):
        from PIL import Image, UnidentifiedImageError

        with reading(path, "an image"):
            try:
                with Image.open(path) as image:
                    mask = np.asarray(image)
            except UnidentifiedImageError:
                raise BrdfInputError(f"{path}: not an image") from None
    else:
        mask = read_image(path)
    mask = np.nan_to_num(np.asarray(mask, dtype=float))
    return mask != 0 if mask.ndim == 2 else np.any(mask != 0, axis=-1)


def read_image(path: str | os.PathLike, scale: float = 1.0) -> np.ndarray:
    """The image at ``path`` as float64, (H, W) or (H, W, C) (module docstring); ``scale``: the value of a 16-bit
    image's 65,535."""
    return read_rows(path, scale)[0]


def read_rows(
    path: str | os.PathLike, scale: float = 1.0, rows: slice = slice(None)
) -> tuple[np.ndarray, tuple[int, ...]]:
    """The ``rows`` of the image at ``path`` as float64 (:func:`read_image`), and the whole image's shape: a
    ``.npy``'s rows read alone (memory-mapped: a Dask worker reads its band of a capture), any other format's
    decoded whole first."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in IMAGE_SUFFIXES:
        raise BrdfInputError(f"{path}: not an image brdffit reads; use {', '.join(IMAGE_SUFFIXES)}")
    with reading(path, "an image"):
        if suffix == ".npy":
            image = _npy(path)
        elif suffix == ".exr":
            image = _exr(path)
        else:
            image = _sixteen_bit(path) * (scale / SIXTEEN_BITS)
        if image.ndim not in (2, 3) or image.size == 0:
            raise BrdfInputError(f"{path}: an image of shape {image.shape}; expected (rows, columns[, channels])")
        taken = image[rows]
        # a memory-mapped file's rows are read into an array of their own now: none stays tied to the open file
        taken = np.array(taken, dtype=float) if isinstance(image, np.memmap) else np.asarray(taken, dtype=float)
        return taken, image.shape


def _npy(path: Path) -> np.ndarray:
    """A ``.npy`` file's array, memory-mapped (its values read when indexed)."""
    try:
        array = np.load(path, mmap_mode="r", allow_pickle=False)
    except ValueError as error:
        raise BrdfInputError(f"{path}: not a NumPy array file ({error})") from None
    if not (np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)):
        raise BrdfInputError(f"{path}: values of type {array.dtype}; expected numbers")
    return array


def _exr(path: Path) -> np.ndarray:
    import OpenEXR as openexr

    try:
        with openexr.File(str(path)) as file:
            channels = {name: channel.pixels for name, channel in file.channels().items()}
    except Exception as error:  # OpenEXR raises RuntimeError, or its own, for any file it cannot read
        raise BrdfInputError(f"{path}: not an OpenEXR image ({str(error).splitlines()[0]})") from None
    for name in ("RGB", "RGBA"):
        if name in channels:
            return np.asarray(channels[name][..., :3], dtype=float)
    if {"R", "G", "B"} <= channels.keys():
        return np.stack([np.asarray(channels[name], dtype=float) for name in "RGB"], axis=-1)
    if len(channels) == 1 or "Y" in channels:
        return np.asarray(channels.get("Y", next(iter(channels.values()))), dtype=float)
    raise BrdfInputError(f"{path}: channels {', '.join(sorted(channels))}; expected RGB, R, G and B, or one (Y)")


def _sixteen_bit(path: Path) -> np.ndarray:
    """A 16-bit PNG (read by pypng: Pillow reads a 16-bit RGB PNG as 8-bit) or TIFF (read by tifffile), greyscale or
    RGB, as an array of its integer values (as float); any other depth is refused."""
    if path.suffix.lower() == ".png":
        png = needs("png", "svbrdf", "16-bit PNG images")
        try:
            with open(path, "rb") as stream:
                width, height, rows, info = png.Reader(file=stream).asDirect()
                image = np.vstack([np.asarray(row, dtype=float) for row in rows]).reshape(height, width, info["planes"])
        except png.Error as error:
            raise BrdfInputError(f"{path}: not a PNG image ({error})") from None
        depth, image = info["bitdepth"], image[..., : 3 if info["planes"] >= 3 else 1]
    else:
        tifffile = needs("tifffile", "svbrdf", "TIFF images")
        try:
            array = tifffile.imread(path)
        except (ValueError, tifffile.TiffFileError) as error:
            raise BrdfInputError(f"{path}: not a TIFF image ({error})") from None
        depth = array.dtype.itemsize * 8 if array.dtype.kind == "u" else array.dtype.name
        image = np.asarray(array, dtype=float)
        image = image[..., :3] if image.ndim == 3 and image.shape[-1] >= 3 else image
    if depth != 16:
        raise BrdfInputError(
            f"{path}: an image of {depth} bits; a capture's PNG and TIFF images must be 16-bit integers (linear"
            " values), or use .exr or .npy"
            if isinstance(depth, int)
            else f"{path}: an image of {depth} values; a capture's TIFF images must be 16-bit integers, or use .exr or"
            " .npy"
        )
    return image[..., 0] if image.ndim == 3 and image.shape[-1] == 1 else image


def write_exr(path: str | os.PathLike, image: np.ndarray, channels: tuple[str, ...] | None = None) -> None:
    """``image`` as a float32 OpenEXR file (lossless ZIP), atomically: (H, W) or (H, W, 1) as its one channel ``Y``,
    (H, W, 3) as ``RGB``, (H, W, C) otherwise as C channels named ``channels``."""
    import OpenEXR as openexr

    pixels = np.ascontiguousarray(image, dtype=np.float32)
    if pixels.ndim == 3 and pixels.shape[-1] == 1:
        pixels = pixels[..., 0]
    if pixels.ndim == 2:
        layers = {"Y": pixels}
    elif pixels.shape[-1] == 3:
        layers = {"RGB": pixels}
    else:
        names = channels or tuple(f"c{index}" for index in range(pixels.shape[-1]))
        layers = {str(name): np.ascontiguousarray(pixels[..., index]) for index, name in enumerate(names)}
    header = {"compression": openexr.ZIP_COMPRESSION, "type": openexr.scanlineimage}
    with atomic_path(path) as temporary, openexr.File(header, layers) as file:
        file.write(str(temporary))


def write_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """``image`` as an 8-bit PNG (:func:`png_bytes`), atomically."""
    data = png_bytes(image)
    with atomic_path(path) as temporary:
        temporary.write_bytes(data)


def png_bytes(image: np.ndarray) -> bytes:
    """``image`` ((H, W), (H, W, 1), (H, W, 3) or (H, W, 4): RGBA, values in [0, 1], clipped; NaN as 0) as an 8-bit
    PNG's bytes."""
    from PIL import Image

    image = image[..., 0] if image.ndim == 3 and image.shape[-1] == 1 else image
    pixels = np.round(np.clip(np.nan_to_num(image, nan=0.0), 0.0, 1.0) * 255.0).astype(np.uint8)
    stream = io.BytesIO()
    Image.fromarray(pixels).save(stream, format="PNG")
    return stream.getvalue()


def srgb_encoded(linear: np.ndarray) -> np.ndarray:
    """Linear values in [0, 1] encoded as sRGB (IEC 61966-2-1): ``12.92 v`` up to 0.0031308, ``1.055 v^(1/2.4) −
    0.055`` above; clipped to [0, 1] first."""
    v = np.clip(linear, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)


def srgb_decoded(encoded: np.ndarray) -> np.ndarray:
    """The inverse of :func:`srgb_encoded` (IEC 61966-2-1): ``v / 12.92`` up to 0.04045, ``((v + 0.055) /
    1.055)^2.4`` above."""
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)
