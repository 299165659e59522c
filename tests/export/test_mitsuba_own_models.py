"""Mitsuba's own models, fitted and exported back (issue 28, part 3): data made by Mitsuba 3's ``principled`` (a
plastic, a clear-coated paint, a metal) and ``roughplastic`` (Beckmann and GGX), 1% noise.

The default fit of brdffit's model of the same name (Mitsuba's BRDF in JAX, ``physics/renderers/``) reaches the best
cost 20 random starts find, gives the parameters back, and, exported to Mitsuba, is the same BSDF: it evaluates at
the data's directions within 1.5% (median) of the data, whose noise is 1%.
"""

import warnings

import numpy as np
import pytest
from test_mitsuba import mitsuba_brdf

from brdffit import Samples, data_synth, fit
from brdffit.export.mitsuba import mitsuba_bsdf

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install 'brdffit[render]')")
mi.set_variant("scalar_rgb")

#: (brdffit's model and options, Mitsuba's plugin parameters, the colour's name in both) by material.
MATERIALS = {
    "principled plastic": (
        ("principled", {}),
        {"type": "principled", "base_color": [0.8, 0.3, 0.1], "roughness": 0.4, "metallic": 0.0, "specular": 0.5},
        "base_color",
    ),
    "principled clear-coated paint": (
        ("principled", {}),
        {
            "type": "principled",
            "base_color": [0.2, 0.3, 0.6],
            "roughness": 0.5,
            "metallic": 0.1,
            "specular": 0.6,
            "clearcoat": 0.8,
            "clearcoat_gloss": 0.9,
        },
        "base_color",
    ),
    "principled copper": (
        ("principled", {}),
        {"type": "principled", "base_color": [0.95, 0.64, 0.54], "roughness": 0.25, "metallic": 1.0},
        "base_color",
    ),
    "roughplastic beckmann": (
        ("roughplastic", {}),
        {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.1, "diffuse_reflectance": [0.8, 0.3, 0.1]},
        "diffuse_reflectance",
    ),
    "roughplastic ggx": (
        ("roughplastic", {"distribution": "ggx", "int_ior": 1.6}),
        {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": 0.3,
            "int_ior": 1.6,
            "diffuse_reflectance": [0.2, 0.3, 0.6],
        },
        "diffuse_reflectance",
    ),
}
LIGHT = ("principled clear-coated paint", "roughplastic ggx")
CASES = [pytest.param(name, marks=() if name in LIGHT else pytest.mark.heavy) for name in MATERIALS]
#: Two fits that end at one minimum agree to the solver's stopping tolerance on the cost's relative change (1e-8 per
#: step, and a few steps' worth): a random start that finds a lower cost by more than 1e-6 found another minimum.
SAME_MINIMUM = 1e-6
#: What one random start may hold: each parameter the fit moves by default, anywhere in its range.
RANDOM_RANGES = {
    "principled": {
        name: (0.02, 0.98) for name in ("roughness", "metallic", "specular", "clearcoat", "clearcoat_gloss")
    },
    "roughplastic": {"alpha": (0.01, 0.8)},
}
HELD = {
    "principled": {name: 0.0 for name in ("spec_tint", "sheen", "sheen_tint", "anisotropic")},
    "roughplastic": {"specular_reflectance": [1.0, 1.0, 1.0]},
}


def mitsuba_dict(parameters: dict, colour: str) -> dict:
    """Mitsuba's dictionary of a material: its colour as an ``rgb`` value."""
    return parameters | {colour: {"type": "rgb", "value": parameters[colour]}}


def mitsuba_data(parameters: dict, colour: str) -> Samples:
    """Mitsuba's BRDF at 1,500 directions uniform in solid angle and 1,500 near the mirror (the lobes), with 1%
    Gaussian noise (seed 1)."""
    wi, wo = data_synth.uniform_random(1500, seed=5)
    near_wi, near_wo = data_synth.near_specular(6, 1500, spread=20.0, seed=6)
    wi, wo = np.vstack([wi, near_wi]), np.vstack([wo, near_wo])
    clean = mitsuba_brdf(mi.load_dict(mitsuba_dict(parameters, colour)), wi, wo)
    noisy = clean * (1.0 + 0.01 * np.random.default_rng(1).standard_normal(clean.shape))
    return Samples.from_arrays(wi, wo, noisy, channels=("r", "g", "b"))


def random_start(model: str, colour: str, rng) -> dict:
    """A start anywhere in the fitted parameters' box (the held ones at their defaults)."""
    start = {name: float(rng.uniform(*bounds)) for name, bounds in RANDOM_RANGES[model].items()}
    return start | HELD[model] | {colour: [float(x) for x in rng.uniform(0.02, 0.98, 3)]}


@pytest.mark.slow
@pytest.mark.parametrize("name", CASES)
def test_mitsubas_own_model_is_fitted_and_exported_back_unchanged(name):
    (model, options), parameters, colour = MATERIALS[name]
    samples = mitsuba_data(parameters, colour)
    result = fit(samples, model, **options)
    assert result.converged and result.warnings == []
    rng = np.random.default_rng(7)
    with warnings.catch_warnings():  # a random start may end anywhere, implausible values and all: said, not raised
        warnings.simplefilter("ignore")
        starts = [random_start(model, colour, rng) for _ in range(20)]
        best_random = min(fit(samples, model, start=start, **options).cost for start in starts)
    assert result.cost <= best_random * (1.0 + SAME_MINIMUM), (result.cost, best_random)
    # 3,000 pairs × 3 channels at 1% noise: the colour and the roughness within ~1% (measured: ≤ 0.2%).
    np.testing.assert_allclose(result.params[colour], parameters[colour], rtol=0.01)
    roughness = "alpha" if model == "roughplastic" else "roughness"
    assert result.params[roughness] == pytest.approx(parameters[roughness], rel=0.01)
    exported = mitsuba_bsdf(result)
    assert exported.exact and exported.bsdf["type"] == model
    assert exported.bsdf[roughness] == result.params[roughness]  # the numbers unchanged
    at_data = mitsuba_brdf(mi.load_dict(exported.bsdf), samples.wi, samples.wo)
    seen = samples.values > 0  # Mitsuba's Beckmann D is 0 where D·cos θh ≤ 1e-20: no relative error there
    relative = np.abs(at_data - samples.values)[seen] / samples.values[seen]
    assert np.median(relative) <= 0.015, np.median(relative)
    # The fit evaluated by brdffit and by Mitsuba: one BSDF, to float32's precision (Mitsuba's scalar_rgb), the
    # clear coat's float32 cancellation near the normal (test_principled.py: 1.6e-3 at its peak) and the rough
    # plastic's tables interpolated in alpha (test_roughplastic.py: 2e-3 on the diffuse term).
    np.testing.assert_allclose(at_data, result.predict(samples.wi, samples.wo), rtol=3e-3, atol=1e-6)
