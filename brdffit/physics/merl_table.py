"""MERL's table of an isotropic BRDF: its bins and their directions (Matusik et al. 2003; Rusinkiewicz 1998).

Bin ``(i, j, k)`` at flat index ``k + 180 j + 16200 i`` holds ``θh = (i/90)² · π/2`` (a square-root grid,
dense near the specular peak), ``θd = j/90 · π/2`` and ``φd = k/180 · π``; ``φd`` is folded into ``[0, π)`` by
reciprocity. These are the angles MERL's ``BRDFRead.cpp`` maps to the bin (each bin's lower edge), and brdffit's
default. ``centres=True`` takes each bin at its centre instead, half a bin further along each index
(``θh = ((i + ½)/90)² · π/2``, ``θd = (j + ½)/90 · π/2``, ``φd = (k + ½)/180 · π``): the mean of the directions
that the lookup maps to the bin, as a table measured by averaging over each bin would hold. The file format is
``data/merl.py``'s; the data-driven model's basis lives on the same bins (``brdffit/datadriven``).
"""

import math

import numpy as np

from .geometry import from_half_difference

#: Table dimensions (θh, θd, φd bins), as in the header.
SHAPE = (90, 90, 180)
N_BINS = SHAPE[0] * SHAPE[1] * SHAPE[2]
#: Directions with ``z`` at most this are below the horizon; it keeps bins that lie exactly on the horizon
#: (``θh + θd = 90°`` at ``φd = 0``), which rounding puts at ``z = ±1e-17``, out on every platform.
HORIZON = 1e-12


def bin_offset(centres: bool = False) -> float:
    """Where in its bin a bin's value lies, in bin indices: 0 at its lower edge (``BRDFRead.cpp``), ½ at its centre."""
    return 0.5 if centres else 0.0


def bin_angles(centres: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(θh, θd, φd)`` in radians of every bin, each of shape (90, 90, 180): each bin's lower edge
    (``BRDFRead.cpp``'s lookup), or its centre with ``centres``."""
    i, j, k = (np.arange(n, dtype=float) + bin_offset(centres) for n in SHAPE)
    theta_h = (i / SHAPE[0]) ** 2 * (math.pi / 2)
    theta_d = j / SHAPE[1] * (math.pi / 2)
    phi_d = k / SHAPE[2] * math.pi
    theta_h, theta_d, phi_d = np.meshgrid(theta_h, theta_d, phi_d, indexing="ij")
    return theta_h, theta_d, phi_d


def bin_directions(centres: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``wi``, ``wo`` (1,458,000, 3) of every bin in file order (Rusinkiewicz 1998, ``φh = 0``), at each
    bin's lower edge or, with ``centres``, its centre.

    Some point below the horizon (``z ≤ 0``); MERL never looks those bins up.
    """
    theta_h, theta_d, phi_d = (a.reshape(-1) for a in bin_angles(centres))
    return from_half_difference(theta_h, np.zeros_like(theta_h), theta_d, phi_d)
