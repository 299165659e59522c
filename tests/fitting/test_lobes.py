"""Several lobes fitted lobe by lobe: the default path reaches the optimum a wide search finds, real and dense."""

import warnings

import numpy as np
import pytest
from paths import TAPE

import data_synth
from brdffit import FitWarning, fit, load_samples
from brdffit.physics.geometry import spherical_to_direction

#: The lowest costs any search found on the real tape, by how its values are read: as stored (the landed code's
#: greedy starts with ``n_starts=30``; issue 11: 63.8 where its default stopped at 129.6) and as the view's
#: cosine-weighted BRDF, its right reading (this code with 3 and 30 starts, and 60 random starts, which found
#: nothing lower). With that reading the l2 loss leaves a third lobe dead: the fit warns, tested below.
TAPE_BEST = {
    ("brdf", "log", 2): 129.6103,
    ("brdf", "log", 3): 63.8001,
    ("brdf", "l2", 2): 14973.5,
    ("brdf", "l2", 3): 14417.9,
    ("cosine-weighted-out", "log", 2): 142.2086,
    ("cosine-weighted-out", "log", 3): 75.9963,
    ("cosine-weighted-out", "l2", 2): 14672.62,
    ("cosine-weighted-out", "l2", 3): 14672.62,
}


def quiet_fit(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # the tape as stored is not reciprocal; said elsewhere
        return fit(*args, **kwargs)


@pytest.mark.parametrize(("quantity", "loss", "lobes"), sorted(TAPE_BEST))
def test_the_real_tape_reaches_the_best_known_optimum_by_default(quantity, loss, lobes):
    """Within 1% of the lowest cost known (costs differ by rounding across machines, far less than 1%). A lobe
    that fits nothing is said: only where a third lobe adds nothing at the optimum (the same cost as two)."""
    result = quiet_fit(load_samples(TAPE, quantity=quantity), "lafortune", loss, lobes=lobes)
    assert result.converged and result.cost <= 1.01 * TAPE_BEST[(quantity, loss, lobes)]
    dead = any("contributes less than" in line for line in result.warnings)
    adds_nothing = lobes == 3 and TAPE_BEST[(quantity, loss, 3)] >= 0.999 * TAPE_BEST[(quantity, loss, 2)]
    assert dead == adds_nothing


def dense_tape():
    """A dense, tape-like measurement: the real tape's 3-lobe fit as the truth (a sharp retro lobe, a broad one
    and a forward one over a Lambertian base), four light zeniths, the view every degree and every 2° of azimuth,
    denser near the retro direction as the real measurement is; 80,032 samples, 5% noise."""
    truth = {
        "rho_d": [0.29],
        "lobes": [
            {"rho_s": [0.254], "cxy": 0.577, "cz": 0.578, "n": 2945.0},
            {"rho_s": [0.196], "cxy": -0.58, "cz": 0.571, "n": 36.8},
            {"rho_s": [0.1355], "cxy": 0.572, "cz": 0.588, "n": 108.4},
        ],
    }
    theta_l = np.radians([15.0, 30.0, 45.0, 60.0])
    light, view, azimuth = np.meshgrid(
        theta_l, np.radians(np.arange(0.5, 88, 1.0)), np.radians(np.arange(0, 181, 2.0)), indexing="ij"
    )
    rng = np.random.default_rng(3)
    near_l = np.repeat(theta_l, 12000)
    near_v = near_l + rng.normal(0, np.radians(3), near_l.size)
    near_p = np.abs(rng.normal(0, np.radians(6), near_l.size))
    keep = (near_v > 0) & (near_v < np.radians(88))
    wi = np.vstack(
        [
            spherical_to_direction(light.ravel(), 0 * light.ravel()),
            spherical_to_direction(near_l[keep], 0 * near_l[keep]),
        ]
    )
    wo = np.vstack(
        [spherical_to_direction(view.ravel(), azimuth.ravel()), spherical_to_direction(near_v[keep], near_p[keep])]
    )
    return data_synth.synthesize("lafortune", truth, wi, wo, noise=0.05, seed=7, lobes=3), truth


@pytest.mark.heavy
@pytest.mark.parametrize("loss", ["l2", "log"])
@pytest.mark.parametrize("lobes", [2, 3])
def test_dense_tape_like_data_reach_the_wide_searchs_optimum(loss, lobes):
    """The landed code's greedy starts stopped 1.5–1.9% above the optimum here with the l2 loss; the default path
    must come within 1% of the best of 30 starts and, for 3 lobes, of a fit started at the truth."""
    samples, truth = dense_tape()
    default = quiet_fit(samples, "lafortune", loss, lobes=lobes)
    references = [quiet_fit(samples, "lafortune", loss, lobes=lobes, n_starts=30).cost]
    if lobes == 3:
        references.append(quiet_fit(samples, "lafortune", loss, lobes=3, start=truth).cost)
    assert default.cost <= 1.01 * min(references)
