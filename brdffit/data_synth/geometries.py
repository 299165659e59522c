"""Gonioreflectometer-style measurement geometries: direction pairs (wi, wo), each (N, 3).

Angles follow brdffit's frame (``docs/conventions.md``: ``z`` the normal, azimuth from ``x``); the light
sits at azimuth 0, so the mirror direction is at azimuth 180°. Grids use bin
midpoints, so no direction lies on the horizon. Random geometries take a seed.
A geometry holds at most :data:`MAX_SAMPLES` pairs, checked from its counts before anything is made.
"""

import math

import numpy as np

from brdffit.checks import angle_up_to_90, whole_number
from brdffit.errors import Argument, BrdfInputError
from brdffit.physics.geometry import mirror_direction, spherical_to_direction

#: The most direction pairs a geometry makes: above a full MERL table's 1,458,000. Synthesizing, writing and fitting a
#: sample takes ~1–2 KB at its peak, so this is a few GB; ``synth --n-theta 10000000`` (2.9 billion pairs) grew to 24 GB
#: and was killed before this cap.
MAX_SAMPLES = 2_000_000


def _directions(theta, phi) -> np.ndarray:
    return np.asarray(spherical_to_direction(np.asarray(theta), np.asarray(phi)))


def _midpoints(count: int, stop: float, start: float = 0.0) -> np.ndarray:
    return start + (np.arange(count) + 0.5) * (stop - start) / count


def _positive_count(name: str, value) -> int:
    return whole_number(name, value)


def _check_size(**counts: int) -> None:
    """Refuse a geometry of more than :data:`MAX_SAMPLES` pairs (the product of ``counts``) before making it."""
    total = math.prod(counts.values())
    if total > MAX_SAMPLES:
        parts: list = []
        for index, (name, value) in enumerate(counts.items()):
            parts += [" × " if index else "", Argument(name, str(value))]
        raise BrdfInputError(*parts, f" is {total:,} direction pairs; at most {MAX_SAMPLES:,}")


def hemisphere_grid(n_incident: int = 8, n_theta: int = 36, n_phi: int = 36) -> tuple[np.ndarray, np.ndarray]:
    """Full hemispherical grid: ``n_incident`` light zeniths × ``n_theta`` viewer zeniths × ``n_phi`` azimuths.

    Light zeniths and viewer zeniths are the midpoints of equal bins of
    [0°, 90°); viewer azimuths are ``k · 360°/n_phi``. 8 × 36 × 36 gives light
    at 5.6°, 16.9°, …, 84.4° and the viewer every 2.5° in zenith and 10° in azimuth.
    """
    n_incident, n_theta, n_phi = (
        _positive_count(k, v) for k, v in (("n_incident", n_incident), ("n_theta", n_theta), ("n_phi", n_phi))
    )
    _check_size(n_incident=n_incident, n_theta=n_theta, n_phi=n_phi)
    theta_i = _midpoints(n_incident, np.pi / 2)
    theta_o = _midpoints(n_theta, np.pi / 2)
    phi_o = np.arange(n_phi) * 2 * np.pi / n_phi
    ti, to, po = np.meshgrid(theta_i, theta_o, phi_o, indexing="ij")
    return _directions(ti.ravel(), 0.0 * ti.ravel()), _directions(to.ravel(), po.ravel())


def in_plane(n_incident: int = 8, n_theta: int = 90) -> tuple[np.ndarray, np.ndarray]:
    """The plane of incidence only: ``n_incident`` light zeniths × ``n_theta`` signed viewer zeniths in (-90°, 90°).

    Negative viewer zeniths lie on the mirror side (azimuth 180°).
    """
    n_incident, n_theta = _positive_count("n_incident", n_incident), _positive_count("n_theta", n_theta)
    _check_size(n_incident=n_incident, n_theta=n_theta)
    theta_i = _midpoints(n_incident, np.pi / 2)
    signed = _midpoints(n_theta, np.pi / 2, -np.pi / 2)
    ti, so = np.meshgrid(theta_i, signed, indexing="ij")
    so = so.ravel()
    return _directions(ti.ravel(), 0.0 * so), _directions(np.abs(so), np.where(so < 0, np.pi, 0.0))


def uniform_random(n_samples: int = 10000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n_samples`` pairs, light and viewer each uniform in solid angle over the hemisphere."""
    n_samples = _positive_count("n_samples", n_samples)
    _check_size(n_samples=n_samples)
    rng = np.random.default_rng(seed)
    # 1 - u with u ∈ [0, 1) gives cos θ ∈ (0, 1]: never exactly on the horizon.
    cos_theta = 1.0 - rng.random((2, n_samples))
    phi = 2 * np.pi * rng.random((2, n_samples))
    theta = np.arccos(cos_theta)
    return _directions(theta[0], phi[0]), _directions(theta[1], phi[1])


def near_specular(
    n_incident: int = 8, n_samples: int = 10000, spread: float = 10.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """``n_samples`` pairs dense around the mirror direction, for sharp lobes.

    Light zeniths as in :func:`hemisphere_grid`; for each, viewer directions at
    an angle ``δ`` from the mirror direction drawn uniformly in [0, ``spread``]
    degrees (so the density per solid angle grows as ``1/δ`` towards the
    peak), at a uniform azimuth about it; directions below 89.9° only.
    """
    n_incident, n_samples = _positive_count("n_incident", n_incident), _positive_count("n_samples", n_samples)
    _check_size(n_samples=n_samples)
    _check_size(n_incident=n_incident)
    angle_up_to_90("spread", spread)
    rng = np.random.default_rng(seed)
    theta_i = _midpoints(n_incident, np.pi / 2)
    per_light = np.diff(np.linspace(0, n_samples, n_incident + 1).round().astype(int))
    horizon = np.cos(np.radians(89.9))
    pairs_i, pairs_o = [], []
    for theta, count in zip(theta_i, per_light, strict=True):
        wi = _directions(np.array([theta]), np.zeros(1))[0]
        mirror = np.asarray(mirror_direction(wi))
        tangent = np.cross([0.0, 1.0, 0.0], mirror)
        tangent /= np.linalg.norm(tangent)
        bitangent = np.cross(mirror, tangent)
        kept = np.empty((0, 3))
        while len(kept) < count:
            delta = np.radians(spread) * rng.random(2 * count + 16)
            around = 2 * np.pi * rng.random(delta.size)
            wo = (
                np.cos(delta)[:, None] * mirror
                + (np.sin(delta) * np.cos(around))[:, None] * tangent
                + (np.sin(delta) * np.sin(around))[:, None] * bitangent
            )
            kept = np.vstack([kept, wo[wo[:, 2] > horizon]])
        pairs_o.append(kept[:count])
        pairs_i.append(np.repeat(wi[None], count, axis=0))
    return np.vstack(pairs_i), np.vstack(pairs_o)


#: ``--geometry`` names and the functions that make them.
GEOMETRIES = {
    "hemisphere": hemisphere_grid,
    "in-plane": in_plane,
    "random": uniform_random,
    "near-specular": near_specular,
}
