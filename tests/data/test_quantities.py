"""What a file's values are: every quantity becomes the BRDF, ``cosine-weighted`` is the light's cosine."""

import math

import numpy as np
import pytest
from conftest import random_directions

from brdffit import BrdfInputError
from brdffit.data.quantities import QUANTITIES, canonical, stored_factor, to_brdf
from brdffit.data.samples import Samples


def test_each_quantity_divides_by_its_factor(rng):
    wi, wo = random_directions(rng, 50), random_directions(rng, 50)
    brdf = rng.random((50, 2))
    for quantity, factor in {
        "brdf": np.ones((50, 1)),
        "reflectance-factor": np.full((50, 1), math.pi),
        "cosine-weighted-in": wi[:, 2:3],
        "cosine-weighted-out": wo[:, 2:3],
    }.items():
        stored = Samples.from_arrays(wi, wo, brdf * factor, sigma=0.01 * factor)
        back = to_brdf(stored, quantity)
        # one multiplication and one division: a few ulp
        np.testing.assert_allclose(back.values, brdf, rtol=1e-14)
        np.testing.assert_allclose(back.sigma, np.full((50, 2), 0.01), rtol=1e-14)
    assert set(QUANTITIES) == {"brdf", "reflectance-factor", "cosine-weighted-in", "cosine-weighted-out"}


def test_cosine_weighted_is_the_lights_cosine(rng):
    wi, wo = random_directions(rng, 5), random_directions(rng, 5)
    assert canonical("cosine-weighted") == "cosine-weighted-in"
    np.testing.assert_array_equal(stored_factor("cosine-weighted", wi, wo), wi[:, 2:3])
    with pytest.raises(BrdfInputError, match=r"^quantity='radiance' is not allowed; choose one of: brdf, "):
        canonical("radiance")
