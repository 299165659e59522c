"""The start search's parts (``fitting/starts/grid.py``): the non-negative least squares of its albedos, and the
grid starts of stacked datasets, each dataset's own."""

from dataclasses import dataclass

import jax
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


@pytest.mark.slow
@pytest.mark.parametrize(
    ("options", "fixed", "bounds"),
    [
        ({"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"}, None, None),
        ({"fresnel": "conductor", "shadowing": "smith"}, {"eta": [1.5, 1.2, 0.9]}, {"m": [0.05, 0.2]}),
        ({"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith", "anisotropic": True}, None, None),
        ({"fresnel": "conductor", "anisotropic": True}, {"ks": None}, {"k": [0.5, 4.0], "alpha_u": [0.02, 0.3]}),
    ],
)
def test_a_separable_lobes_search_equals_the_whole_lobes(monkeypatch, options, fixed, bounds):
    """A conductor's grid searched by its distinct factors (``_Separated``: each microfacet term and each index once)
    scores every grid shape as the search of whole lobes does, holds and all. Tolerance: the two sum the same terms in
    another order (``Σ w F² U²`` against ``Σ w (F U)²``), a few ulps a term over ~10³ terms: 1e-11 relative."""
    from brdffit.fitting.single.constraints import constraints_for
    from brdffit.fitting.starts import grid

    model = get_model("cook-torrance", **options)
    truth = {"kd": [0.1, 0.05, 0.02], "ks": [1.0] * 3, "eta": [0.2, 0.9, 1.1], "k": [3.5, 2.6, 2.3]}
    truth |= {"alpha_u": 0.05, "alpha_v": 0.2, "phi_t": 30.0} if options.get("anisotropic") else {"m": 0.1}
    wi, wo = data_synth.uniform_random(400, seed=3)
    samples = data_synth.synthesize(model, truth, wi, wo, noise=0.01, seed=4)
    problem = build_problems([samples])
    constraints = constraints_for(model, 3, fixed, bounds)
    hold = None if constraints is None else jax.tree.map(lambda leaf: jnp.asarray(leaf)[None], constraints.hold())
    channels = grid.grid_channels(model, samples.channels)
    assert grid._Separated.of(model, grid._grid(model, channels), {}, (400, 3)) is not None
    first = lambda tree: None if tree is None else jax.tree.map(lambda leaf: leaf[0], tree)  # the one dataset's
    search = lambda: jax.jit(lambda p, h: grid.grid_starts(model, get_loss("log"), 5, p, h, channels))(problem, hold)
    candidates = lambda: jax.jit(lambda p, h: grid._candidates(model, get_loss("log"), p, h, {}, channels))(
        first(problem), first(hold)
    )
    separated, separated_starts = candidates(), search()
    monkeypatch.setattr(grid, "SEPARATED_BYTES", 0)  # every lobe whole
    jax.clear_caches()  # grid_starts' inner jit keeps its trace: traced again, with the whole lobes
    try:
        whole, whole_starts = candidates(), search()
    finally:
        jax.clear_caches()  # no later test inherits the whole lobes' trace
    np.testing.assert_allclose(separated[0], whole[0], rtol=1e-11)
    np.testing.assert_allclose(separated[1], whole[1], rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(separated_starts, whole_starts, rtol=1e-11, atol=1e-11)
