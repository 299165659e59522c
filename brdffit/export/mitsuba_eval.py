"""Mitsuba 3 itself: loaded where it is installed (a one-line error naming the extra where not), and a BSDF evaluated
by it at direction pairs, the renderer's own values of an export."""

from typing import Any

import numpy as np

from ..errors import BrdfInputError

#: What to install for Mitsuba.
EXTRA = "pip install 'brdffit[render]' (Mitsuba 3)"


def mitsuba():
    """Mitsuba 3 with its ``scalar_rgb`` variant set, or a one-line error saying how to install it."""
    try:
        import mitsuba as mi
    except ImportError:
        raise BrdfInputError(f"rendering with Mitsuba needs Mitsuba 3, which is not installed: {EXTRA}") from None
    mi.set_variant("scalar_rgb")
    return mi


def mitsuba_version() -> str | None:
    """The installed Mitsuba 3's version, or None where it is not installed."""
    try:
        import mitsuba as mi
    except ImportError:
        return None
    return str(mi.__version__)


def mitsuba_brdf(bsdf: dict[str, Any], wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The BRDF (N, 3) in 1/sr that Mitsuba 3 (``scalar_rgb``) computes for the BSDF ``bsdf`` (the dictionary
    ``mitsuba.load_dict`` takes) at pairs ``wi`` (towards the light), ``wo`` (towards the viewer), (N, 3) in the
    surface's frame. Mitsuba's ``BSDF.eval`` returns ``f · cos θ`` of the direction it is given (here the light's),
    which is divided out; pairs with either direction at or below the horizon are 0. About 3 µs a pair."""
    mi = mitsuba()
    loaded = mi.load_dict(bsdf)
    context = mi.BSDFContext()
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    values = np.zeros((len(wi), 3))
    for index, (light, viewer) in enumerate(zip(wi.tolist(), wo.tolist(), strict=True)):
        if light[2] <= 0.0 or viewer[2] <= 0.0:
            continue
        interaction = mi.SurfaceInteraction3f()
        interaction.wi = mi.Vector3f(*viewer)
        value = loaded.eval(context, interaction, mi.Vector3f(*light))
        values[index] = (value[0] / light[2], value[1] / light[2], value[2] / light[2])
    return values
