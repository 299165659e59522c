"""The photograph fitted maps predict: the rectified image of the sample under a new point light and camera.

Texel by texel (``texels.py``'s geometry, in reverse, in each texel's frame where the capture had a normal map): ``L =
f(wi, wo) · I · cos θi / |l − p|²``, with ``f`` the texel's fitted BRDF (``maps.py``), ``I`` the light's radiant
intensity, ``l`` its position and ``p`` the texel's centre (mm); NaN where a texel was not fitted. So a photograph held
back from a fit can be set beside the image its maps predict for the same light and camera.
"""

import os

import jax
import numpy as np

from .._jax import float64
from .._programs import built_once
from ..errors import BrdfInputError
from ..physics.models.model import Model
from ..physics.models.params import Params
from ..physics.models.registry import get_model
from .capture import texel_centres
from .maps import Maps, nested_params, read_maps
from .texels import MIN_COSINE, point_light

#: Texels evaluated in one call of the compiled, vmapped BRDF.
CHUNK = 65536


@float64
def relight(maps: "Maps | str | os.PathLike", light_mm, camera_mm, intensity=1.0) -> np.ndarray:
    """The image (H, W, C) of linear radiance ``maps`` (or a maps folder) predict with a point light at
    ``light_mm`` (3,) of radiant ``intensity`` (a number, or one per channel, > 0) and the camera at ``camera_mm``
    (3,), both above the plane."""
    maps = maps if isinstance(maps, Maps) else read_maps(maps)
    light, camera = (point_above(name, value) for name, value in (("light_mm", light_mm), ("camera_mm", camera_mm)))
    n_channels = len(maps.channels)
    try:
        intensity = np.broadcast_to(np.asarray(intensity, dtype=float), (n_channels,))
    except ValueError:
        raise BrdfInputError(
            f"intensity: {np.size(intensity)} values for {n_channels} channels; give one, or one per channel"
        ) from None
    if not np.all(np.isfinite(intensity) & (intensity > 0)):
        raise BrdfInputError(f"intensity: {intensity.tolist()}: every value must be > 0")
    centres = texel_centres(maps.width_mm, maps.height_mm, maps.shape)
    normals = None if maps.normals is None else maps.normals.reshape(-1, 3)
    wi, wo, squared = (array[:, 0] for array in point_light(centres, light[None], camera[None], normals))
    values = np.full((centres.shape[0], n_channels), np.nan)
    fitted = np.flatnonzero(maps.fitted.ravel())
    model = get_model(maps.model, **maps.model_options)
    flat = {name: array.reshape(-1, *array.shape[2:]) for name, array in maps.params.items()}
    for start in range(0, len(fitted), CHUNK):
        chunk = fitted[start : start + CHUNK]
        values[chunk] = texel_brdf(model, stacked_params(model, flat, chunk), wi[chunk], wo[chunk])
    cos_i = np.maximum(wi[:, 2], MIN_COSINE)
    radiance = values * (intensity[None, :] * cos_i[:, None] / squared[:, None])
    return radiance.reshape(*maps.shape, n_channels)


def stacked_params(model: Model, flat: dict[str, np.ndarray], texels: np.ndarray) -> Params:
    """The :class:`~brdffit.physics.models.params.Params` of ``texels`` (T,) of flat maps (name → (H·W[, C]), as
    ``maps.flat_params`` names them), stacked along a leading axis of T, each texel's checked as a result's are."""
    params = [
        model.dictionary.to_params(nested_params({name: array[texel].tolist() for name, array in flat.items()}))
        for texel in texels
    ]
    return jax.tree.map(lambda *leaves: np.stack(leaves), *params)


@float64
def texel_brdf(model: Model, stacked: Params, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The BRDF (T, C) in 1/sr of each of T texels with its parameters (``stacked``, :func:`stacked_params`) at its
    own pair ``wi``, ``wo`` (T, 3), in one compiled, vmapped call."""
    return np.asarray(_vmapped_brdf(model)(stacked, np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)))


@built_once
def _vmapped_brdf(model: Model):
    return jax.jit(jax.vmap(lambda params, wi, wo: model.brdf(params, wi[None], wo[None])[0]))


def point_above(name: str, value) -> np.ndarray:
    """``value`` as a point (3,) in mm above the sample's plane; a one-line error naming ``name`` where it is not
    three finite numbers with z > 0."""
    try:
        point = np.asarray(value, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise BrdfInputError(f"{name}: must be three numbers x, y, z in mm, got {value!r}") from None
    if not np.all(np.isfinite(point)) or not point[2] > 0.0:
        raise BrdfInputError(f"{name}: {point.tolist()} must be finite and above the sample's plane (z > 0 mm)")
    return point
