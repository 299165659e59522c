"""Shared test set-up: float64 JAX, warnings as errors (pyproject), a private compilation cache."""

import os
import tempfile

import numpy as np
import pytest

from brdffit import _jax  # noqa: F401  (float64 before any test builds an array)

# The command line keeps compiled programs in ~/.cache; the tests keep theirs in a folder of their own.
os.environ.setdefault("BRDFFIT_CACHE_DIR", tempfile.mkdtemp(prefix="brdffit-test-cache-"))


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def random_directions(rng, n: int, min_cos: float = 1e-3) -> np.ndarray:
    """``n`` unit vectors uniform in solid angle with ``cos θ ∈ [min_cos, 1]``."""
    cos_theta = min_cos + (1.0 - min_cos) * rng.random(n)
    phi = 2 * np.pi * rng.random(n)
    sin_theta = np.sqrt(1.0 - cos_theta**2)
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=-1)


def directions_from_degrees(theta, phi) -> np.ndarray:
    theta, phi = np.radians(np.atleast_1d(theta)), np.radians(np.atleast_1d(phi))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
