"""What a file's values are, and how they become BRDF values in 1/sr.

==================  =========================  ==========================================
quantity            the values are             BRDF from them
==================  =========================  ==========================================
brdf                ``f``, 1/sr                as they are
reflectance-factor  ``R = π f``                ``R / π``
cosine-weighted     ``f · cos θi``             divided by ``cos θi`` (the light's cosine)
==================  =========================  ==========================================
"""

import math
from dataclasses import replace

import numpy as np

from ..checks import choice
from .samples import Samples

QUANTITIES = ("brdf", "reflectance-factor", "cosine-weighted")


def to_brdf(samples: Samples, quantity: str) -> Samples:
    """``samples`` whose values (and sigma) are ``quantity`` turned into BRDF values in 1/sr."""
    choice("quantity", quantity, QUANTITIES)
    if quantity == "brdf":
        return samples
    if quantity == "reflectance-factor":
        scale = np.full((samples.n_samples, 1), 1.0 / math.pi)
    else:
        scale = (1.0 / samples.wi[:, 2])[:, None]
    sigma = None if samples.sigma is None else samples.sigma * scale
    return replace(samples, values=samples.values * scale, sigma=sigma)
