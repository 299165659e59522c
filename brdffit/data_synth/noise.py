"""Measurement noise, seeded. Values are BRDFs (1/sr) and stay non-negative."""

import numpy as np

from brdffit.checks import choice
from brdffit.errors import not_allowed

NOISE_KINDS = ("multiplicative", "additive")


def add_noise(
    values: np.ndarray, level: float, kind: str = "multiplicative", seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy copy of ``values`` and the 1-σ of the noise (both like ``values``).

    ``multiplicative``: ``y (1 + level·ε)``, σ = ``level · y`` (``level`` 0.01 is 1%);
    ``additive``: ``y + level·ε``, σ = ``level`` in 1/sr. ``ε`` is standard
    normal from ``numpy.random.default_rng(seed)``. Results below 0 are set to
    0 (a reflectance cannot be negative); at 1% multiplicative noise that needs a 100-σ draw.
    """
    choice("noise_kind", kind, NOISE_KINDS)
    if not (isinstance(level, int | float) and np.isfinite(level) and level >= 0):
        raise not_allowed("noise", level, "give a number ≥ 0")
    values = np.asarray(values, dtype=float)
    epsilon = np.random.default_rng(seed).standard_normal(values.shape)
    if kind == "multiplicative":
        return np.maximum(values * (1.0 + level * epsilon), 0.0), level * values
    return np.maximum(values + level * epsilon, 0.0), np.full_like(values, float(level))
