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

Given the data (``samples``), the PNG shows three spheres side by side at the one exposure: Mitsuba's render of the
export, brdffit's render of the fit (``views/render.py``: the same light, an orthographic camera) and the data's own
sphere (each pixel's nearest sample; lit pixels no sample is near are striped grey): an export that renders too dark
or a highlight the fit misses shows at once.

A Mitsuba BSDF file (``brdffit export --to mitsuba``'s XML, :func:`render_bsdf_file`) renders in the same scene as it
is, loaded by Mitsuba: an export is made once and rendered as often as wanted, with nothing fitted again.
"""

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._files import atomic_path
from ..errors import Argument, BrdfInputError, needs
from ..fitting.single.result import FitResult
from .at_data import data_for
from .mitsuba import MitsubaExport, mitsuba_bsdf
from .mitsuba_eval import mitsuba

if TYPE_CHECKING:
    from ..data.samples import Samples

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
    samples: "Samples | str | os.PathLike | None" = None,
) -> MitsubaExport:
    """Render a sphere of ``result``'s Mitsuba BSDF with Mitsuba and write it to ``path`` (PNG, or OpenEXR for
    ``.exr``; atomically); returns the export (exact or how far it lies). ``exposure``: the factor radiance is
    multiplied by before display (:data:`EXPOSURE` by default, the same for every image), or ``"auto"``: this
    image's own (its 99th percentile of luminance to white). An OpenEXR file holds the radiance, unexposed.
    ``samples``: the data the fit was made from (read as the fit read them): the PNG then shows the render beside the
    fit's sphere and the data's (module docstring), and the export says how far it lies from them
    (:attr:`MitsubaExport.at_data`)."""
    exposure = checked_exposure(exposure)
    check_image_path(path)
    if samples is not None and Path(path).suffix.lower() != ".png":
        raise BrdfInputError(
            Argument.given("path", str(path)), ": the render beside the data is a .png (an .exr holds one image)"
        )
    mi = mitsuba()
    data = None if samples is None else data_for(result, samples, subset=False)  # before the work: a bad file fails
    exported = mitsuba_bsdf(result)
    if data is not None:
        exported = exported.compared_with(result, data)
    radiance = rendered_radiance(mi, exported.bsdf, size, spp)
    if Path(path).suffix.lower() == ".exr":
        write_exr(mi, radiance, path)
    elif data is None:
        write_png(radiance, path, exposure)
    else:
        write_beside_the_data(radiance, result, data, path, exposure)
    return exported


#: The suffix of a Mitsuba BSDF file :func:`render_bsdf_file` renders (``brdffit export --to mitsuba``'s XML).
XML_SUFFIX = ".xml"


def check_image_path(path: str | os.PathLike) -> None:
    """A one-line error, before any work, for an image whose suffix names no format written (:data:`IMAGE_SUFFIXES`)
    or a PNG where matplotlib, which draws and writes it, is not installed."""
    if Path(path).suffix.lower() not in IMAGE_SUFFIXES:
        raise BrdfInputError(
            Argument.given("path", str(path)), f": the image must end in {' or '.join(IMAGE_SUFFIXES)}"
        )
    if Path(path).suffix.lower() == ".png":
        needs("matplotlib", "render", "PNG images")


def render_bsdf_file(
    bsdf_file: str | os.PathLike,
    path: str | os.PathLike,
    *,
    size: int = 256,
    spp: int = 64,
    exposure: float | str = EXPOSURE,
) -> list[str]:
    """Render the BSDF of a Mitsuba 3 XML file (``brdffit export --to mitsuba``'s, or one's own) as
    :func:`render_sphere` renders a fit's: the same scene, loaded by Mitsuba from the file as it is, so nothing is
    fitted again (an export's render is the render of its file, pixel for pixel); written to ``path`` (PNG, or
    OpenEXR for ``.exr``; atomically). Returns the lines of the file's leading comments (brdffit's export writes
    what it made and how far it lies there). One-line errors for a file Mitsuba cannot load or that is not a BSDF."""
    exposure = checked_exposure(exposure)
    check_image_path(path)
    mi = mitsuba()
    try:
        text = Path(bsdf_file).read_text(encoding="utf-8")
        loaded = mi.load_string(text)
    except (OSError, UnicodeDecodeError, RuntimeError) as error:
        why = str(error).strip().splitlines()[-1] if str(error).strip() else type(error).__name__
        raise BrdfInputError(f"{bsdf_file}: not a file Mitsuba 3 loads ({why})") from None
    if not isinstance(loaded, mi.BSDF):
        raise BrdfInputError(f"{bsdf_file}: holds a Mitsuba {type(loaded).__name__}, not a BSDF; give one BSDF")
    radiance = rendered_radiance(mi, loaded, size, spp)
    if Path(path).suffix.lower() == ".exr":
        write_exr(mi, radiance, path)
    else:
        write_png(radiance, path, exposure)
    return leading_comments(text)


def leading_comments(xml: str) -> list[str]:
    """The text of the ``<!-- … -->`` comments before an XML document's first element, one line each."""
    lines = []
    rest = xml.lstrip()
    while rest.startswith("<?"):
        rest = rest[rest.find("?>") + 2 :].lstrip() if "?>" in rest else ""
    while rest.startswith("<!--") and "-->" in rest:
        end = rest.index("-->")
        lines.append(" ".join(rest[4:end].split()))
        rest = rest[end + 3 :].lstrip()
    return lines


def rendered_radiance(mi, bsdf, size: int, spp: int) -> np.ndarray:
    """The radiance (size, size, 3) of the module docstring's scene, a sphere with ``bsdf`` (the dictionary
    ``mitsuba.load_dict`` takes, or a loaded BSDF), rendered by Mitsuba with ``spp`` samples per pixel (its
    ``independent`` sampler's default seed: the same BSDF renders the same image)."""
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
            "sphere": {"type": "sphere", "bsdf": bsdf},
            "key": {
                "type": "directional",
                "direction": [1.0, -1.0, -1.0],
                "irradiance": {"type": "rgb", "value": [1.0] * 3},
            },
        }
    )
    return np.asarray(mi.render(scene), dtype=float)


def write_beside_the_data(
    radiance: np.ndarray, result: FitResult, samples: "Samples", path: str | os.PathLike, exposure: float | str
) -> Path:
    """Mitsuba's ``radiance`` (H, W, 3) beside brdffit's sphere of ``result`` and the sphere of the data ``samples``
    (``views/render.py``; one or three channels, as the export), all times one ``exposure`` (``"auto"``: that of
    Mitsuba's image), as one PNG (atomically)."""
    from matplotlib.figure import Figure

    from ..views.figures import label, save_figure
    from ..views.render import display_rgb, exposure_for, render_measured, sphere_normals, to_srgb
    from ..views.render import render_sphere as render_fit
    from ..views.sphere import disc_image, measured_image

    size = radiance.shape[0]
    factor = exposure_for(radiance) if exposure == "auto" else float(exposure)
    fit_rgb, _ = display_rgb(
        render_fit(result.model, result.params, size=size, channels=result.channels, **result.model_options),
        result.channels,
    )
    found = render_measured(samples, size=size)
    data_rgb, _ = display_rgb(found.radiance, samples.channels)
    inside, _ = sphere_normals(size)
    panels = [
        ("Mitsuba's render of the export", to_srgb(radiance, factor)),
        ("brdffit's sphere of the fit", disc_image(fit_rgb, factor, inside)),
        (f"the data ({found.data_fraction:.0%} of the lit disc)", measured_image(found, data_rgb, factor)),
    ]
    figure = Figure(figsize=(3 * 2.6 + 0.2, 2.6 + 0.6), layout="constrained")
    for axis, (title, image) in zip(figure.subplots(1, 3), panels, strict=True):
        axis.imshow(image, interpolation="nearest")
        axis.set_title(title, fontsize=9)
        axis.set_axis_off()
    exposed = "each at its own exposure" if exposure == "auto" else f"all at exposure {factor:.3g}"
    figure.suptitle(f"{label(result)}: one light from the upper left, {exposed}", fontsize=8)
    return save_figure(figure, path)


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
