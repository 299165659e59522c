"""A material's coefficients fitted to samples: a ridge start in the mapped space, then Levenberg-Marquardt.

In the space the basis is linear in (``mapping.py``), the material is ``m = mean + Φ c``: fitting the coefficients there
is ridge regression, solved exactly in one step (``(ΦᵀΦ + ridge·I) c = Φᵀ(m(y) − mean)``, per channel). That is what the
linearity buys: no search over starts, a unique optimum of the mapped problem, and a start that is already at the
optimum when the measurements lie on the basis. The fit itself minimises the chosen loss on the BRDF values, ``Σ r² +
ridge · Σ c²``, with brdffit's one-pass Levenberg-Marquardt (``fitting/solver/levenberg_marquardt.py``, on Optimistix)
from that start, chunk by chunk (a MERL-size measurement fits in the memory of one chunk): the loss and the map differ
(a log loss on ``ln(1 + f cos θi)``, a map on ``ln(f cos θi cos θo + ε)``), and the BRDF between bins is a blend of its
neighbours' (``basis.py``), so a few steps remain. Channels have their own coefficients and are solved one after another
by one compiled program.
"""

from functools import partial
from typing import Any, NamedTuple

import numpy as np

from .._jax import float64, jax, jnp
from .._programs import jit
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..fitting.objective.losses import Loss
from ..fitting.objective.problem import Sums, build_problem, chunk_size, target_and_scale
from ..fitting.single.outcome import result_of
from ..fitting.single.result import FitResult
from ..fitting.solver.compiled import TOLERANCES, Solved, fit_descent, outcome_of
from ..physics.models.params import Params
from .basis import Corners, visible_pairs
from .mapping import EPSILON, cosine_weight, mapped
from .model import PcaModel, pca

#: A fitted coefficient this many library standard deviations from the library's mean gets a warning: the
#: material lies outside the library, where the basis extrapolates.
OUTSIDE_LIBRARY = 4.0


@float64
def fit_pca(
    samples: Samples, model: PcaModel, loss: Loss, *, start: dict | None, max_steps: int, max_theta: float | None
) -> FitResult:
    """The fit of ``model``'s coefficients to ``samples`` (already selected by ``max_theta``)."""
    problem = build_problem(samples)
    wi, wo = np.asarray(problem.wi), np.asarray(problem.wo)
    corners = model.basis.corners(wi, wo)
    visible = visible_pairs(wi, wo) & np.asarray(problem.real)
    empty = int(np.sum(visible & (corners.weight.sum(axis=1) == 0)))
    corners = corners._replace(weight=corners.weight * visible[:, None])
    target, scale = (np.broadcast_to(np.asarray(a), problem.measured.shape) for a in target_and_scale(loss, problem))
    if "ridge_scale" not in model.model_options:  # measured on these samples, then recorded with the result
        measured_scale = ridge_scale(model.basis.mapping, loss, problem, scale, corners)
        model = pca(**{**model.model_options, "ridge_scale": measured_scale})
    if start is None:
        coefficients = ridge_start(model, corners, np.asarray(problem.measured), scale, wi, wo)
    else:
        coefficients = np.asarray(model.dictionary.to_params(start).specular)
        if coefficients.shape[1] != samples.n_channels:
            raise BrdfInputError(
                Argument("start"),
                f" coefficients have {coefficients.shape[1]} channel(s) but the samples have {samples.n_channels}",
            )
    device_corners = jax.device_put(corners)
    solutions, outcomes, steps = [], [], []
    for c in range(samples.n_channels):
        channel = Channel(
            corners=device_corners,
            measured=problem.measured[:, c],
            target=jnp.asarray(target[:, c]),
            scale=jnp.asarray(scale[:, c]),
            cos_i=problem.wi[:, 2],
            real=problem.real,
            weight=jnp.asarray(model.prior_weight),
        )
        value, outcome, n_steps = _solve_channel(
            loss, model.basis.mapping, max_steps, jnp.asarray(coefficients[:, c]), channel
        )
        solutions.append(np.asarray(value))
        outcomes.append(int(outcome))
        steps.append(int(n_steps))
    coefficients = np.stack(solutions, axis=1)
    predicted = corners.brdf(model.basis.mapping, coefficients)
    real = np.asarray(problem.real)
    residuals = (np.asarray(loss.transform(predicted, problem.measured, problem.wi[:, 2:3])) - target) * scale
    failed = next((outcome for outcome in outcomes if outcome != 0), 0)  # the first channel that did not converge
    params = Params(np.zeros(samples.n_channels), coefficients, {})
    solved = Solved(
        theta=model.unconstrained.from_params(params),
        cost=float(np.sum(residuals[real] ** 2)),
        n_steps=max(steps),
        result=failed,
        converged=failed == 0,
        params=params,
        rmse=float(np.sqrt(np.mean((predicted[real] - np.asarray(problem.measured)[real]) ** 2))),
    )
    more = pca_caveats(samples, coefficients, empty)
    return result_of(model, loss, samples, solved, max_steps, "float64", max_theta=max_theta, more_caveats=more)


def ridge_scale(mapping: str, loss: Loss, problem, scale: np.ndarray, corners: Corners) -> float:
    """The median over the samples of ``(scale · dT/dρ · dρ/dm)²`` at the measurements: what a residual of 1 in the
    mapped space is, squared, in the loss's units. The ridge is given in the mapped space, where the library's
    statistics live; the fit weighs it by this against the loss's residuals."""
    measured = np.maximum(np.asarray(problem.measured), 0.0)
    _, slope = loss.value_and_slope(jnp.asarray(measured), problem.measured, problem.wi[:, 2:3])
    cosine = np.maximum(cosine_weight(np.asarray(problem.wi), np.asarray(problem.wo)), 1e-12)[:, None]
    per_mapped = 1.0 if mapping == "none" else measured + EPSILON / cosine  # dρ/dm = (ρw + ε)/w
    # Samples below the horizon already have no corner weight (fit_pca): the weight says which count.
    counted = (scale > 0) & (corners.weight.sum(axis=1) > 0)[:, None]
    values = (scale * np.asarray(slope) * per_mapped)[counted] ** 2
    median = float(np.median(values)) if values.size else 0.0
    return median if median > 0 else 1.0


def ridge_start(model: PcaModel, corners: Corners, measured, scale, wi, wo) -> np.ndarray:
    """Coefficients (K, C) of the ridge regression in the mapped space: ``(ΦᵀWΦ + ridge·I) c = ΦᵀW(m(y) − mean)``
    with ``Φ``, ``mean`` and the reference blended at each sample and ``W`` 1 on the samples that count."""
    weight = corners.weight
    features = np.einsum("nj,njk->nk", weight, corners.components)
    mean = np.einsum("nj,nj->n", weight, corners.mean)
    reference = np.einsum("nj,nj->n", weight, corners.reference)
    cosine = np.maximum(cosine_weight(wi, wo), 1e-12)
    k = features.shape[1]
    out = np.zeros((k, measured.shape[1]))
    for c in range(measured.shape[1]):
        y = mapped(model.basis.mapping, measured[:, c], reference, cosine) - mean
        w = (weight.sum(axis=1) > 0) * (scale[:, c] > 0)
        matrix = features.T @ (w[:, None] * features) + max(model.ridge, 1e-12) * np.eye(k)  # mapped units
        out[:, c] = np.linalg.solve(matrix, features.T @ (w * y))
    return out


class Channel(NamedTuple):
    """One channel's data for the solve, padded rows included (scale 0): the basis at each sample's ``corners``,
    ``measured`` (1/sr), the loss's ``target`` and residual ``scale``, ``cos_i``, which rows are ``real``, and the
    prior's ``weight`` (``PcaModel.prior_weight``)."""

    corners: Corners
    measured: Any
    target: Any
    scale: Any
    cos_i: Any
    real: Any
    weight: Any


def channel_sums(loss: Loss, mapping: str, c, channel: Channel) -> Sums:
    """``rᵀr``, ``Jᵀr``, ``JᵀJ`` and ``Σ (f − y)²`` of one channel at coefficients ``c`` (K,), the prior's
    ``weight · Σ c²`` included, in one pass over chunks of the samples (``problem.chunk_size``): memory is one
    chunk's (its (chunk, 8, K) corners and a (chunk, K) Jacobian by forward mode) whatever the data size."""
    n = channel.measured.shape[0]
    size = chunk_size(n)
    rows = channel._replace(weight=None)
    chunked = jax.tree.map(lambda leaf: leaf.reshape(n // size, size, *leaf.shape[1:]), rows)

    def residuals(c, chunk):
        f = chunk.corners.brdf(mapping, c[:, None])[:, 0]
        return (loss.transform(f, chunk.measured, chunk.cos_i) - chunk.target) * chunk.scale, f

    def accumulate(sums, chunk):
        (r, f), jacobian = residuals(c, chunk), jax.jacfwd(lambda x: residuals(x, chunk)[0])(c)
        error = jnp.where(chunk.real, f - chunk.measured, 0.0)
        cost, gradient, gram, squared_error = sums
        return (
            cost + r @ r,
            gradient + jacobian.T @ r,
            gram + jacobian.T @ jacobian,
            squared_error + error @ error,
        ), None

    k = c.shape[0]
    zero = jnp.zeros((), jnp.float64)
    start = (zero, jnp.zeros(k, jnp.float64), jnp.zeros((k, k), jnp.float64), zero)
    (cost, gradient, gram, squared_error), _ = jax.lax.scan(accumulate, start, chunked)
    weight = channel.weight
    return Sums(cost + weight * (c @ c), gradient + weight * c, gram + weight * jnp.eye(k), squared_error)


@jit(static_argnums=(0, 1, 2))
def _solve_channel(loss: Loss, mapping: str, max_steps: int, c0, channel: Channel):
    """brdffit's Levenberg-Marquardt (``fitting/solver/levenberg_marquardt.py``, MINPACK's tests and tolerances) on one
    channel's coefficients: residuals ``scale·(T(f) − T(y))`` and the prior's ``sqrt(weight)·c``
    (:func:`_channel_residuals`), each step from :func:`channel_sums`. Returns the coefficients, the outcome's index
    into ``OUTCOMES`` and the steps taken."""
    from ..fitting.solver.levenberg_marquardt import least_squares

    ftol, gtol, atol = TOLERANCES["float64"]
    solution = least_squares(
        partial(_channel_residuals, loss, mapping),
        c0,
        channel,
        rtol=ftol,
        atol=atol,
        gtol=gtol,
        max_steps=max_steps,
        has_aux=True,
        normal_equations=partial(channel_sums, loss, mapping),
        descent=fit_descent(),
    )
    return solution.value, outcome_of(solution.result), solution.stats["num_steps"]


def _channel_residuals(loss: Loss, mapping: str, c, channel: Channel):
    """The residuals whose sums :func:`channel_sums` accumulates: ``scale·(T(f) − T(y))`` (N,) then the prior's
    ``sqrt(weight)·c`` (K,), and, as their aux, ``Σ (f − y)²`` over the real samples."""
    f = channel.corners.brdf(mapping, c[:, None])[:, 0]
    r = (loss.transform(f, channel.measured, channel.cos_i) - channel.target) * channel.scale
    error = jnp.where(channel.real, f - channel.measured, 0.0)
    return jnp.concatenate([r, jnp.sqrt(channel.weight) * c]), error @ error


def pca_caveats(samples: Samples, coefficients: np.ndarray, empty: int) -> list[str]:
    """What a user must know about a data-driven fit: coefficients far outside the library, samples that fall
    where the basis holds nothing."""
    warnings = []
    far = np.abs(coefficients) >= OUTSIDE_LIBRARY
    if far.any():
        k, c = np.unravel_index(int(np.argmax(np.abs(coefficients))), coefficients.shape)
        warnings.append(
            f"coefficients[{k}][{samples.channels[c]}] = {coefficients[k, c]:+.2f} library standard deviations"
            f" ({int(far.sum())} coefficient(s) beyond ±{OUTSIDE_LIBRARY:g}): the material lies outside the library,"
            " where the basis extrapolates; raise the ridge (--ridge) or build the basis from a library that holds"
            " such materials"
        )
    if empty:
        warnings.append(
            f"{empty} sample(s) fall where the basis holds no value (bins no library table has): the model is 0 there"
        )
    return warnings
