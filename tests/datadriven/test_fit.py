"""Fitting a material's coefficients: exact where the basis holds the material, the ridge prior, uncertainty, and
every route a fit takes (start, batch, compare)."""

import numpy as np
import pytest

import brdffit
from brdffit.data.merl import bin_directions, read_merl
from brdffit.data.samples import Samples
from brdffit.datadriven.basis import load_basis, save_basis
from brdffit.datadriven.build import build_basis
from brdffit.datadriven.directions import select_bins
from brdffit.errors import BrdfInputError, FitWarning

from .conftest import ward_table


def samples_at(table: np.ndarray, bins: np.ndarray, noise: float = 0.0, seed: int = 0) -> Samples:
    wi, wo = bin_directions()
    values = table[bins] * (1 + noise * np.random.default_rng(seed).standard_normal((bins.size, 3)))
    return Samples.from_arrays(wi[bins], wo[bins], values, channels=("r", "g", "b"), source="test")


@pytest.fixture(scope="module")
def exact_basis(linear_library, tmp_path_factory):
    path = tmp_path_factory.mktemp("exact") / "exact.npz"
    save_basis(build_basis(linear_library[0], components=2, mapping="none"), path)
    return path


def test_a_material_in_the_span_is_recovered_exactly(exact_basis, linear_library):
    """A mixture the basis spans, measured at 20 selected pairs without noise, fitted with no ridge: the whole table
    comes back to 1e-5 relative (the components are stored in float32, 6e-8, amplified by the fit's conditioning)."""
    _, first, second = linear_library
    table = 0.35 * first + 1.3 * second  # outside the library's mixtures' range
    bins = select_bins(load_basis(exact_basis), 20)
    with pytest.warns(FitWarning, match="outside the library"):  # 5 mixtures have a narrow spread: it is outside
        result = brdffit.fit(samples_at(table, bins), model="pca", loss="l2", basis=str(exact_basis), ridge=0.0)
    assert result.converged
    dense = read_merl_like(table, seed=1)
    predicted = result.predict(dense.wi, dense.wo)
    np.testing.assert_allclose(predicted, dense.values, rtol=1e-5, atol=1e-9)


def read_merl_like(table: np.ndarray, seed: int, count: int = 5000) -> Samples:
    """``count`` seeded bins of ``table`` above the horizon, as samples."""
    wi, wo = bin_directions()
    above = np.flatnonzero((wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3))
    return samples_at(table, np.random.default_rng(seed).choice(above, count, replace=False))


def test_a_held_out_material_from_twenty_noisy_pairs(basis_file, library):
    """The held-out Ward table from the 20 selected pairs with 1% noise: its dense table to a median relative error
    of 5% (a Ward family basis of 6 components holds it well; measured 1.5–2%)."""
    table = ward_table(library[1][7])
    bins = select_bins(load_basis(basis_file), 20)
    result = brdffit.fit(samples_at(table, bins, noise=0.01), model="pca", basis=str(basis_file))
    assert result.converged
    dense = read_merl_like(table, seed=2)
    relative = np.abs(result.predict(dense.wi, dense.wo) - dense.values) / dense.values
    assert np.median(relative) < 0.05


def test_the_cost_is_the_residuals_squares(basis_file, library):
    samples = read_merl(library[0][7], subsample=300, seed=3)
    result = brdffit.fit(samples, model="pca", basis=str(basis_file))
    assert result.cost == pytest.approx(float(np.sum(result.residuals(samples) ** 2)), rel=1e-9)


def test_the_ridge_pulls_toward_the_library_mean(basis_file, library):
    samples = read_merl(library[0][7], subsample=40, seed=4)
    loose = brdffit.fit(samples, model="pca", basis=str(basis_file), ridge=0.0)
    tight = brdffit.fit(samples, model="pca", basis=str(basis_file), ridge=1e3)
    norm = lambda result: np.linalg.norm(result.params["coefficients"])
    assert norm(tight) < 0.1 * norm(loose)
    assert tight.cost > loose.cost


def test_the_curvature_holds_the_ridge(basis_file, library):
    """Laplace's JᵀJ is the data's plus ``prior_weight·I`` (the prior's residuals are linear, so exactly; 1e-9 for
    the data part summed in another order); the cost the sampler sees holds the prior, and the prior's terms count
    as values that share the noise."""
    from brdffit.physics.models.registry import get_model
    from brdffit.uncertainty.density import compiled_chi_squared, counted_values, density_of
    from brdffit.uncertainty.laplace import gauss_newton_matrix

    samples = read_merl(library[0][7], subsample=60, seed=5)
    result = brdffit.fit(samples, model="pca", basis=str(basis_file), ridge=0.5)
    density = density_of(result, samples)
    weight = density.model.prior_weight
    assert weight == pytest.approx(0.5 * result.model_options["ridge_scale"])
    without = get_model("pca", **{**result.model_options, "ridge": 0.0})
    assert without == density.model  # one compiled program for both: the ridge is data
    v = np.asarray(density.optimum)
    with_ridge = gauss_newton_matrix(density, v)
    data_only = gauss_newton_matrix(density._replace(model=without), v)
    np.testing.assert_allclose(with_ridge - data_only, weight * np.eye(v.size), atol=1e-9)
    chi2 = float(compiled_chi_squared(density.model, density.loss)(v, density.problem, weight))
    assert chi2 == pytest.approx(result.cost + weight * np.sum(v**2), rel=1e-9)
    assert counted_values(density) == density.n_values + v.size
    assert counted_values(density._replace(model=without)) == density.n_values


@pytest.mark.filterwarnings("ignore::brdffit.errors.UncertaintyWarning")
def test_fewer_values_than_coefficients(basis_file, library):
    """4 pairs × 3 channels for 18 coefficients: the prior determines what the data cannot, so the fit runs and
    Laplace's errors are finite (the prior's terms count as values); without a ridge it is refused."""
    samples = read_merl(library[0][7], subsample=4, seed=9)
    result = brdffit.fit(samples, model="pca", basis=str(basis_file), uncertainty="laplace")
    assert np.all(np.isfinite(np.array(result.uncertainty["stderr"]["coefficients"])))
    with pytest.raises(BrdfInputError, match="cannot determine"):
        brdffit.fit(samples, model="pca", basis=str(basis_file), ridge=0.0)


@pytest.mark.filterwarnings("ignore::brdffit.errors.UncertaintyWarning")
def test_mcmc_samples_the_coefficients(basis_file, library):
    samples = read_merl(library[0][7], subsample=60, seed=6)
    settings = brdffit.MCMC(walkers=40, steps=60, burn=20, seed=1)
    result = brdffit.fit(samples, model="pca", basis=str(basis_file), uncertainty="mcmc", mcmc=settings)
    assert result.draws.shape[1] == 6 * 3
    assert np.all(np.isfinite(result.draws))


@pytest.mark.slow
def test_start_batch_and_compare(basis_file, library):
    samples = [read_merl(path, subsample=200, seed=7) for path in library[0][6:8]]
    first = brdffit.fit(samples[0], model="pca", basis=str(basis_file))
    again = brdffit.fit(samples[0], model="pca", basis=str(basis_file), start=first.params)
    np.testing.assert_allclose(again.params["coefficients"], first.params["coefficients"], atol=1e-6)
    batch = brdffit.fit_batch(samples, model="pca", basis=str(basis_file), progress=False)
    np.testing.assert_allclose(batch[0].params["coefficients"], first.params["coefficients"], atol=1e-9)
    started = brdffit.fit_batch(samples, model="pca", basis=str(basis_file), start=first.params, progress=False)
    np.testing.assert_allclose(started[0].params["coefficients"], again.params["coefficients"], atol=1e-9)
    comparison = brdffit.compare(samples[1], models=["ward", f"pca:basis={basis_file}"], folds=3)
    scores = {score.spec.partition(":")[0]: score for score in comparison.models}
    assert scores["pca"].k == 18 and np.isfinite(scores["pca"].cv_loss)


def test_a_start_of_other_channels(basis_file, library):
    samples = read_merl(library[0][7], subsample=50, seed=8)
    with pytest.raises(BrdfInputError, match="channel"):
        brdffit.fit(samples, model="pca", basis=str(basis_file), start={"coefficients": [[0.0]] * 6})


def test_float32_is_refused(basis_file, library):
    samples = read_merl(library[0][7], subsample=50, seed=8)
    with pytest.raises(BrdfInputError, match="dtype=float32 does not apply to model pca"):
        brdffit.fit(samples, model="pca", basis=str(basis_file), dtype="float32")
