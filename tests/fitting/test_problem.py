"""Padding, chunks and the one-pass normal equations against a directly formed Jacobian."""

import sys
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from catalogue import CASES, parametrize_cases

import brdffit
from brdffit import data_synth, get_model
from brdffit.data.samples import Samples
from brdffit.fitting.objective.losses import LOSSES, get_loss
from brdffit.fitting.objective.problem import (
    CHUNK,
    build_problem,
    chunk_size,
    cost,
    normal_equations,
    padded_size,
    prepared,
    residuals,
)

problem_module = sys.modules["brdffit.fitting.objective.problem"]


@pytest.mark.parametrize("n", [1, 7, 8, 15, 16, 17, 100, 1000, 10368, 65537, 1_458_000])
def test_bucketed_sizes(n):
    """At most 1/8 padding (beyond 16 samples), and chunks of at most CHUNK rows that divide the size."""
    size = padded_size(n)
    assert n <= size <= max(16, n * 9 / 8)
    chunk = chunk_size(size)
    assert size % chunk == 0 and chunk <= max(CHUNK, size if size <= CHUNK else 0)


def assert_normal_equations_match(model, options, params, loss_name):
    """rᵀr, Jᵀr and JᵀJ from the chunked basis form equal those of jax.jacfwd over the padded residual vector.

    3000 samples pad to 3072 rows; with chunks of 256 rows (set by the callers) the pass runs over 12 chunks,
    and the 72 padded rows must add nothing. Tolerance: sums of ~10⁴ terms in another order, a few ulp each."""
    built, loss = get_model(model, **options), get_loss(loss_name)
    wi, wo = data_synth.uniform_random(3000, seed=2)
    samples = data_synth.synthesize(model, params, wi, wo, noise=0.02, seed=3, **options)
    theta = jnp.asarray(built.unconstrained.from_params(built.dictionary.to_params(params))) * 1.01
    problem = build_problem(samples)
    assert problem.wi.shape[0] == 3072 and chunk_size(3072) == 256
    squares, gradient, gram, squared_error = jax.jit(partial(normal_equations, built, loss))(theta, problem)
    error = built.brdf(built.unconstrained.to_params(theta, 3), samples.wi, samples.wo) - samples.values
    np.testing.assert_allclose(squared_error, np.sum(error**2), rtol=1e-11)  # the 72 padded rows excluded
    residual_fn = partial(residuals, built, loss)
    r = residual_fn(theta, problem).ravel()
    jacobian = jax.jit(jax.jacfwd(lambda t: residual_fn(t, problem).ravel()))(theta)
    np.testing.assert_allclose(squares, r @ r, rtol=1e-11)
    np.testing.assert_allclose(cost(residual_fn, theta, problem), r @ r, rtol=1e-11)
    for got, expected in ((gradient, jacobian.T @ r), (gram, jacobian.T @ jacobian)):
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12 * float(jnp.max(jnp.abs(expected))))


@parametrize_cases()
def test_normal_equations_of_every_model(model, options, params, monkeypatch):
    monkeypatch.setattr(problem_module, "CHUNK", 256)
    assert_normal_equations_match(model, options, params, "log")


@pytest.mark.parametrize("loss_name", list(LOSSES))
def test_normal_equations_of_every_loss(loss_name, monkeypatch):
    monkeypatch.setattr(problem_module, "CHUNK", 256)
    assert_normal_equations_match(*CASES[4], loss_name)


@pytest.mark.parametrize("columns", ["none", "sigma", "weight", "both"])
@pytest.mark.parametrize("loss_name", ["log", "cbrt"])
def test_residuals_follow_the_loss_formula_on_samples_and_vanish_on_padding(columns, loss_name):
    """Residuals of a padded problem, its target and scale computed on the fly or prepared once, against
    The losses of docs/losses.md written out in numpy: sqrt(weight)·(T(f) − T(y)) / (sigma·|T'(max(y, sigma))|).

    1000 samples pad to 1024 rows, whose residuals must be exactly 0. T' of log (ci / (1 + v ci)) and of
    cbrt (v^(-2/3) / 3) by hand. Tolerance: T(f) and T(y) are each within an ulp or two of the numpy
    values, and their difference cancels up to ~10³-fold where f and y are close, so 1e-10 relative."""
    model, loss = get_model("ward"), get_loss(loss_name)
    params = CASES[1][2]
    wi, wo = data_synth.uniform_random(1000, seed=5)
    clean = data_synth.synthesize("ward", params, wi, wo, noise=0.05, seed=6)
    rng = np.random.default_rng(7)
    sigma = 0.02 * clean.values + 1e-3 if columns in ("sigma", "both") else None
    weight = rng.uniform(0.0, 2.0, 1000) if columns in ("weight", "both") else None
    samples = Samples.from_arrays(wi, wo, clean.values, channels=clean.channels, sigma=sigma, weight=weight)
    problem = build_problem(samples)
    assert problem.wi.shape[0] == 1024
    theta = jnp.asarray(model.unconstrained.from_params(model.dictionary.to_params(params))) * 1.02
    on_the_fly = np.asarray(jax.jit(partial(residuals, model, loss))(theta, problem))
    once = np.asarray(jax.jit(lambda t, q: residuals(model, loss, t, prepared(loss, q)))(theta, problem))

    ci, y = wi[:, 2:3], clean.values
    f = model.brdf(model.unconstrained.to_params(theta, 3), wi, wo)
    if loss_name == "log":
        transform, slope = (lambda v: np.log1p(v * ci)), (lambda v: ci / (1.0 + v * ci))
    else:
        transform, slope = np.cbrt, (lambda v: np.maximum(v, np.finfo(float).tiny) ** (-2.0 / 3.0) / 3.0)
    expected = transform(np.asarray(f)) - transform(y)
    if sigma is not None:
        expected = expected / (sigma * np.abs(slope(np.maximum(y, sigma))))
    if weight is not None:
        expected = expected * np.sqrt(weight)[:, None]
    for got in (on_the_fly, once):
        np.testing.assert_allclose(got[:1000], expected, rtol=1e-10, atol=0.0)
        assert np.all(got[1000:] == 0.0)


def test_brdffit_jit_agrees_with_jax_jit_at_top_level_and_inside_traces():
    """``brdffit._programs.jit`` compiles with the CPU options on its own and falls back to plain ``jax.jit`` inside an
    outer ``jit`` or ``vmap`` (where JAX refuses compiler options). Another emitter may sum 1001 terms in another
    order, hence rtol 1e-12 (~1000 ulp of float64) rather than equality."""
    from brdffit._programs import jit
    from brdffit._programs.jit import CPU_COMPILER_OPTIONS, compiler_options

    def f(x):
        return jnp.sum(jnp.log1p(x) * x[::-1])

    x = jnp.linspace(0.0, 3.0, 1001)
    expected = float(jax.jit(f)(x))
    wrapped = jit(f)
    wrapped.precompile(jax.ShapeDtypeStruct(x.shape, x.dtype))  # as fitting does in a thread; the call reuses it
    np.testing.assert_allclose(wrapped(x), expected, rtol=1e-12)
    np.testing.assert_allclose(jax.jit(wrapped)(x), expected, rtol=1e-12)
    np.testing.assert_allclose(jax.vmap(wrapped)(jnp.stack([x, 2 * x]))[0], expected, rtol=1e-12)
    assert compiler_options() == (CPU_COMPILER_OPTIONS if jax.default_backend() == "cpu" else None)


def test_the_old_module_paths_are_the_new_modules():
    """Paths the documentation once gave (and older pickles name) import the modules where they live now."""
    import importlib

    from brdffit.fitting.fit import compiled_solver
    from brdffit.fitting.losses import get_loss as old_get_loss
    from brdffit.fitting.problem import build_problem as old_build_problem

    from brdffit.fitting.comparison import compare
    from brdffit.fitting.solver.compiled import compiled_solver as new_compiled_solver

    assert compiled_solver is new_compiled_solver and old_get_loss is get_loss and old_build_problem is build_problem
    assert importlib.import_module("brdffit.fitting.compare") is compare
    results = importlib.import_module("brdffit.fitting.results")
    assert results.FitResult is brdffit.FitResult
    # The module keeps its own spec under both names (its relative imports, inside functions too, find its rooms).
    assert results.__spec__.name == "brdffit.fitting.single.result" and compare.__spec__.parent == compare.__package__
