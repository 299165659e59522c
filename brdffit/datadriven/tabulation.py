"""Where a direction pair falls in MERL's table, and the weights that interpolate the table there.

The table is MERL's (``data/merl.py``; Matusik et al. 2003): bins ``(i, j, k)`` at Rusinkiewicz's (1998)
``θh = (i/90)²·π/2``, ``θd = j/90·π/2``, ``φd = k/180·π``, ``φd`` folded into ``[0, π)`` by reciprocity. A pair
of directions has *table coordinates* ``(90·sqrt(θh/(π/2)), 90·θd/(π/2), 180·φd/π)``, integers exactly at the
bins, and the table is interpolated trilinearly in them: ``φd`` wraps around (``φd = π`` is bin 0 again), ``θh``
and ``θd`` are held at their last bin. Bins that hold no value (below the horizon, or missing in the library)
take no weight: the weights of the others are renormalised, and a pair whose every neighbour is empty gets
weight 0 everywhere (the model is then 0 there). Host code (numpy).
"""

import math

import numpy as np

from ..physics.geometry import to_half_difference
from ..physics.merl_table import SHAPE


def table_coordinates(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Fractional table coordinates (N, 3) of the pairs ``wi``, ``wo`` (N, 3): bin indices along θh, θd, φd."""
    theta_h, _, theta_d, phi_d = to_half_difference(np.asarray(wi, float), np.asarray(wo, float))
    along_h = SHAPE[0] * np.sqrt(np.clip(theta_h, 0.0, math.pi / 2) / (math.pi / 2))
    along_d = SHAPE[1] * np.clip(theta_d, 0.0, math.pi / 2) / (math.pi / 2)
    along_phi = SHAPE[2] * np.mod(phi_d, math.pi) / math.pi
    return np.stack([along_h, along_d, along_phi], axis=-1)


def interpolation(
    wi: np.ndarray, wo: np.ndarray, filled: np.ndarray, offset: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Flat bin indices (N, 8) and trilinear weights (N, 8) of the pairs; ``filled`` (bins,) says which bins
    hold a value. The weights of each pair sum to 1, or to 0 where no neighbour is filled. ``offset``: where in its
    bin each value lies, in bin indices (½ for a table of bin centres; ``physics/merl_table.py``)."""
    coordinates = table_coordinates(wi, wo) - offset
    corners, weights = [], []
    along = []
    for axis, size in enumerate(SHAPE):
        u = coordinates[:, axis]
        if axis == 2:  # φd wraps: the bin after the last is the first
            low = np.floor(u).astype(np.int64) % size
            high = (low + 1) % size
        else:
            u = np.clip(u, 0.0, size - 1)
            low = np.minimum(np.floor(u).astype(np.int64), size - 2)
            high = low + 1
        along.append((low, high, u - np.floor(u) if axis == 2 else u - low))
    (h0, h1, th), (d0, d1, td), (p0, p1, tp) = along
    for hi, wh in ((h0, 1 - th), (h1, th)):
        for di, wd in ((d0, 1 - td), (d1, td)):
            for pi, wp in ((p0, 1 - tp), (p1, tp)):
                corners.append((hi * SHAPE[1] + di) * SHAPE[2] + pi)
                weights.append(wh * wd * wp)
    index, weight = np.stack(corners, axis=1), np.stack(weights, axis=1)
    weight = weight * filled[index]
    total = weight.sum(axis=1, keepdims=True)
    return index, np.divide(weight, total, out=np.zeros_like(weight), where=total > 0)
