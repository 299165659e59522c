"""The posterior density of a fit's parameters: priors, a likelihood consistent with the loss, and its logarithm.

Coordinates are the model's *sampling vector* (``Model.sampling``): the
physical parameters themselves, except that a Lafortune lobe's direction is
its angle ``psi``. When the samples carry no ``sigma``, one more coordinate,
``ln s``, scales the noise.

Likelihood: Gaussian on the residuals of the fit's loss (``problem.py``),
``r = scale · (T(f) - T(y))``. With a ``sigma`` column ``scale`` already
divides by the measurement's σ carried into the loss's units, so
``ln L = -½ Σ r²``. Without one the residuals share an unknown standard
deviation ``s`` (a nuisance parameter)::

    ln L = -½ Σ r² / s² - n ln s            (n: fitted values, samples × channels)

A model whose fit includes a prior (the data-driven model's ridge, ``Model.prior_weight = W``) adds
``W · Σ v²`` to ``Σ r²``: pseudo-observations ``v ≈ 0`` in the residuals' units, which share ``s`` and are
counted in ``n`` (:func:`counted_values`).

Priors (``physics/domains.py``): flat on albedos and bounded parameters (``f0``,
``psi``), log-uniform on scales (roughness, exponents, ``eta - 1``) and on
``s``. They are improper where unbounded; the likelihood makes the posterior
proper whenever the fit is determined. A fit that held parameters
(``fit.fixed``, ``fit.bounds``; ``fitting/single/constraints.py``) keeps them held:
its fixed ones are no coordinates of the posterior (they stay at their values),
and its bounds truncate the prior.

The log density is compiled once per problem and walker batch shape, evaluates
a whole batch of walkers at once, and returns ``-inf`` (never NaN) outside the
prior's support or wherever the model cannot be evaluated.
"""

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._jax import float64
from .._programs import built_once, jit
from ..data.samples import Samples
from ..errors import BrdfInputError
from ..fitting.objective.losses import Loss, get_loss
from ..fitting.objective.problem import Problem, build_problem, cost, prepared, residuals_at, target_and_scale
from ..fitting.single.constraints import constraints_for
from ..fitting.single.result import FitResult
from ..physics.models.model import Model
from ..physics.models.registry import get_model

#: Name of the noise coordinate ``ln s`` (sampled only when the samples carry no sigma).
LOG_NOISE = "ln_noise"


class Density(NamedTuple):
    """The posterior density of ``result``'s parameters given the ``samples`` it was fitted to: what
    Laplace's approximation and the sampler both start from."""

    model: Model
    loss: Loss
    problem: Problem
    optimum: np.ndarray  # the sampling vector at the fitted parameters
    labels: list[str]  # of the sampling vector
    n_channels: int
    has_sigma: bool
    n_values: int  # fitted values: real samples × channels with a nonzero weight
    free: np.ndarray  # (k,) bool: the sampling vector's coordinates the fit determined (not fixed)
    low: np.ndarray  # (k,) the bounds the fit held each coordinate within, ±inf where none
    high: np.ndarray

    @property
    def free_labels(self) -> list[str]:
        """The labels of the coordinates the posterior moves (the fixed ones stay at their values)."""
        return [label for label, free in zip(self.labels, self.free, strict=True) if free]

    def embedded(self, free_values) -> np.ndarray:
        """Whole sampling vectors (…, k) from values (…, n_free) of the free coordinates: the fixed ones at the
        optimum's values (numpy)."""
        free_values = np.asarray(free_values, float)
        whole = np.broadcast_to(self.optimum, (*free_values.shape[:-1], self.optimum.size)).copy()
        whole[..., self.free] = free_values
        return whole


def density_of(result: FitResult, samples: Samples) -> Density:
    """The model, loss and problem of ``result``, checked against ``samples`` (the samples it was fitted to)."""
    if not isinstance(samples, Samples):
        raise BrdfInputError(f"expected Samples (from brdffit.load_samples), got {type(samples).__name__}")
    if tuple(samples.channels) != tuple(result.channels):
        raise BrdfInputError(
            f"{samples.source}: channels {', '.join(samples.channels)} differ from the fit's"
            f" ({', '.join(result.channels)})"
        )
    if samples.n_samples != result.n_samples:
        raise BrdfInputError(
            f"{samples.source}: {samples.n_samples} samples, but the fit used {result.n_samples};"
            " give the samples it was fitted to (after the same max_theta)"
        )
    model = get_model(result.model, **result.model_options)
    loss = get_loss(result.loss)
    problem = build_problem(samples)
    optimum = model.sampling.from_params(model.dictionary.to_params(result.params))
    n_values = int(_count_weighted(loss, problem))
    labels = model.sampling.labels(tuple(result.channels))
    constraints = constraints_for(model, len(result.channels), result.fixed, result.bounds, defaults=False)
    if constraints is None:
        free, (low, high) = np.ones(optimum.size, bool), (np.full(optimum.size, -np.inf), np.full(optimum.size, np.inf))
    else:
        free, (low, high) = constraints.free, constraints.sampling_bounds()
    has_sigma = samples.sigma is not None
    return Density(model, loss, problem, optimum, labels, len(result.channels), has_sigma, n_values, free, low, high)


def counted_values(density: Density) -> int:
    """The terms of the cost that share the noise ``s``: the fitted values, and the prior's ``Σ v²`` as one term per
    coordinate when the model has one. A ridge is the data-driven model's pseudo-observations ``v ≈ 0`` in the
    residuals' units, so it scales with ``s²`` as they do, and counts as they do."""
    return density.n_values + (density.optimum.size if density.model.prior_weight > 0 else 0)


def n_free(density: Density) -> int:
    """The parameters the fit determined: the sampling vector's coordinates less the fixed ones."""
    return int(np.count_nonzero(density.free))


@jit(static_argnums=0)
def _count_weighted(loss: Loss, problem: Problem):
    """How many residuals carry weight: values of real samples whose residual scale is not 0."""
    return jnp.count_nonzero(jnp.broadcast_to(target_and_scale(loss, problem)[1], problem.measured.shape))


def chi_squared(model: Model, loss: Loss, v, problem: Problem, prior_weight=0.0):
    """``Σ r² + prior_weight · Σ v²`` at the sampling vector ``v``, float64, chunk by chunk (JAX): the fit's cost,
    with the prior it includes (``Model.prior_weight``, the data-driven model's ridge; 0 for the others)."""
    c = problem.measured.shape[1]
    data = cost(lambda w, chunk: residuals_at(model, loss, model.sampling.to_params(w, c), chunk), v, problem)
    return data + prior_weight * jnp.sum(jnp.square(v.astype(jnp.float64)))


@built_once
def compiled_chi_squared(model: Model, loss: Loss):
    """:func:`chi_squared` compiled: ``(v, problem, prior_weight) -> Σ r² + prior_weight · Σ v²``."""
    return jit(partial(chi_squared, model, loss))


def log_prior(model: Model, v, n_channels: int):
    """Sum of the domains' log priors at the sampling vector ``v`` (JAX); ``-inf`` outside the support."""
    return sum(domain.log_prior(v[i]) for i, domain in enumerate(model.sampling.domains(n_channels)))


class Frame(NamedTuple):
    """Where the walkers' free coordinates sit in the sampling vector (data to the compiled density): the optimum,
    whose fixed entries stay, the indices of the free ones, and the bounds of every coordinate."""

    optimum: Any  # (k,)
    free_index: Any  # (n_free,) int
    low: Any  # (k,)
    high: Any


@built_once
def compiled_log_density(model: Model, loss: Loss, has_sigma: bool):
    """``(walkers (W, D), problem, n_values, prior_weight, frame) -> (W,)`` log posterior densities, jit-compiled,
    vmapped over walkers; D is the number of free coordinates (+1 for ``ln s``), placed into the sampling vector by
    ``frame`` (:class:`Frame`); ``n_values`` counts the prior's terms too (:func:`counted_values`)."""

    def one(x, problem, n_values, prior_weight, frame: Frame):
        c = problem.measured.shape[1]
        n = frame.free_index.shape[0]
        v = frame.optimum.at[frame.free_index].set(x[:n])
        chi2 = chi_squared(model, loss, v, problem, prior_weight)
        if has_sigma:
            likelihood = -0.5 * chi2
        else:  # x[n] = ln s, with a flat prior (log-uniform in s)
            likelihood = -0.5 * chi2 * jnp.exp(-2.0 * x[n]) - n_values * x[n]
        within = jnp.all((v >= frame.low) & (v <= frame.high))  # the fit's bounds truncate the prior
        total = jnp.where(within, log_prior(model, v, c), -jnp.inf) + likelihood
        return jnp.where(jnp.isfinite(total), total, -jnp.inf)

    walkers = jax.vmap(one, in_axes=(0, None, None, None, None))
    return jit(
        lambda x, problem, n_values, w, frame: walkers(x, prepared(loss, problem), n_values, w, frame),
        closes_over=(model, loss),  # the model's compiler options (``_programs/jit.py``)
    )


def log_probability_function(density: Density):
    """``log_prob(walkers) -> (W,)`` for a (W, D) numpy batch, D the number of free coordinates (+1 for ``ln s``)."""
    compiled = compiled_log_density(density.model, density.loss, density.has_sigma)
    frame = Frame(density.optimum, np.flatnonzero(density.free), density.low, density.high)

    @float64
    def log_prob(walkers):
        x = jnp.asarray(walkers, dtype=jnp.float64)
        return np.asarray(compiled(x, density.problem, counted_values(density), density.model.prior_weight, frame))

    return log_prob


@float64
def physical_draws(model: Model, draws: np.ndarray, n_channels: int) -> np.ndarray:
    """Sampling-vector draws (S, k) as flat physical vectors (S, p) in ``model.physical.labels`` order."""
    convert = jit(
        jax.vmap(lambda v: model.physical.from_params(model.sampling.to_params(v, n_channels))), closes_over=(model,)
    )
    return np.asarray(convert(jnp.asarray(draws, dtype=jnp.float64)))
