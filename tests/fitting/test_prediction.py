"""The 1-σ band of a fit's prediction (``FitResult.eval_uncertainty``, lmfit's name): the delta method, checked against
an albedo's exact band and against derivatives taken by finite differences of the public ``evaluate``."""

import numpy as np
import pytest
from paths import EXAMPLE

import brdffit
from brdffit import data_synth


@pytest.fixture(scope="module")
def oak():
    samples = brdffit.load_samples(EXAMPLE)
    with pytest.warns(brdffit.UncertaintyWarning):  # the robust errors replace the Gauss-Newton ones: said
        return samples, brdffit.fit(samples, "ward", uncertainty="laplace")


def test_a_lambertian_band_is_its_albedos_error_over_pi():
    """``f = rho_d/π`` is linear in its one parameter per channel: the band is ``stderr(rho_d)/π`` exactly (to float64
    rounding), at every direction."""
    samples = data_synth.synthesize(
        "lambert", {"rho_d": [0.2, 0.5]}, *data_synth.uniform_random(400, seed=1), noise=0.01, seed=2
    )
    result = brdffit.fit(samples, "lambert", uncertainty="laplace")
    band = result.eval_uncertainty(samples.wi[:5], samples.wo[:5])
    expected = np.asarray(result.uncertainty["stderr"]["rho_d"]) / np.pi
    np.testing.assert_allclose(band, np.broadcast_to(expected, band.shape), rtol=1e-12)
    np.testing.assert_allclose(result.eval_uncertainty(samples.wi[:5], samples.wo[:5], sigma=2), 2 * band, rtol=1e-15)


def test_a_ward_band_is_the_covariance_carried_by_finite_differences(oak):
    """The band of the oak example's Ward fit at 50 pairs, against ``sqrt(diag(J C Jᵀ))`` with ``J`` by central
    differences of ``brdffit.evaluate`` in each physical parameter (step 1e-6 of its value: the difference's
    truncation error, ~1e-12 relative, and its rounding, ~1e-10, are far below the 1e-6 asked)."""
    samples, result = oak
    wi, wo = samples.wi[::200][:50], samples.wo[::200][:50]
    names = result.uncertainty["covariance"]["names"]
    covariance = np.asarray(result.uncertainty["covariance"]["matrix"], dtype=float)
    flat = [*result.params["rho_d"], *result.params["rho_s"], result.params["alpha"]]
    assert names == ["rho_d[r]", "rho_d[g]", "rho_d[b]", "rho_s[r]", "rho_s[g]", "rho_s[b]", "alpha"]

    def values(vector):
        params = {"rho_d": list(vector[:3]), "rho_s": list(vector[3:6]), "alpha": vector[6]}
        return brdffit.evaluate("ward", params, wi, wo)

    columns = []
    for index, value in enumerate(flat):
        step = 1e-6 * abs(value)
        up, down = np.array(flat, dtype=float), np.array(flat, dtype=float)
        up[index] += step
        down[index] -= step
        columns.append((values(up) - values(down)) / (2 * step))
    jacobian = np.stack(columns, axis=-1)  # (N, C, p)
    expected = np.sqrt(np.einsum("ncp,pq,ncq->nc", jacobian, covariance, jacobian))
    np.testing.assert_allclose(result.eval_uncertainty(wi, wo), expected, rtol=1e-6)


def test_a_result_without_an_estimate_is_one_line(oak):
    samples, _ = oak
    result = brdffit.fit(samples, "lambert")
    with pytest.raises(
        brdffit.BrdfInputError, match=r"^this result has no uncertainty estimate: fit with uncertainty="
    ):
        result.eval_uncertainty(samples.wi[:2], samples.wo[:2])
