"""Several lobes fitted lobe by lobe: the default path reaches the optimum a wide search finds, real and dense."""

import warnings

import numpy as np
import pytest
from paths import TAPE

from brdffit import FitWarning, data_synth, fit, load_samples
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.starts.lobes import SAME_MINIMUM, LobeFit, distinct_minima
from brdffit.physics.geometry import spherical_to_direction

#: The lowest costs any search found on the real tape, by how its values are read: as stored (the landed code's
#: greedy starts with ``n_starts=30``; issue 11: 63.8 where its default stopped at 129.6) and as the view's
#: cosine-weighted BRDF, its right reading (this code with 3 and 30 starts, and 60 random starts). Under the l2 loss
#: lower minima exist than the default starts reach (issue 29): 30 starts find 10,173.7 for 2 lobes as stored (a
#: narrow retro lobe of albedo 5·10⁷), which 3 lobes reach too when every grid shape starts each lobe, and 12,466.7
#: for 3 lobes read cosine-weighted.
TAPE_BEST = {
    ("brdf", "log", 2): 129.6103,
    ("brdf", "log", 3): 63.8001,
    ("brdf", "l2", 2): 10173.7,
    ("brdf", "l2", 3): 10173.7,
    ("cosine-weighted-out", "log", 2): 142.2086,
    ("cosine-weighted-out", "log", 3): 75.9963,
    ("cosine-weighted-out", "l2", 2): 14672.62,
    ("cosine-weighted-out", "l2", 3): 12466.7,
}
#: Where the default fit's third lobe ends dead (the same cost as two lobes), which the fit says.
DEAD_THIRD_LOBE = {("cosine-weighted-out", "l2", 3)}
#: The caveat of a fit whose starts ended in several minima under a linear loss (``starts/lobes.py``).
MANY_MINIMA = "many local minima"


def quiet_fit(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # the tape as stored is not reciprocal; said elsewhere
        return fit(*args, **kwargs)


@pytest.mark.slow
@pytest.mark.parametrize(("quantity", "loss", "lobes"), sorted(TAPE_BEST))
def test_the_real_tape_reaches_the_best_known_optimum_by_default_or_says_it_may_not(quantity, loss, lobes):
    """Within 1% of the lowest cost known (costs differ by rounding across machines, far less than 1%), or the fit
    says that its starts ended in several minima and more starts may find a lower one (the l2 cases); under the log
    loss, which reaches it, nothing is said. A lobe that fits nothing is said."""
    result = quiet_fit(load_samples(TAPE, quantity=quantity), "lafortune", loss, lobes=lobes)
    assert result.converged
    may_not = [line for line in result.warnings if MANY_MINIMA in line]
    assert result.cost <= 1.01 * TAPE_BEST[(quantity, loss, lobes)] or may_not
    assert (loss == "log") == (not may_not)
    assert not may_not or "--starts" in may_not[0]
    dead = any("contributes less than" in line for line in result.warnings)
    assert dead == ((quantity, loss, lobes) in DEAD_THIRD_LOBE)


def test_minima_are_told_apart_by_their_relative_cost():
    """Runs within :data:`SAME_MINIMUM` of each other ended in one minimum; a failed run (non-finite) is none; only a
    loss linear in the values says so."""
    assert distinct_minima([2.0, 1.0, 1.0 + 1e-9, np.inf, 1.5, np.nan]) == [1.0, 1.5, 2.0]
    assert distinct_minima([0.0, 0.0]) == [0.0]
    l2, log = get_loss("l2"), get_loss("log")
    assert LobeFit(None, 1.0, (3.0, 3.0 * (1 + SAME_MINIMUM / 2))).caveats(l2, 3) == []
    assert LobeFit(None, 1.0, (3.0, 3.3, 3.0)).caveats(log, 5) == []
    (said,) = LobeFit(None, 1.0, (3.0, 3.3, 3.0)).caveats(l2, 5)
    assert "3 runs ended in 2 different ones" in said and "more starts than 5" in said


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
