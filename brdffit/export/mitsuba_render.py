"""A sphere with a fit's Mitsuba 3 BSDF (``mitsuba.py``), rendered by Mitsuba itself: the renderer's own view.

The scene (Mitsuba 3's ``scalar_rgb`` variant, which runs on any CPU): a unit sphere seen by a perspective camera
4.5 units away (field of view 28°), lit by one directional light from the upper left front (brdffit's own
``point`` preset, ``views/render.py``), Mitsuba's ``direct`` integrator, ``spp`` samples per pixel (a delta light
leaves only the pixels' antialiasing to sample).

Every image is exposed alike (:data:`EXPOSURE`, unless asked otherwise), so that two renders compare: an export that
reflects 0.4 times the light of another renders 0.4 times as bright, where exposing each image on its own (its 99th
percentile of luminance to white, ``exposure="auto"``, as brdffit's figures do) would show both alike. A PNG is the
exposed image, clipped and sRGB-encoded (``views/render.py``); an OpenEXR file (``.exr``) is the linear radiance
itself, unexposed, for a user's own tone mapping.
"""

import os
from pathlib import Path

import numpy as np

from .._files import atomic_path
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from .mitsuba import MitsubaExport, mitsuba_bsdf
from .mitsuba_eval import mitsuba

#: The exposure every image gets by default: π, so that a white Lambertian surface facing the light (radiance 1/π
#: under the scene's unit irradiance) is display white; a darker or brighter material looks darker or brighter.
EXPOSURE = float(np.pi)
#: The image formats :func:`render_sphere` writes, by suffix.
IMAGE_SUFFIXES = (".png", ".exr")


def render_sphere(
    result: FitResult,
    path: str | os.PathLike,
    *,
    size: int = 256,
    spp: int = 64,
    exposure: float | str = EXPOSURE,
) -> MitsubaExport:
    """Render a sphere of ``result``'s Mitsuba BSDF with Mitsuba and write it to ``path`` (PNG, or OpenEXR for
    ``.exr``; atomically); returns the export (exact or how far it lies). ``exposure``: the factor radiance is
    multiplied by before display (:data:`EXPOSURE` by default, the same for every image), or ``"auto"``: this
    image's own (its 99th percentile of luminance to white). An OpenEXR file holds the radiance, unexposed."""
    exposure = checked_exposure(exposure)
    if Path(path).suffix.lower() not in IMAGE_SUFFIXES:
        raise BrdfInputError(
            Argument.given("path", str(path)), f": the image must end in {' or '.join(IMAGE_SUFFIXES)}"
        )
    mi = mitsuba()
    exported = mitsuba_bsdf(result)
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct"},
            "sensor": {
                "type": "perspective",
                "fov": 28.0,
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {"type": "hdrfilm", "width": size, "height": size},
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "sphere": {"type": "sphere", "bsdf": exported.bsdf},
            "key": {
                "type": "directional",
                "direction": [1.0, -1.0, -1.0],
                "irradiance": {"type": "rgb", "value": [1.0] * 3},
            },
        }
    )
    radiance = np.asarray(mi.render(scene), dtype=float)
    if Path(path).suffix.lower() == ".exr":
        write_exr(mi, radiance, path)
    else:
        write_png(radiance, path, exposure)
    return exported


def write_png(linear_rgb: np.ndarray, path: str | os.PathLike, exposure: float | str = EXPOSURE) -> Path:
    """A linear RGB image (H, W, 3) times ``exposure`` (or its own, ``"auto"``), clipped and sRGB-encoded as
    brdffit's spheres are, as a PNG (atomically)."""
    import matplotlib.image

    from ..views.render import exposure_for, to_srgb

    path = Path(path)
    factor = exposure_for(linear_rgb) if exposure == "auto" else float(exposure)
    with atomic_path(path) as temporary:
        matplotlib.image.imsave(temporary, to_srgb(linear_rgb, factor), format="png")
    return path


def write_exr(mi, linear_rgb: np.ndarray, path: str | os.PathLike) -> Path:
    """A linear RGB image (H, W, 3) as OpenEXR (32-bit float, Mitsuba's writer), atomically."""
    path = Path(path)
    with atomic_path(path) as temporary:
        mi.Bitmap(np.ascontiguousarray(linear_rgb, dtype=np.float32)).write(str(temporary))
    return path


def checked_exposure(value) -> float | str:
    """``--exposure``/``exposure=``: a number > 0, or ``"auto"``; a one-line error otherwise."""
    if value == "auto":
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if isinstance(value, bool) or not (number > 0 and np.isfinite(number)):
        raise BrdfInputError(Argument.given("exposure", value), " must be a number > 0, or 'auto' (each image its own)")
    return number
