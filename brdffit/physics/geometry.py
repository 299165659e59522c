"""Directions in the local shading frame.

Frame: ``z`` is the surface normal, ``x`` the tangent (azimuth ``phi = 0``), ``y = z × x``. ``wi`` points
from the surface towards the light, ``wo`` towards the viewer. Angles are in radians unless a name says
degrees; files use degrees.

Every function works on numpy and JAX arrays alike (:func:`brdffit._jax.arrays.namespace`) and broadcasts
over leading axes; the last axis holds ``(x, y, z)``. Host code (readers, writers, ``data_synth``) gets
numpy back, so this module imports no JAX of its own.
"""

from __future__ import annotations  # the jaxtyping annotations stay unevaluated: importing jax costs ~0.5 s

from typing import TYPE_CHECKING, Any, overload

import numpy as np

from .._jax import first_bad, namespace
from ..errors import BrdfInputError

if TYPE_CHECKING:
    from collections.abc import Callable

    from jaxtyping import Array, Bool, Float

    Directions = Float[Array, "*batch 3"] | Float[np.ndarray, "*batch 3"]
    #: Angles on the host, whose directions are numpy's.
    HostAngles = np.ndarray | float

#: The surface normal, used to stand in for directions the models must ignore.
NORMAL = (0.0, 0.0, 1.0)
#: Direction vectors may deviate this much from unit length (printed files round); they are then normalised.
UNIT_LENGTH_TOLERANCE = 1e-3


@overload
def spherical_to_direction(theta: HostAngles, phi: HostAngles) -> np.ndarray: ...
@overload
def spherical_to_direction(theta: Any, phi: Any) -> Directions: ...
def spherical_to_direction(theta, phi):
    """Unit vector ``(sin θ cos φ, sin θ sin φ, cos θ)`` for zenith ``θ`` and azimuth ``φ`` (radians)."""
    xp = namespace(theta, phi)
    sin_theta = xp.sin(theta)
    return xp.stack([sin_theta * xp.cos(phi), sin_theta * xp.sin(phi), xp.cos(theta)], axis=-1)


def direction_to_spherical(direction: Directions):
    """Zenith ``θ ∈ [0, π]`` and azimuth ``φ ∈ (-π, π]`` (radians) of a unit vector."""
    xp = namespace(direction)
    x, y, z = direction[..., 0], direction[..., 1], direction[..., 2]
    azimuth = xp.arctan2(y, x)
    # arctan2 gives -π for x < 0 and y = -0.0 (or a negative y too small to move the result): that is φ = π.
    return xp.arctan2(xp.hypot(x, y), z), xp.where(azimuth == -xp.pi, xp.pi, azimuth)


def zenith_degrees(direction: Directions):
    """The zenith angle ``θ = acos(z)`` of unit vectors, in degrees.

    The one place θ is computed from a direction: every selection by angle (``max_theta``, MERL's
    reader, ``brdffit info``) uses it, so that two code paths cannot disagree at a boundary.
    """
    xp = namespace(direction)
    return xp.degrees(xp.arccos(xp.clip(direction[..., 2], -1.0, 1.0)))


def half_vector(wi: Directions, wo: Directions) -> Directions:
    """``h = normalize(wi + wo)``, the microfacet normal that mirrors ``wi`` into ``wo``.

    Finite (with finite derivatives) whenever ``wi + wo ≠ 0``, which holds for any
    two directions in the upper hemisphere.
    """
    xp = namespace(wi, wo)
    summed = wi + wo
    return summed / xp.sqrt(xp.sum(summed * summed, axis=-1, keepdims=True))


def to_half_difference(wi: Directions, wo: Directions):
    """Rusinkiewicz's (EGWR 1998) half/difference angles ``θh, φh, θd, φd`` (radians) of the pairs ``wi``, ``wo``.

    ``h = normalize(wi + wo)`` has zenith ``θh`` and azimuth ``φh``; the difference vector
    ``d = R_y(−θh) R_z(−φh) wi`` (the light seen from the half vector's frame) has zenith ``θd`` and azimuth
    ``φd``. Isotropic BRDFs depend on ``θh, θd, φd`` only (MERL's table, Matusik et al. 2003). The inverse is
    :func:`from_half_difference`. numpy or JAX.
    """
    xp = namespace(wi, wo)
    theta_h, phi_h = direction_to_spherical(half_vector(wi, wo))
    cos_p, sin_p, cos_t, sin_t = xp.cos(phi_h), xp.sin(phi_h), xp.cos(theta_h), xp.sin(theta_h)
    x = cos_p * wi[..., 0] + sin_p * wi[..., 1]  # R_z(−φh) wi
    y = -sin_p * wi[..., 0] + cos_p * wi[..., 1]
    d = xp.stack([cos_t * x - sin_t * wi[..., 2], y, sin_t * x + cos_t * wi[..., 2]], axis=-1)  # R_y(−θh)
    theta_d, phi_d = direction_to_spherical(d)
    return theta_h, phi_h, theta_d, phi_d


@overload
def from_half_difference(
    theta_h: HostAngles, phi_h: HostAngles, theta_d: HostAngles, phi_d: HostAngles
) -> tuple[np.ndarray, np.ndarray]: ...
@overload
def from_half_difference(theta_h: Any, phi_h: Any, theta_d: Any, phi_d: Any) -> tuple[Directions, Directions]: ...
def from_half_difference(theta_h, phi_h, theta_d, phi_d):
    """``wi, wo`` (N, 3) of Rusinkiewicz's angles (radians), the inverse of :func:`to_half_difference`:
    ``wi = R_z(φh) R_y(θh) d(θd, φd)`` and ``wo = R_z(φh) R_y(θh) (−d_x, −d_y, d_z)``. numpy or JAX."""
    xp = namespace(theta_h, phi_h, theta_d, phi_d)
    d = spherical_to_direction(theta_d, phi_d)
    mirrored = d * xp.asarray([-1.0, -1.0, 1.0])
    return _rotated(d, theta_h, phi_h), _rotated(mirrored, theta_h, phi_h)


def _rotated(v, theta_h, phi_h):
    """``R_z(φh) R_y(θh) v``: ``v`` from the frame whose ``z`` is the half vector ``(θh, φh)``."""
    xp = namespace(v)
    cos_t, sin_t, cos_p, sin_p = xp.cos(theta_h), xp.sin(theta_h), xp.cos(phi_h), xp.sin(phi_h)
    x = cos_t * v[..., 0] + sin_t * v[..., 2]
    z = -sin_t * v[..., 0] + cos_t * v[..., 2]
    y = v[..., 1]
    return xp.stack([cos_p * x - sin_p * y, sin_p * x + cos_p * y, z], axis=-1)


@overload
def in_turned_frame(w: np.ndarray, azimuth: HostAngles) -> np.ndarray: ...
@overload
def in_turned_frame(w: Directions, azimuth: Any) -> Directions: ...
def in_turned_frame(w, azimuth):
    """Directions ``w`` as seen in the frame turned by ``azimuth`` (radians) about the normal: their components along
    ``t = (cos a, sin a, 0)``, ``b = (−sin a, cos a, 0)`` and ``z``. An anisotropic lobe's tangent ``t`` at azimuth
    ``a``: ``w·t`` and ``w·b`` are its tangent-frame slopes' numerators. numpy or JAX."""
    xp = namespace(w, azimuth)
    cos_a, sin_a = xp.cos(azimuth), xp.sin(azimuth)
    x, y = w[..., 0], w[..., 1]
    return xp.stack([cos_a * x + sin_a * y, cos_a * y - sin_a * x, w[..., 2]], axis=-1)


def mirror_direction(w: Directions) -> Directions:
    """Mirror image of ``w`` about the normal: ``(-x, -y, z)``."""
    xp = namespace(w)
    return w * xp.asarray([-1.0, -1.0, 1.0], dtype=w.dtype)


def above_horizon(
    wi: Directions, wo: Directions
) -> tuple[Bool[Array, " n"] | Bool[np.ndarray, " n"], Directions, Directions]:
    """Which pairs have both directions above the horizon, and the directions with every other pair
    replaced by the normal.

    A model is zero below the horizon; computing it there on the normal instead keeps its values and
    derivatives finite, where the ``where`` that zeroes them would otherwise multiply an infinite
    derivative by 0 (and give NaN). ``wi``, ``wo``: (N, 3).
    """
    xp = namespace(wi, wo)
    visible = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    normal = xp.asarray(NORMAL, dtype=wi.dtype)
    return visible, xp.where(visible[:, None], wi, normal), xp.where(visible[:, None], wo, normal)


def tan2_from_cos(cos_theta):
    """``tan²θ = (1 - cos²θ) / cos²θ`` for ``cos θ > 0``, never below 0.

    A normalised half vector can have ``cos θ`` a rounding above 1 (MERL's specular bins); the negative
    ``tan²θ`` that gives would make ``exp(-tan²θ/α²)`` overflow for a sharp lobe.
    """
    xp = namespace(cos_theta)
    cos2 = cos_theta * cos_theta
    return xp.maximum((1.0 - cos2) / cos2, 0.0)


def safe_power(base, exponent):
    """``max(base, 0) ** exponent`` with finite values and derivatives everywhere.

    Computed as ``exp(exponent · ln base)`` where ``base`` is above the smallest
    normal float and as 0 elsewhere, so that neither ``ln 0`` nor ``1/0`` ever
    enters a derivative. Exponents of 10⁴ and more simply underflow to 0.
    """
    xp = namespace(base, exponent)
    tiny = xp.finfo(xp.result_type(base)).tiny
    positive = base > tiny
    safe_base = xp.where(positive, base, 1.0)
    return xp.where(positive, xp.exp(exponent * xp.log(safe_base)), 0.0)


def normalised(vectors: np.ndarray, message: Callable[[int, float], str]) -> np.ndarray:
    """``vectors`` (N, 3) divided by their lengths, each of which must be 1 within :data:`UNIT_LENGTH_TOLERANCE`;
    otherwise a :class:`BrdfInputError` with ``message(row, length)`` for the first that is not."""
    length = np.sqrt(np.einsum("ij,ij->i", vectors, vectors))  # a third of np.linalg.norm's time (524,288 rows: 3 ms)
    bad = first_bad(np.abs(length - 1.0) > UNIT_LENGTH_TOLERANCE)
    if bad is not None:
        raise BrdfInputError(message(bad[0], float(length[bad[0]])))
    return vectors / length[:, None]


def directions_from_angles(theta_i, phi_i, theta_o, phi_o, *, degrees: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``wi``, ``wo`` (N, 3) of light and viewer from their zeniths and azimuths: a samples file's
    ``theta_i, phi_i, theta_o, phi_o`` columns (degrees, or radians with ``degrees=False``), as ``load_samples``
    reads them (:func:`spherical_to_direction`). Each may be a number or an array; they broadcast. A zenith outside
    [0, 90°] (below the horizon) or an angle that is not finite is a one-line error."""
    names = ("theta_i", "phi_i", "theta_o", "phi_o")
    angles = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (theta_i, phi_i, theta_o, phi_o)))
    unit, right = ("degrees", 90.0) if degrees else ("radians", np.pi / 2)
    for name, values in zip(names, angles, strict=True):
        zenith = name.startswith("theta")
        bad = np.flatnonzero(~np.isfinite(values) | (((values < 0) | (values > right)) if zenith else False))
        if bad.size:
            allowed = f" and within [0, {right:g}] {unit} (above the horizon)" if zenith else ""
            raise BrdfInputError(f"{name} = {values.ravel()[bad[0]]:g} (at {bad[0]}) must be finite{allowed}")
    radians = [np.radians(a) if degrees else a for a in angles]
    return spherical_to_direction(radians[0], radians[1]), spherical_to_direction(radians[2], radians[3])


def angles_from_directions(wi, wo, *, degrees: bool = True) -> tuple[np.ndarray, ...]:
    """Zeniths and azimuths ``theta_i, phi_i, theta_o, phi_o`` of unit vectors ``wi``, ``wo`` (N, 3): the samples
    file's columns, in degrees (or radians with ``degrees=False``), azimuths in (−180°, 180°], as brdffit's writers
    compute them (:func:`direction_to_spherical`)."""
    angles = [angle for w in (wi, wo) for angle in direction_to_spherical(np.asarray(w, dtype=np.float64))]
    return tuple(np.degrees(angle) if degrees else angle for angle in angles)
