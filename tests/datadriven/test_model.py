"""The pca model: its evaluation in JAX and on the host, physics, derivatives, parameters and options."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import brdffit
from brdffit.errors import BrdfInputError
from brdffit.physics.models.registry import get_model
from tests.conftest import random_directions


@pytest.fixture(scope="module")
def model(basis_file):
    return get_model("pca", basis=str(basis_file))


def coefficients(model, rng, channels=3):
    return rng.normal(0, 1, (model.n_components, channels))


def test_jax_and_host_agree(model):
    """The JAX path (a host callback for the basis, the blend in JAX) and the host path compute the same
    numbers (1e-12: the same operations in another order)."""
    rng = np.random.default_rng(0)
    wi, wo = random_directions(rng, 400), random_directions(rng, 400)
    c = coefficients(model, rng)
    params = model.dictionary.to_params({"coefficients": c.tolist()})
    in_jax = np.asarray(jax.jit(model.brdf)(params, jnp.asarray(wi), jnp.asarray(wo)))
    np.testing.assert_allclose(in_jax, model.host_brdf(params, wi, wo), rtol=1e-12, atol=1e-14)


def test_reciprocal_and_isotropic(model):
    """Swapping light and viewer, or turning both about the normal, gives the same values: the table's angles are
    reciprocal and azimuth-free (rounding of the angles: 1e-9 relative)."""
    rng = np.random.default_rng(1)
    wi, wo = random_directions(rng, 500), random_directions(rng, 500)
    c = coefficients(model, rng).tolist()
    values = brdffit.evaluate(model, {"coefficients": c}, wi, wo)
    np.testing.assert_allclose(brdffit.evaluate(model, {"coefficients": c}, wo, wi), values, rtol=1e-9, atol=1e-12)
    turn = 0.7
    rotation = np.array([[np.cos(turn), -np.sin(turn), 0], [np.sin(turn), np.cos(turn), 0], [0, 0, 1]])
    turned = brdffit.evaluate(model, {"coefficients": c}, wi @ rotation.T, wo @ rotation.T)
    np.testing.assert_allclose(turned, values, rtol=1e-9, atol=1e-12)


def test_finite_and_non_negative_to_the_horizon(model):
    rng = np.random.default_rng(2)
    wi, wo = random_directions(rng, 2000, min_cos=1e-9), random_directions(rng, 2000, min_cos=1e-9)
    values = brdffit.evaluate(model, {"coefficients": (3 * coefficients(model, rng)).tolist()}, wi, wo)
    assert np.all(np.isfinite(values)) and np.all(values >= 0)
    below = wi.copy()
    below[:, 2] *= -1
    assert np.all(brdffit.evaluate(model, {"coefficients": coefficients(model, rng).tolist()}, below, wo) == 0)


def test_mean_material_at_zero_coefficients(model, library):
    """Coefficients 0 give the library's mean in the mapped space: at a bin, exactly the map's inverse of the
    mean there (the blend has one corner)."""
    from brdffit.data.merl import bin_directions
    from brdffit.datadriven.basis import bin_cosine_weights
    from brdffit.datadriven.mapping import unmapped

    wi, wo = bin_directions()
    chosen = np.array([30 * 16200 + 20 * 180 + 40, 10 * 16200 + 45 * 180 + 90])
    zero = {"coefficients": np.zeros((model.n_components, 1)).tolist()}
    values = brdffit.evaluate(model, zero, wi[chosen], wo[chosen])
    basis = model.basis
    expected = unmapped(basis.mapping, basis.mean[chosen], basis.reference[chosen], bin_cosine_weights()[chosen])
    np.testing.assert_allclose(values[:, 0], expected, rtol=1e-9)


def test_derivatives_match_finite_differences(model):
    """∂f/∂c by forward mode against central differences (step 1e-6: error ~1e-10 relative, tolerance 1e-6)."""
    rng = np.random.default_rng(3)
    wi, wo = jnp.asarray(random_directions(rng, 50)), jnp.asarray(random_directions(rng, 50))
    c0 = coefficients(model, rng, 1).ravel()

    def f(v):
        return model.brdf(model.sampling.to_params(v, 1), wi, wo).ravel()

    jacobian = np.asarray(jax.jacfwd(f)(jnp.asarray(c0)))
    step = 1e-6
    for k in range(c0.size):
        up, down = c0.copy(), c0.copy()
        up[k] += step
        down[k] -= step
        numeric = (np.asarray(f(jnp.asarray(up))) - np.asarray(f(jnp.asarray(down)))) / (2 * step)
        np.testing.assert_allclose(jacobian[:, k], numeric, rtol=1e-6, atol=1e-9)


def test_parameter_forms(model):
    rng = np.random.default_rng(4)
    c = coefficients(model, rng)
    params = model.dictionary.to_params({"coefficients": c.tolist()})
    assert model.dictionary.from_params(params) == {"coefficients": c.tolist()}
    vector = model.physical.from_params(params)
    np.testing.assert_array_equal(model.physical.to_params(vector, 3).specular, c)
    labels = model.physical.labels(("r", "g", "b"))
    assert labels[:4] == ["coefficients[0][r]", "coefficients[0][g]", "coefficients[0][b]", "coefficients[1][r]"]
    assert len(labels) == model.unconstrained.size(3) == c.size


@pytest.mark.parametrize(
    "params, message",
    [
        ({"rho_d": [0.1]}, "coefficients"),
        ({"coefficients": [[0.1], [0.2]]}, "must be 6 lists"),
        ({"coefficients": [["a"]] * 6}, "lists of numbers"),
        ({"coefficients": [[float("nan")]] * 6}, "finite"),
    ],
)
def test_bad_parameters(model, params, message):
    with pytest.raises(BrdfInputError, match=message):
        model.dictionary.to_params(params)


def test_options_and_their_errors(basis_file, tmp_path):
    with pytest.raises(BrdfInputError, match="needs basis"):
        get_model("pca")
    with pytest.raises(BrdfInputError, match="ridge"):
        get_model("pca", basis=str(basis_file), ridge=-1)
    with pytest.raises(BrdfInputError, match="SHA-256 differs"):
        get_model("pca", basis=str(basis_file), basis_sha256="0" * 64)
    with pytest.raises(BrdfInputError, match="basis file's path, got Basis"):
        get_model("pca", basis=get_model("pca", basis=str(basis_file)).basis)
    built = get_model("pca", basis=str(basis_file), ridge=0.5)
    assert built.model_options["ridge"] == 0.5 and len(built.model_options["basis_sha256"]) == 64
    assert built == get_model("pca", basis=str(basis_file), ridge=0.5)  # hashable, equal by options (JAX static)
    assert "array(" not in repr(built)  # the basis's arrays stay out of the repr (stored programs' names)


def test_pickled_it_is_its_options(model):
    """A Dask worker gets the model as a few bytes and reads the basis itself (checked by its digest)."""
    import pickle

    data = pickle.dumps(model)
    assert len(data) < 2_000
    again = pickle.loads(data)
    assert again == model and again.model_options == model.model_options


def test_evaluated_in_a_float32_process(basis_file):
    """In a process without float64 (a user's), the JAX path runs on XLA's threads, where a float64 callback
    result would be refused: the basis crosses as float32 pairs (a regression: the sphere renderer failed)."""
    import subprocess
    import sys

    code = f"""
import jax, jax.numpy as jnp, numpy as np
from brdffit.physics.models.registry import get_model
model = get_model("pca", basis={str(basis_file)!r})
rng = np.random.default_rng(0)
v = rng.normal(size=(200_000, 3)); v[:, 2] = np.abs(v[:, 2]); v /= np.linalg.norm(v, axis=1, keepdims=True)
params = model.dictionary.to_params({{"coefficients": np.zeros((model.n_components, 3)).tolist()}})
values = jax.jit(model.brdf)(params, jnp.asarray(v), jnp.asarray(v[::-1]))
assert values.dtype == jnp.float32 and bool(jnp.all(jnp.isfinite(values))), values.dtype
print("ok")
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "ok" in done.stdout, done.stderr[-2000:]
