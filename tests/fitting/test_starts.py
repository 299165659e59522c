"""The start search's parts (``fitting/starts/grid.py``): the non-negative least squares of its albedos, and the
grid starts of stacked datasets, each dataset's own."""

import numpy as np
import pytest
import scipy.optimize

import data_synth
from brdffit import get_model
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.objective.problem import build_problems
from brdffit.fitting.starts.grid import grid_starts, nonnegative_least_squares


@pytest.mark.parametrize("n_basis", [1, 2, 3, 5])
def test_nonnegative_least_squares_equals_scipy_nnls(rng, n_basis):
    """On 50 random systems per size, some with an active bound, the support enumeration finds scipy's
    (Lawson-Hanson) solution. Tolerance: the ridge of 1e-12·trace moves x by ~1e-12 × the condition number
    (below 1e3 here) relative to |x|."""
    designs = rng.standard_normal((50, 40, n_basis))
    coefficients = rng.standard_normal((50, n_basis))  # about half negative: their bounds are active
    targets = np.einsum("dni,di->dn", designs, coefficients) + 0.3 * rng.standard_normal((50, 40))
    gram = np.einsum("dni,dnj->dij", designs, designs)
    rhs = np.einsum("dni,dn->di", designs, targets)
    found = np.asarray(nonnegative_least_squares(gram, rhs))
    expected = np.stack([scipy.optimize.nnls(a, b)[0] for a, b in zip(designs, targets, strict=True)])
    assert np.any(expected == 0.0) or n_basis == 1  # some bounds are active
    np.testing.assert_allclose(found, expected, atol=1e-8 * np.max(np.abs(expected)))
    assert np.all(found >= 0.0)


def test_stacked_grid_starts_are_each_datasets_own():
    """The grid search of three stacked datasets (one program) gives each the start it gets alone."""
    model, loss = get_model("ward"), get_loss("log")
    wi, wo = data_synth.uniform_random(300, seed=2)
    datasets = [
        data_synth.synthesize("ward", {"rho_d": [d] * 3, "rho_s": [s] * 3, "alpha": a}, wi, wo, noise=0.01, seed=i)
        for i, (d, s, a) in enumerate([(0.1, 0.05, 0.08), (0.4, 0.2, 0.3), (0.2, 0.5, 0.15)])
    ]
    together = grid_starts(model, loss, 2, build_problems(datasets, "float64", 3))
    assert together.shape == (3, 2, model.unconstrained.size(3))
    for index, samples in enumerate(datasets):
        alone = grid_starts(model, loss, 2, build_problems([samples], "float64", 1))
        np.testing.assert_allclose(together[index], alone[0], rtol=1e-12, atol=1e-12)
