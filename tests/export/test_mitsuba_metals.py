"""Mitsuba's own metals, fitted and exported back (issue 28, part 1): data made by Mitsuba 3's ``roughconductor`` with
its built-in ``material`` (``Au``, ``Cu``, ``Al``: a complex index per channel, from its spectral tables), 1% noise.

The default fit of the matching model (``cook-torrance:fresnel=conductor,distribution=…,shadowing=smith``, ``ks``
held at 1) reaches the best cost 20 random starts find, gives back the roughness within 1%, and, exported to
Mitsuba, evaluates at the data's directions within 1.5% (median) of the data, whose noise is 1%.
"""

import math
import warnings

import numpy as np
import pytest
from test_mitsuba import mitsuba_brdf

from brdffit import Samples, data_synth, fit
from brdffit.export.mitsuba import mitsuba_bsdf
from brdffit.physics.metals import METALS

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install 'brdffit[render]')")
mi.set_variant("scalar_rgb")

ALPHA = 0.2
CASES = [
    pytest.param(metal, distribution, marks=() if (metal, distribution) == ("Au", "ggx") else pytest.mark.heavy)
    for metal in ("Au", "Cu", "Al")
    for distribution in ("ggx", "beckmann")
]
#: Two fits that end at one minimum agree to the solver's stopping tolerance on the cost's relative change (1e-8 per
#: step, and a few steps' worth): a random start that finds a lower cost by more than 1e-6 found another minimum.
SAME_MINIMUM = 1e-6


def metal_data(metal: str, distribution: str) -> tuple[Samples, np.ndarray]:
    """Mitsuba's BRDF of ``metal`` at 1,500 directions uniform in solid angle and 1,500 near the mirror (the lobe),
    with 1% Gaussian noise (seed 1); and the noiseless values."""
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": distribution, "alpha": ALPHA, "material": metal})
    wi, wo = data_synth.uniform_random(1500, seed=5)
    near_wi, near_wo = data_synth.near_specular(6, 1500, spread=4 * math.degrees(math.atan(ALPHA)), seed=6)
    wi, wo = np.vstack([wi, near_wi]), np.vstack([wo, near_wo])
    clean = mitsuba_brdf(bsdf, wi, wo)
    noisy = clean * (1.0 + 0.01 * np.random.default_rng(1).standard_normal(clean.shape))
    return Samples.from_arrays(wi, wo, noisy, channels=("r", "g", "b")), clean


def random_start(rng) -> dict:
    """A start anywhere metals are: roughness log-uniform in [0.02, 0.8], eta log-uniform in [0.1, 5], k in [0, 8]."""
    return {
        "kd": [0.01, 0.01, 0.01],
        "ks": [1.0, 1.0, 1.0],
        "m": float(np.exp(rng.uniform(np.log(0.02), np.log(0.8)))),
        "eta": [float(x) for x in np.exp(rng.uniform(np.log(0.1), np.log(5.0), 3))],
        "k": [float(x) for x in rng.uniform(0.0, 8.0, 3)],
    }


@pytest.mark.parametrize(("metal", "distribution"), CASES)
def test_mitsubas_metals_are_fitted_and_exported_back(metal, distribution):
    samples, _ = metal_data(metal, distribution)
    options = {"fresnel": "conductor", "distribution": distribution, "shadowing": "smith"}
    result = fit(samples, "cook-torrance", **options)
    assert result.fixed == {"ks": [1.0, 1.0, 1.0]}
    rng = np.random.default_rng(7)
    with warnings.catch_warnings():  # a random start may end anywhere, implausible values and all: said, not raised
        warnings.simplefilter("ignore")
        best_random = min(fit(samples, "cook-torrance", start=random_start(rng), **options).cost for _ in range(20))
    assert result.cost <= best_random * (1.0 + SAME_MINIMUM), (result.cost, best_random)
    # Beckmann: Mitsuba's G1 is Walter's rational approximation (≤ 0.5%), which moves the optimum far less than 1%.
    assert result.params["m"] == pytest.approx(ALPHA, rel=0.01)
    # The index itself: eta and k trade off along the Fresnel curve, so each is near Mitsuba's, not equal to it
    # (measured: within 10%, most within 2%); the BRDF, judged below, is what is determined.
    table = METALS[metal]
    np.testing.assert_allclose(result.params["k"], table.k_rgb, rtol=0.15)
    exported = mitsuba_bsdf(result)
    at_data = mitsuba_brdf(mi.load_dict(exported.bsdf), samples.wi, samples.wo)
    # Mitsuba's Beckmann D underflows float32 far from the mirror: values of exactly 0 there have no relative error.
    measured = samples.values > 0
    relative = np.abs(at_data - samples.values)[measured] / samples.values[measured]
    assert np.median(relative) <= 0.015, np.median(relative)


@pytest.mark.heavy
def test_compare_on_mitsubas_beckmann_copper_names_a_model_whose_export_meets_the_promise():
    """``compare`` with its default candidates on Mitsuba's copper (Beckmann, the default roughconductor, alpha 0.15) on
    the renderers benchmark's hemisphere (2,592 pairs, 1% noise): its pick, exported to Mitsuba and evaluated by
    Mitsuba at the data's directions, lies within 1.5% of the data at the median (over the values the export's figure
    counts: at least 10⁻⁴ 1/sr; measured 0.72%). Before Beckmann + Smith was a default candidate it picked Ward-Dür,
    3.1% off."""
    from brdffit import compare

    wi, wo = data_synth.hemisphere_grid(6, 18, 24)
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": "beckmann", "alpha": 0.15, "material": "Cu"})
    clean = mitsuba_brdf(bsdf, wi, wo)
    noisy = clean * (1.0 + 0.01 * np.random.default_rng(1).standard_normal(clean.shape))
    samples = Samples.from_arrays(wi, wo, noisy, channels=("r", "g", "b"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the candidates' caveats
        best = compare(samples, seed=0).best.result
    exported = mitsuba_bsdf(best).compared_with(best, samples)
    assert exported.at_data.median_error <= 0.015, (best.model, best.model_options, exported.at_data.line())
