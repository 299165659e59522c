"""The start search's parts (``fitting/starts/grid.py``): the non-negative least squares of its albedos, and the
grid starts of stacked datasets, each dataset's own."""

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

from brdffit import LobeModel, MappedLobe, Params, Samples, data_synth, get_model
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.objective.problem import build_problems
from brdffit.fitting.starts.grid import grid_starts, nonnegative_least_squares
from brdffit.physics.domains import ALBEDO
from brdffit.physics.models.ward import WardLobe


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


@dataclass(frozen=True)
class HalfLambertian(MappedLobe):
    """A diffuse term of half Lambert's value, ``1/(2π)``: a parameter-free diffuse term other than the built-in one."""

    summary = "1/(2π)"
    albedo_domain = ALBEDO
    peaks_at_mirror = True

    @property
    def parameters(self):
        return ()

    @property
    def grid(self):
        return ({},)

    def __call__(self, shape, wi, wo):
        return jnp.full(wi.shape[:1], 0.5 / jnp.pi, wi.dtype)


def test_the_starts_ask_the_models_diffuse_term():
    """Noise-free Ward data with a half-Lambertian diffuse term, at a shape of the grid: the start's albedos are the
    data's (0.4, 0.05), as with Lambert's term, not what they would be if the start search wrote the diffuse term as
    1/π (0.18, measured before the search asked the model)."""
    model = LobeModel("ward-half", "Ward with a half-Lambertian diffuse term", WardLobe(), 1, diffuse=HalfLambertian())
    params = Params(np.array([0.4]), np.array([[0.05]]), {"alpha": np.array([0.15])})  # 0.15: on the grid
    wi, wo = data_synth.hemisphere_grid(6, 12, 12)
    samples = Samples.from_arrays(wi, wo, model.host_brdf(params, wi, wo))
    (theta,) = np.asarray(grid_starts(model, get_loss("l2"), 1, build_problems([samples])))[0]
    start = model.unconstrained.to_params(theta, 1)
    # Exact but for the least squares' relative ridge of 1e-12 and float64 rounding.
    assert float(start.diffuse[0]) == pytest.approx(0.4, rel=1e-9)
    assert float(start.specular[0, 0]) == pytest.approx(0.05, rel=1e-9)
