"""A sphere lit by a few directional lights, rendered with a model or with measured values: pure computation.

The scene (as in Ngan, Durand and Matusik, "Experimental analysis of BRDF models", EGSR 2005, whose figures
show each fit beside the measured material on a lit sphere):

* **camera**: orthographic, looking down ``-z`` at a unit sphere centred at the origin. Image and world share
  one frame: ``x`` to the right, ``y`` up, ``z`` towards the viewer, so the view direction is ``v = (0, 0, 1)``
  everywhere. Pixel ``(row, column)`` of a ``size × size`` image has its centre at
  ``x = (2·column + 1)/size − 1``, ``y = 1 − (2·row + 1)/size``; it sees the sphere where ``x² + y² < 1``, at
  the normal ``n = (x, y, sqrt(1 − x² − y²))``.
* **shading frame** (:func:`shading_frame`): ``z = n``; the tangent ``x`` points along the parallels of a
  sphere whose poles lie on the world ``y`` axis (east, the direction of increasing longitude about ``y``):
  ``t = normalize(ŷ × n) = (n_z, 0, −n_x) / sqrt(n_x² + n_z²)``, and ``y = n × t``. An anisotropic model's
  highlight (``ward-aniso``: ``alpha_x`` along ``t``) thus stretches along the parallels when
  ``alpha_x > alpha_y`` and along the meridians when ``alpha_x < alpha_y``, as on a sphere brushed about its
  vertical axis. The poles ``n = ±ŷ`` lie on the silhouette, which no pixel centre reaches, so the frame is
  smooth over the whole disc (no seam); at the poles themselves the tangent is taken as ``x̂``.
* **lights** (:class:`Light`): directional, each a unit direction towards the light (world frame) and an
  irradiance ``E`` (linear sRGB components) on a surface facing it. Presets in :data:`LIGHTS`.
* **rendering equation** for directional lights (Kajiya 1986, the integral reduced to a sum over delta lights;
  Pharr, Jakob and Humphreys, *Physically Based Rendering*, 4th ed., §12.1)::

      L_o(n, v)[c] = Σ_lights f(wi, wo)[c] · E[c] · max(cos θi, 0)

  with ``wi``, ``wo`` the light and view directions in the pixel's shading frame; a light below the local
  horizon contributes nothing. ``L_o`` is radiance in the units of ``E`` per steradian.

:func:`render_sphere` evaluates a model's JAX BRDF (:meth:`brdffit.physics.models.Model.brdf`), compiled and
vectorised over pixels and lights. :func:`render_measured` looks every pixel's directions up in measured
samples instead: the sample nearest in Rusinkiewicz's half/difference angles (EGWR 1998), within
:data:`MAX_DISTANCE_DEGREES`, as MERL's table lookup takes the bin a direction pair falls in. :func:`to_srgb`
and :func:`exposure_for` turn radiance into an image.
"""

import numbers
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import jax.numpy as jnp
import numpy as np

from .._jax import namespace
from .._programs import jit
from ..checks import choice, whole_number
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..physics.geometry import to_half_difference
from ..physics.models.model import Model
from ..physics.models.params import Params
from ..physics.models.registry import model_for

#: The view direction in world (= camera) coordinates: towards the viewer.
VIEW = (0.0, 0.0, 1.0)
#: Luminance of linear sRGB (IEC 61966-2-1: the Rec. 709 primaries' Y row).
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
#: The default for a measured lookup: a direction pair with no sample this close (degrees, in the metric of
#: :func:`rusinkiewicz_embedding`) has no data. MERL's bins (θh bins up to 2° wide, θd and φd bins 1°, each at
#: its lower edge as ``BRDFRead.cpp`` looks it up) lie within 1.44° of every lookup of a 256² sphere under either
#: preset (measured), so a full table covers the whole lit disc; a 10k-sample gonioreflectometer set about half.
MAX_DISTANCE_DEGREES = 2.0
#: The luminance percentile, over the lit pixels, that :func:`exposure_for` maps to display white.
EXPOSURE_PERCENTILE = 99.0
#: Largest image side :func:`render_sphere` and :func:`render_measured` accept (pixels).
MAX_SIZE = 4096


@dataclass(frozen=True)
class Light:
    """A directional light: ``direction`` a unit vector towards the light in world coordinates (``x`` right,
    ``y`` up, ``z`` towards the viewer; normalised here), ``irradiance`` ``E`` on a surface facing it as
    three linear sRGB components (relative units: radiance comes out in these units per steradian)."""

    name: str
    direction: tuple[float, float, float]
    irradiance: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self):
        direction = np.asarray(self.direction, dtype=float)
        irradiance = np.asarray(self.irradiance, dtype=float)
        length = np.linalg.norm(direction) if direction.shape == (3,) else np.nan
        if not np.isfinite(length) or length == 0:
            raise BrdfInputError(Argument.given("direction", self.direction), " must be a non-zero 3-vector")
        if irradiance.shape != (3,) or not np.all(np.isfinite(irradiance)) or np.any(irradiance < 0):
            raise BrdfInputError(
                Argument.given("irradiance", self.irradiance), " must be three finite, non-negative numbers (r, g, b)"
            )
        object.__setattr__(self, "direction", tuple(float(c) for c in direction / length))
        object.__setattr__(self, "irradiance", tuple(float(c) for c in irradiance))


def _towards(x: float, y: float, z: float) -> tuple[float, float, float]:
    unit = np.array([x, y, z]) / np.linalg.norm([x, y, z])
    return float(unit[0]), float(unit[1]), float(unit[2])


#: Light presets by name. ``point``: one white light from the upper left, in front (54.7° from the view
#: direction), so the highlight of a glossy sphere sits up and left of centre. ``environment``: a studio's few
#: lights: the same key, a dimmer fill from the lower right, a rim light from behind on the upper right (it
#: lights the silhouette: grazing, Fresnel-like behaviour) and a faint headlight at the camera (light and view
#: coincide at every pixel: a retro-reflector's peak, brightest at the disc's centre).
LIGHTS: dict[str, tuple[Light, ...]] = {
    "point": (Light("key", _towards(-1.0, 1.0, 1.0)),),
    "environment": (
        Light("key", _towards(-1.0, 1.0, 1.0), (1.0, 1.0, 1.0)),
        Light("fill", _towards(1.0, -0.4, 0.9), (0.3, 0.3, 0.3)),
        Light("rim", _towards(0.8, 0.6, -0.7), (0.8, 0.8, 0.8)),
        Light("headlight", VIEW, (0.15, 0.15, 0.15)),
    ),
}


@dataclass(frozen=True)
class MeasuredSphere:
    """The sphere rendered from measured samples (:func:`render_measured`).

    ``radiance``: (size, size, C) as :func:`render_sphere` gives it, 0 outside the disc and where there is no
    data. ``lit``: (size, size) pixels of the disc that some light reaches (above the local horizon).
    ``has_data``: lit pixels for which every light that reaches them found a sample within ``max_distance``
    (degrees). ``data_fraction``: ``has_data`` over ``lit``, the share of the lit disc the samples cover: near 1
    for a dense table (MERL), small for a sparse gonioreflectometer set.
    """

    radiance: np.ndarray
    lit: np.ndarray
    has_data: np.ndarray
    data_fraction: float
    max_distance: float


# ---------------------------------------------------------------------- geometry
def sphere_normals(size: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """The disc of a ``size × size`` image: ``inside`` (size, size) bool, and ``normals`` (P, 3) of the P pixels
    inside it in row-major order (world frame; see the module docstring for the pixel centres)."""
    size = whole_number("size", size, minimum=2, maximum=MAX_SIZE)
    centres = (2.0 * np.arange(size) + 1.0) / size - 1.0
    x, y = np.meshgrid(centres, -centres)  # row 0 at the top: y decreases down the rows
    radius2 = x * x + y * y
    inside = radius2 < 1.0
    normals = np.stack([x[inside], y[inside], np.sqrt(1.0 - radius2[inside])], axis=-1)
    return inside, normals


def shading_frame(normals):
    """The shading frame of each normal (…, 3): rows ``(t, b, n)`` (…, 3, 3) in world coordinates.

    ``t = normalize(ŷ × n)``, east along the parallels about the world ``y`` axis (``x̂`` at the poles
    ``n = ±ŷ``), ``b = n × t``. A world vector ``w`` has local coordinates ``frame @ w``. numpy or JAX.
    """
    xp = namespace(normals)
    nx, nz = normals[..., 0], normals[..., 2]
    length = xp.sqrt(nx * nx + nz * nz)
    at_pole = length == 0.0
    safe = xp.where(at_pole, 1.0, length)
    zero = xp.zeros_like(nx)
    tangent = xp.stack([xp.where(at_pole, 1.0, nz / safe), zero, xp.where(at_pole, 0.0, -nx / safe)], axis=-1)
    bitangent = xp.cross(normals, tangent)
    return xp.stack([tangent, bitangent, normals], axis=-2)


def _local_directions(normals: np.ndarray, lights: Sequence[Light]) -> tuple[np.ndarray, np.ndarray]:
    """``wi`` (L, P, 3) of every light and ``wo`` (P, 3) in each pixel's shading frame (numpy)."""
    frame = shading_frame(normals)
    directions = np.array([light.direction for light in lights])
    wi = np.einsum("pij,lj->lpi", frame, directions)
    return wi, frame @ np.asarray(VIEW)


def rusinkiewicz_embedding(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Points (N, 4) for nearest-neighbour lookups of isotropic, reciprocal BRDF values at pairs ``wi``, ``wo`` (N, 3).

    Rusinkiewicz's (EGWR 1998) half/difference angles: ``h = normalize(wi + wo)``, ``θh`` its zenith, ``φh`` its
    azimuth; ``d = R_y(−θh) R_z(−φh) wi`` with zenith ``θd`` and azimuth ``φd``. Isotropy drops ``φh``;
    reciprocity (``φd → φd + π`` swaps ``wi`` and ``wo``) makes ``φd`` a coordinate modulo π, as MERL's table
    folds it (Matusik et al. 2003). The point is ``(θh, θd, ½ sin θd cos 2φd, ½ sin θd sin 2φd)`` (radians):
    periodic in ``φd`` with period π, and its Euclidean distance is locally the angular one,
    ``dθh² + dθd² + sin²θd dφd²`` (the θd term stretched by at most ``sqrt(1 + ¼cos²θd) ≤ 1.12``). No fold
    ``φd → −φd`` (bilateral symmetry) is assumed: MERL's lookup does not assume it either.
    """
    theta_h, _, theta_d, phi_d = to_half_difference(np.asarray(wi, dtype=float), np.asarray(wo, dtype=float))
    twice_phi_d = 2.0 * phi_d
    radius = 0.5 * np.sin(theta_d)
    return np.stack([theta_h, theta_d, radius * np.cos(twice_phi_d), radius * np.sin(twice_phi_d)], axis=-1)


# ---------------------------------------------------------------------- lights and channels
def resolve_lights(lights: "str | Sequence[Light]") -> tuple[Light, ...]:
    """A preset's lights (a key of :data:`LIGHTS`) or the given :class:`Light` sequence, checked."""
    if isinstance(lights, str):
        return LIGHTS[choice("lights", lights, LIGHTS)]
    given: tuple[Light, ...] = tuple(lights) if isinstance(lights, Sequence) and not isinstance(lights, str) else ()
    if not given or not all(isinstance(light, Light) for light in given):
        raise BrdfInputError(
            Argument("lights"), f" must be one of: {', '.join(LIGHTS)}, or a non-empty sequence of Light"
        )
    return given


def channel_irradiance(lights: Sequence[Light], channels: Sequence[str] | None, n_channels: int) -> np.ndarray:
    """Each light's irradiance (L, C) in the model's channels.

    Three channels named ``x, y, z`` are CIE XYZ: the lights' linear sRGB is converted with the inverse of the
    matrix :func:`display_rgb` converts back with (so a white light on a flat albedo shows grey). Any other three
    channels are taken as r, g, b. Other counts (one channel, spectral bands) get the light's luminance in every
    channel: the lights as grey.
    """
    rgb = np.array([light.irradiance for light in lights], dtype=float)
    if n_channels == 3 and tuple(channels or ()) == ("x", "y", "z"):
        return rgb @ _srgb_matrix("rgb_to_xyz").T
    if n_channels == 3:
        return rgb
    return np.repeat((rgb @ LUMINANCE_WEIGHTS)[:, None], n_channels, axis=1)


def display_rgb(radiance: np.ndarray, channels: Sequence[str] | None) -> tuple[np.ndarray, str]:
    """Radiance (…, C) as linear sRGB (…, 3), and how the channels were shown ("" when as they are).

    One channel: grey (nothing to say). Three: r, g, b as they are, except channels ``x, y, z`` (CIE XYZ),
    converted with IEC 61966-2-1's XYZ → sRGB matrix (colour-science's
    ``RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB``, as ``brdffit/data/spectral.py`` uses it). Other counts: the mean
    over channels, as grey.
    """
    radiance = np.asarray(radiance, dtype=float)
    n_channels = radiance.shape[-1]
    if n_channels == 3 and tuple(channels or ()) == ("x", "y", "z"):
        return radiance @ _srgb_matrix("xyz_to_rgb").T, "CIE XYZ shown as sRGB"
    if n_channels == 3:
        return radiance, ""
    grey = radiance.mean(axis=-1, keepdims=True)
    note = "" if n_channels == 1 else f"grey: mean of {n_channels} channels"
    return np.repeat(grey, 3, axis=-1), note


def _srgb_matrix(direction: str) -> np.ndarray:
    import colour  # ~1 s to import: only for XYZ channels

    xyz_to_rgb = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB, dtype=float)
    # colour-science's own matrix_RGB_to_XYZ (from the primaries) differs from this one's inverse by ~2e-5
    return np.linalg.inv(xyz_to_rgb) if direction == "rgb_to_xyz" else xyz_to_rgb


# ---------------------------------------------------------------------- rendering
def render_sphere(
    model: "str | Model",
    params: dict[str, Any],
    *,
    size: int = 256,
    lights: "str | Sequence[Light]" = "point",
    channels: Sequence[str] | None = None,
    **model_options: Any,
) -> np.ndarray:
    """Radiance (size, size, C) of a unit sphere of ``model`` with ``params`` (the result file's dictionary).

    ``lights``: a preset of :data:`LIGHTS` or a sequence of :class:`Light`. ``channels``: the params' channel
    names, which say how the lights' RGB irradiance enters each channel (:func:`channel_irradiance`; None: r, g,
    b for three channels). ``model_options`` as for :func:`brdffit.evaluate` (``fresnel=``, ``lobes=``). Scene and
    formula: the module docstring. Float64, 0 outside the disc (:func:`sphere_normals` gives the disc's mask),
    finite everywhere for finite parameters.
    """
    model = model_for(model, params, **model_options)
    checked = model.dictionary.to_params(params)
    lights = resolve_lights(lights)
    inside, normals = sphere_normals(size)
    n_channels = checked.diffuse.shape[0]
    directions = np.array([light.direction for light in lights])
    irradiance = channel_irradiance(lights, channels, n_channels)
    image = np.zeros((*inside.shape, n_channels))
    image[inside] = np.asarray(_radiance(model, checked, normals, directions, irradiance))
    return image


@jit(static_argnums=0)
def _radiance(model: Model, params: Params, normals, light_directions, irradiance):
    """``Σ_l f(wi_l, wo) · E_l · max(cos θi_l, 0)`` (P, C) for normals (P, 3), lights (L, 3) and (L, C)."""
    frame = shading_frame(normals)  # (P, 3, 3)
    wi = jnp.einsum("pij,lj->lpi", frame, light_directions)  # (L, P, 3)
    wo = jnp.broadcast_to(frame @ jnp.asarray(VIEW), wi.shape)  # (L, P, 3)
    n_lights, n_pixels = wi.shape[:2]
    values = model.brdf(params, wi.reshape(-1, 3), wo.reshape(-1, 3)).reshape(n_lights, n_pixels, -1)
    cosine = jnp.maximum(wi[..., 2], 0.0)  # brdf() is already 0 below the horizon
    return jnp.einsum("lpc,lp,lc->pc", values, cosine, irradiance)


def render_measured(
    samples: Samples,
    *,
    size: int = 256,
    lights: "str | Sequence[Light]" = "point",
    max_distance: float = MAX_DISTANCE_DEGREES,
) -> MeasuredSphere:
    """The sphere of :func:`render_sphere` with each BRDF value looked up in ``samples`` instead of a model.

    For every lit pixel and light, the value is that of the sample nearest in :func:`rusinkiewicz_embedding`
    (isotropic, reciprocal: as MERL tabulates; Ngan et al. 2005 render their measured spheres from the table's
    bins) if one lies within ``max_distance`` degrees; a pixel where some light found none has no data (its
    radiance 0, ``has_data`` False). Light irradiance enters the samples' channels as in
    :func:`channel_irradiance`.
    """
    if not isinstance(samples, Samples):
        raise BrdfInputError(Argument("samples"), f" must be Samples, got {type(samples).__name__}")
    if isinstance(max_distance, bool) or not isinstance(max_distance, numbers.Real) or not 0 < max_distance <= 90:
        raise BrdfInputError(Argument.given("max_distance", max_distance), " is not allowed; give degrees in (0, 90]")
    lights = resolve_lights(lights)
    inside, normals = sphere_normals(size)
    wi, wo = _local_directions(normals, lights)
    lit_by = wi[..., 2] > 0  # (L, P); wo_z = n_z > 0 inside the disc
    tree = _sample_tree(samples)
    light_index, pixel_index = np.nonzero(lit_by)
    queries = rusinkiewicz_embedding(wi[light_index, pixel_index], wo[pixel_index])
    distance, nearest = tree.query(queries, distance_upper_bound=np.radians(max_distance), workers=-1)
    found = np.isfinite(distance)
    irradiance = channel_irradiance(lights, samples.channels, samples.n_channels)
    contribution = np.zeros((len(queries), samples.n_channels))
    contribution[found] = (
        samples.values[nearest[found]]
        * irradiance[light_index[found]]
        * wi[light_index[found], pixel_index[found], 2][:, None]
    )
    radiance = np.zeros((len(normals), samples.n_channels))
    np.add.at(radiance, pixel_index, contribution)
    missing = np.zeros(len(normals), dtype=bool)
    missing[pixel_index[~found]] = True
    lit = lit_by.any(axis=0)
    has_data = lit & ~missing
    radiance[~has_data] = 0.0
    image = np.zeros((*inside.shape, samples.n_channels))
    image[inside] = radiance
    lit_image, data_image = np.zeros(inside.shape, dtype=bool), np.zeros(inside.shape, dtype=bool)
    lit_image[inside], data_image[inside] = lit, has_data
    fraction = float(has_data.sum() / lit.sum()) if lit.any() else 0.0
    return MeasuredSphere(image, lit_image, data_image, fraction, float(max_distance))


#: The k-d tree of each Samples object while it lives (Samples are frozen): a figure with both lightings, or a
#: report, looks a MERL table up more than once, and building its tree costs about a second.
_TREES: "weakref.WeakKeyDictionary[Samples, Any]" = weakref.WeakKeyDictionary()


def _sample_tree(samples: Samples):
    """A :class:`scipy.spatial.cKDTree` over the samples' :func:`rusinkiewicz_embedding`, built once per object."""
    tree = _TREES.get(samples)
    if tree is None:
        from scipy.spatial import cKDTree

        tree = _TREES[samples] = cKDTree(rusinkiewicz_embedding(samples.wi, samples.wo))
    return tree


# ---------------------------------------------------------------------- display
def exposure_for(linear_rgb: np.ndarray | Sequence[np.ndarray], mask=None) -> float:
    """The exposure that maps the :data:`EXPOSURE_PERCENTILE` percentile of luminance to display white.

    ``linear_rgb``: one image (…, 3) or several (their pixels pooled: one exposure for images that must
    compare); ``mask``: the pixels to count (the same shapes without the last axis; default every pixel with a
    luminance above 0). Luminance is linear sRGB's Y (IEC 61966-2-1). Returns 1 when nothing is lit.
    """
    images = [linear_rgb] if isinstance(linear_rgb, np.ndarray) else list(linear_rgb)
    masks = [mask] if isinstance(mask, np.ndarray) or mask is None else list(mask)
    if len(masks) == 1 and len(images) > 1:
        masks = masks * len(images)
    pooled = []
    for image, chosen in zip(images, masks, strict=True):
        luminance = np.asarray(image, dtype=float) @ LUMINANCE_WEIGHTS
        pooled.append(luminance[(luminance > 0) if chosen is None else np.asarray(chosen, dtype=bool)])
    values = np.concatenate(pooled) if pooled else np.zeros(0)
    values = values[np.isfinite(values)]
    white = np.percentile(values, EXPOSURE_PERCENTILE) if values.size else 0.0
    return float(1.0 / white) if white > 0 else 1.0


def to_srgb(linear_rgb: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Display values in [0, 1]: ``exposure · linear_rgb`` clipped to [0, 1], then sRGB-encoded.

    The sRGB transfer function (IEC 61966-2-1:1999, §5.2; colour-science's ``cctf_encoding``, written out here
    because importing colour-science costs ~1 s): ``12.92 · v`` for ``v ≤ 0.0031308``, else
    ``1.055 · v^(1/2.4) − 0.055``. Clipping is the tone curve: what is brighter than white stays white.
    """
    linear = np.clip(np.asarray(linear_rgb, dtype=float) * exposure, 0.0, 1.0)
    linear = np.nan_to_num(linear, nan=0.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1.0 / 2.4) - 0.055)
