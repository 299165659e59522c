"""Several lobes fitted lobe by lobe: the default path reaches the optimum a wide search finds, real and dense."""

import warnings

import numpy as np
import pytest
from paths import TAPE

import data_synth
from brdffit import FitWarning, fit, load_samples
from brdffit.physics.geometry import spherical_to_direction

#: The lowest costs any search found on the real tape (values as stored): the landed code's greedy starts with
#: ``n_starts=30`` (issue 11: 63.8 where its default stopped at 129.6) and this code with 3 and 30 starts.
TAPE_BEST = {("log", 2): 129.6103, ("log", 3): 63.8001, ("l2", 2): 14973.5, ("l2", 3): 14417.9}


def quiet_fit(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # the tape as stored is not reciprocal; said elsewhere
        return fit(*args, **kwargs)


@pytest.mark.skipif(not TAPE.exists(), reason=f"{TAPE} absent (../shared/data is not part of the project)")
@pytest.mark.parametrize(("loss", "lobes"), sorted(TAPE_BEST))
def test_the_real_tape_reaches_the_best_known_optimum_by_default(loss, lobes):
    """Within 1% of the lowest cost known (costs differ by rounding across machines, far less than 1%)."""
    result = quiet_fit(load_samples(TAPE), "lafortune", loss, lobes=lobes)
    assert result.converged and result.cost <= 1.01 * TAPE_BEST[(loss, lobes)]
    assert not any("contributes less than" in line for line in result.warnings)  # no dead lobe on the way


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
