"""Neighbour starts: a texel whose fit ended in a local minimum fitted again from a neighbour's parameters.

A few dozen samples leave a texel's start search in a local minimum now and then (a noise-free capture of Mitsuba's
``principled``: 37 of 64 texels at costs of 0.01–0.09 where the truth's is 4·10⁻¹⁴). Neighbouring texels are alike,
so each texel whose cost is above :data:`RESTART_ABOVE` times one of its four neighbours' is fitted again from that
neighbour's parameters (the one of lowest cost) and keeps the new fit only where it ends lower: a fit never gets worse
for it, and nothing is smoothed. Up to :data:`PASSES` passes, so that a good fit spreads across a stuck patch.
"""

from collections.abc import Callable
from typing import Any

import numpy as np

from .capture import Capture
from .maps import column_params

#: A texel whose cost is above this many times a neighbour's is fitted again from the neighbour's parameters: a fit
#: stuck in a local minimum ends far above, while neighbours' costs at one noise level differ by tens of percent.
RESTART_ABOVE = 2.0
PASSES = 3
#: A refit replaces a fit when its cost is lower by more than this (relative).
SAME_COST = 1e-9
#: A texel's four neighbours, in the order :func:`_lowest_neighbour` stacks them.
DIRECTIONS = ("up", "down", "left", "right")


def neighbour_starts(
    columns: dict[str, np.ndarray], capture: Capture, refit: Callable[[np.ndarray, list[dict[str, Any]]], dict]
) -> dict[str, int]:
    """Each texel of ``columns`` (the capture's flat arrays, updated) far above a neighbour's cost refitted from its
    parameters, ``refit(texels, starts) -> arrays`` (module docstring); how many fits were ``retried`` and
    ``improved``."""
    rows, width = capture.shape
    offsets = np.array([-width, width, -1, 1])  # the order of DIRECTIONS, as ``_lowest_neighbour`` stacks them
    fitted = columns["n_samples"].reshape(rows, width) > 0  # a refit keeps a texel's samples
    retried = improved = 0
    for _ in range(PASSES):
        cost = columns["cost"].reshape(rows, width)
        best, lowest = _lowest_neighbour(np.where(fitted, cost, np.inf))
        again = np.isfinite(cost) & fitted & (cost > RESTART_ABOVE * lowest)
        if not again.any():
            break
        texels = np.flatnonzero(again.ravel())
        sources = texels + offsets[best.ravel()[texels]]
        starts = [column_params(columns, source) for source in sources]
        tile = refit(texels, starts)
        lower = tile["cost"] < columns["cost"][texels] * (1.0 - SAME_COST)
        for name, values in tile.items():
            if name in columns:
                columns[name][texels[lower]] = values[lower]
        retried, improved = retried + len(texels), improved + int(lower.sum())
        if not lower.any():
            break
    return {"retried": retried, "improved": improved}


def _lowest_neighbour(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which of each texel's four neighbours (:data:`DIRECTIONS`) has the lowest of ``cost`` (H, W; ``inf`` where
    none), and that cost."""
    finite = np.where(np.isfinite(cost), cost, np.inf)
    padded = np.pad(finite, 1, constant_values=np.inf)
    shifted = np.stack([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]])
    best = shifted.argmin(axis=0)
    return best, np.take_along_axis(shifted, best[None], axis=0)[0]
