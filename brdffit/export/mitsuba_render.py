"""A sphere with a fit's Mitsuba 3 BSDF (``mitsuba.py``), rendered by Mitsuba itself: the renderer's own view.

The scene (Mitsuba 3's ``scalar_rgb`` variant, which runs on any CPU): a unit sphere seen by a perspective camera
4.5 units away (field of view 28°), lit by one directional light from the upper left front (brdffit's own
``point`` preset, ``views/render.py``), Mitsuba's ``direct`` integrator, ``spp`` samples per pixel (a delta light
leaves only the pixels' antialiasing to sample). The image is tone-mapped as brdffit's spheres are (``views/render.py``:
the 99th percentile of luminance to white, sRGB).
"""

import os
from pathlib import Path

import numpy as np

from .._files import atomic_path
from ..errors import BrdfInputError
from ..fitting.single.result import FitResult
from .mitsuba import MitsubaExport, mitsuba_bsdf

#: What to install for :func:`render_sphere`.
EXTRA = "pip install 'brdffit[render]' (Mitsuba 3)"


def mitsuba():
    """Mitsuba 3 with its ``scalar_rgb`` variant set, or a one-line error saying how to install it."""
    try:
        import mitsuba as mi
    except ImportError:
        raise BrdfInputError(f"rendering with Mitsuba needs Mitsuba 3, which is not installed: {EXTRA}") from None
    mi.set_variant("scalar_rgb")
    return mi


def render_sphere(result: FitResult, path: str | os.PathLike, *, size: int = 256, spp: int = 64) -> MitsubaExport:
    """Render a sphere of ``result``'s Mitsuba BSDF with Mitsuba and write it to ``path`` (PNG, atomically);
    returns the export (exact or how far it lies)."""
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
    write_png(np.asarray(mi.render(scene), dtype=float), path)
    return exported


def write_png(linear_rgb: np.ndarray, path: str | os.PathLike) -> Path:
    """A linear RGB image (H, W, 3), tone-mapped as brdffit's spheres are, as a PNG (atomically)."""
    import matplotlib.image

    from ..views.render import exposure_for, to_srgb

    path = Path(path)
    with atomic_path(path) as temporary:
        matplotlib.image.imsave(temporary, to_srgb(linear_rgb, exposure_for(linear_rgb)), format="png")
    return path
