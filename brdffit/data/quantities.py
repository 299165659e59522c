"""What a file's values are, and how they become BRDF values in 1/sr.

===================  ==========================  ==============================================
quantity             the values are              BRDF from them
===================  ==========================  ==============================================
brdf                 ``f``, 1/sr                 as they are
reflectance-factor   ``R = π f``                 ``R / π``
cosine-weighted-in   ``f · cos θi`` (the light)  divided by ``cos θi``
cosine-weighted-out  ``f · cos θo`` (the view)   divided by ``cos θo``
===================  ==========================  ==============================================

``cosine-weighted`` is another name for ``cosine-weighted-in``. Which one a file holds is not always
written in it (ALTA's ``#PARAM_OUT INV_STERADIAN_COSINE_FACTOR`` is ``cosine-weighted-out``; the real gray
tape has no ``#PARAM_OUT`` line and is too): ``reciprocity.py`` tells them apart on data that hold
reciprocal pairs.
"""

import math
from dataclasses import replace

import numpy as np

from ..checks import choice
from ..errors import BrdfInputError
from .samples import Samples

QUANTITIES = ("brdf", "reflectance-factor", "cosine-weighted-in", "cosine-weighted-out")
#: Other names a quantity is given by.
ALIASES = {"cosine-weighted": "cosine-weighted-in"}


def canonical(quantity: str) -> str:
    """The quantity's own name (``cosine-weighted`` → ``cosine-weighted-in``), checked."""
    choice("quantity", quantity, (*QUANTITIES, *ALIASES))
    return ALIASES.get(quantity, quantity)


def stored_factor(quantity: str, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The factor (N, 1) by which a file holding ``quantity`` multiplies the BRDF: the value is ``f · factor``."""
    quantity = canonical(quantity)
    if quantity == "reflectance-factor":
        return np.full((len(wi), 1), math.pi)
    if quantity == "cosine-weighted-in":
        return wi[:, 2:3]
    if quantity == "cosine-weighted-out":
        return wo[:, 2:3]
    return np.ones((len(wi), 1))


def to_brdf(samples: Samples, quantity: str) -> Samples:
    """``samples`` whose values (and sigma) are ``quantity``, turned into BRDF values in 1/sr."""
    factor = stored_factor(quantity, samples.wi, samples.wo)
    if np.all(factor == 1.0):
        return samples
    with np.errstate(over="ignore"):
        values = samples.values / factor
    if not np.all(np.isfinite(values)):
        row = int(np.argmax(~np.isfinite(values).all(axis=1)))
        raise BrdfInputError(f"{samples.source}: sample {row + 1}: the value read as {quantity} overflows as a BRDF")
    sigma = None if samples.sigma is None else samples.sigma / factor
    return replace(samples, values=values, sigma=sigma)
