"""A fitting problem as arrays, its residuals, and the normal equations accumulated in one pass.

The residual of sample ``n``, channel ``c`` is
``scale[n, c] · (T(f(wi_n, wo_n))[c] - T(y)[n, c])`` with ``T`` the loss transform
(``losses.py``) and ``f`` the model at the parameters the unconstrained vector
``theta`` maps to (``Model.unconstrained``).

Sizes are *bucketed*: a problem of N samples is padded to ``padded_size(N)``
(N rounded up to 4 significant bits, at most 1/8 more) with rows of scale 0,
which add nothing to any sum. Datasets of nearby sizes then share one compiled
solver, and the rows split evenly into chunks of at most :data:`CHUNK` samples,
over which :func:`normal_equations` accumulates ``JᵀJ``, ``Jᵀr`` and ``rᵀr``
without ever holding the (N·C × k) Jacobian or the residual vector.
"""

from collections.abc import Sequence
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from ..._jax import float64
from ..._programs import jit
from ...data.samples import Samples
from ...physics.geometry import NORMAL
from ...physics.models.model import LobeModel, Model
from ...physics.models.params import Params
from .jacobian import jacobian_coefficients, value_and_basis
from .losses import Loss, residual_scale

#: Most samples per chunk of the normal-equation pass: 2¹⁴ × 3 channels × 8 parameters is a 3 MB Jacobian block.
CHUNK = 2**14


class Problem(NamedTuple):
    """The data of one fit, as arrays (a JAX pytree, so one compiled solver serves every dataset of a shape).

    Rows beyond the samples' count are padding: ``real`` False, both directions
    the normal, ``measured`` 0, ``sigma`` 1 and ``weight`` 0. The loss's
    ``T(measured)`` and residual scale depend on the loss: :func:`prepared`
    fills them in at the top of a compiled program that passes over the data
    many times (the solver, the sampler), and :func:`target_and_scale` computes
    them on the fly where they are missing.
    """

    wi: Float[Array, "N 3"] | Float[np.ndarray, "N 3"]  # numpy on the host (host_problems)
    wo: Float[Array, "N 3"] | Float[np.ndarray, "N 3"]
    measured: Float[Array, "N C"] | Float[np.ndarray, "N C"]  # BRDF, 1/sr
    sigma: Float[Array, "N C"] | Float[np.ndarray, "N C"] | None  # 1-σ uncertainty of measured, 1/sr
    weight: Float[Array, " N"] | Float[np.ndarray, " N"] | None
    real: Bool[Array, " N"] | Bool[np.ndarray, " N"]  # a sample, not padding
    target: Float[Array, "N C"] | None = None  # T(measured), None until prepared
    scale: Float[Array, "N C"] | Float[Array, "N 1"] | None = None  # residual scale, 0 on padding; None until prepared


def padded_size(n: int) -> int:
    """``n`` rounded up to ``m·2^e`` with ``8 ≤ m ≤ 16``: at most 12.5% padding, few distinct sizes."""
    exponent = max(n.bit_length() - 4, 0)
    return -(-n // 2**exponent) * 2**exponent


def chunk_size(n_padded: int) -> int:
    """The largest power of two ≤ :data:`CHUNK` that divides ``n_padded`` (all of it when it fits in one chunk)."""
    if n_padded <= CHUNK:
        return n_padded
    return min(n_padded & -n_padded, CHUNK)


@float64
def build_problem(samples: Samples, dtype: str = "float64") -> Problem:
    """The padded arrays of ``samples``, in ``dtype`` (the model is evaluated in it; sums stay float64).

    The padding is done on the host, into :data:`ALIGNMENT`-aligned buffers
    that the CPU backend takes without a copy (``jax.device_put``), so no
    program is compiled or run. For a MERL-size problem (1.46·10⁶ samples) this
    replaced ~0.25 s of compiling and running an XLA padding program by ~50 ms
    of copying (2-core Xeon).
    """
    return jax.device_put(jax.tree.map(lambda leaf: leaf[0], host_problems([samples], dtype)))


@float64
def build_problems(samples: Sequence[Samples], dtype: str = "float64", count: int | None = None) -> Problem:
    """The problems of datasets of one bucket (``padded_size`` and channels alike), stacked: arrays (D, N, …).

    ``count`` ≥ D rows of datasets, the rows after the last a copy of the first (so that a batch's size can
    come from a few values and reuse its compiled program); one transfer for them all.
    """
    return jax.device_put(host_problems(samples, dtype, count))


def host_problems(samples: Sequence[Samples], dtype: str = "float64", count: int | None = None) -> Problem:
    """:func:`build_problems` on the host: numpy arrays (count, N, …), each written once into aligned buffers."""
    count = len(samples) if count is None else count
    wi, wo, real = stacked_directions(samples, dtype, count)
    return Problem(
        wi,
        wo,
        _stacked_all(samples, count, lambda one: one.values, dtype),
        _stacked(samples, count, lambda one: one.sigma, dtype, 1.0),
        _stacked(samples, count, lambda one: one.weight, dtype),
        real,
    )


def stacked_directions(samples: Sequence[Samples], dtype: str, count: int) -> tuple[np.ndarray, ...]:
    """``wi``, ``wo`` (count, N, 3) and ``real`` (count, N) of ``samples`` as :func:`host_problems` stacks them:
    padded with the normal, which is not real, the rows after the last dataset copies of the first."""
    return (
        _stacked_all(samples, count, lambda one: one.wi, dtype, NORMAL),
        _stacked_all(samples, count, lambda one: one.wo, dtype, NORMAL),
        _stacked_all(samples, count, lambda one: np.ones(one.n_samples, bool), bool, False),
    )


def _stacked_all(samples: Sequence[Samples], count: int, field, dtype, fill=0.0) -> np.ndarray:
    """:func:`_stacked` of a field every dataset has (its directions, its values)."""
    stacked = _stacked(samples, count, field, dtype, fill)
    assert stacked is not None
    return stacked


def _stacked(samples: Sequence[Samples], count: int, field, dtype, fill=0.0) -> np.ndarray | None:
    """``field`` of each of ``samples`` (None when it is absent) in one aligned buffer (count, N, …): rows padded
    to :func:`padded_size` with ``fill``, the rows after the last dataset copies of the first."""
    copies = [*samples, *[samples[0]] * (count - len(samples))]
    arrays = [field(one) for one in copies]
    if arrays[0] is None:
        return None
    out = _aligned((count, padded_size(samples[0].n_samples), *np.shape(arrays[0])[1:]), dtype)
    for row, array in zip(out, arrays, strict=True):
        row[: len(array)] = array
        row[len(array) :] = fill
    return out


#: Byte alignment at which the CPU backend shares a numpy buffer instead of copying it.
ALIGNMENT = 64


def _aligned(shape: tuple[int, ...], dtype) -> np.ndarray:
    """A new uninitialised array whose data start on an :data:`ALIGNMENT`-byte boundary."""
    dtype = np.dtype(dtype)
    n_bytes = int(np.prod(shape)) * dtype.itemsize
    raw = np.empty(n_bytes + ALIGNMENT, np.uint8)
    offset = -raw.ctypes.data % ALIGNMENT
    return raw[offset : offset + n_bytes].view(dtype).reshape(shape)


def prepared(loss: Loss, problem: Problem) -> Problem:
    """``problem`` with its ``target`` and ``scale`` for ``loss`` filled in (JAX, inside a compiled program).

    Computed once per program, they cost one transform of the measurements
    (~30 ms at MERL size); recomputed in every pass instead, they made a
    Cook-Torrance pass ~20% slower (a second ``log1p`` per value).
    """
    target, scale = target_and_scale(loss, problem)
    return problem._replace(target=target, scale=scale)


def target_and_scale(loss: Loss, problem: Problem):
    """``T(measured)`` (N, C) and the residual scale of ``losses.residual_scale``, 0 on padding (JAX).

    Those of a :func:`prepared` problem, or computed here. Without ``sigma``
    and ``weight`` the scale is the same for every channel, 1 on samples and 0
    on padding, and is kept as one column (N, 1), which broadcasts: a pass then
    reads a third of it.
    """
    if problem.target is not None:
        return problem.target, problem.scale
    cos_i = problem.wi[:, 2:3]
    target = loss.transform(problem.measured, problem.measured, cos_i)
    if problem.sigma is None and problem.weight is None:
        return target, problem.real[:, None].astype(target.dtype)
    scale = residual_scale(loss, problem.measured, cos_i, problem.sigma, problem.weight)
    return target, jnp.where(problem.real[:, None], scale, 0.0)


def residuals(model: Model, loss: Loss, theta: Float[Array, " k"], problem: Problem) -> Float[Array, "N C"]:
    """Residuals (N, C) at the unconstrained parameters ``theta``, computed in the problem's dtype."""
    return residuals_at(model, loss, model.unconstrained.to_params(theta, problem.measured.shape[1]), problem)


def residuals_at(model: Model, loss: Loss, params: Params, problem: Problem) -> Float[Array, "N C"]:
    """Residuals (N, C) at the parameters ``params`` (arrays), computed in the problem's dtype."""
    params = jax.tree.map(lambda leaf: leaf.astype(problem.wi.dtype), params)
    return residuals_of_values(loss, model.brdf(params, problem.wi, problem.wo), problem)


def residuals_of_values(loss: Loss, predicted: Float[Array, "N C"], problem: Problem) -> Float[Array, "N C"]:
    """Residuals (N, C) of a model whose values at ``problem``'s directions are ``predicted`` (N, C), 1/sr."""
    transformed = loss.transform(predicted, problem.measured, problem.wi[:, 2:3])
    target, scale = target_and_scale(loss, problem)
    return (transformed - target) * scale


@float64
def sample_residuals(model: Model, loss: Loss, params: Params, samples: Samples) -> np.ndarray:
    """The loss's residuals (N, C) of the model with ``params`` on ``samples``, sigma and weight applied: what a fit
    minimises the squares of (``docs/losses.md``), in the loss's units, float64, on the host."""
    return np.asarray(_residuals_at(model, loss, params, build_problem(samples)))[: samples.n_samples]


_residuals_at = jit(residuals_at, static_argnums=(0, 1))


def residuals_and_basis(model: LobeModel, loss: Loss, theta, problem: Problem):
    """Residuals ``r`` (N, C), their weights ``w = scale·T'(f)`` (N, C), the model's basis (N, M) and values (N, C).

    The residual Jacobian is ``∂r[n, c]/∂θ = w[n, c] · Σ_m basis[n, m] · A[c, m]``
    with ``A`` from :func:`basis.jacobian_coefficients`; ``T'`` by forward mode.
    """
    values, basis = value_and_basis(model, theta, problem.wi, problem.wo, problem.measured.shape[1])
    transformed, slope = loss.value_and_slope(values, problem.measured, problem.wi[:, 2:3])
    target, scale = target_and_scale(loss, problem)
    return (transformed - target) * scale, slope * scale, basis, values


def chunks(problem: Problem) -> Problem:
    """``problem`` reshaped to (chunks, chunk_size, …), for a ``lax.scan`` over its rows."""
    n = problem.wi.shape[0]
    size = chunk_size(n)
    return jax.tree.map(lambda a: a.reshape(n // size, size, *a.shape[1:]), problem)


class Sums(NamedTuple):
    """What one pass over a problem accumulates (float64)."""

    cost: Float[Array, ""]  # rᵀr
    gradient: Float[Array, " k"]  # Jᵀr
    gram: Float[Array, "k k"]  # JᵀJ
    squared_error: Float[Array, ""]  # Σ (f - y)² over the real samples and every channel, (1/sr)²: the rmse's numerator


def normal_equations(model: LobeModel, loss: Loss, theta: Float[Array, " k"], problem: Problem) -> Sums:
    """``rᵀr``, ``Jᵀr``, ``JᵀJ`` and ``Σ (f - y)²`` at ``theta``, float64, in one pass over the chunks of ``problem``.

    With ``J[n, c] = w[n, c] Σ_m B[n, m] A[c, m]`` (:func:`residuals_and_basis`; ``B[n, c, m]`` for a lobe with
    per-channel parameters, which the sums below take channel by channel),
    ``JᵀJ = Σ_c A_cᵀ Q_c A_c`` and ``Jᵀr = Σ_c A_cᵀ R_c``, where the pass only
    accumulates ``Q_c = Σ_n w²[n, c] B_n B_nᵀ`` (C × M × M) and
    ``R_c = Σ_n w[n, c] r[n, c] B_n`` (C × M): the Jacobian itself is never
    formed, and memory is that of one chunk whatever the data size. The sum of
    squared BRDF errors comes with it, so that the solver knows the rmse of the
    point it stops at without evaluating the model once more.
    """

    def accumulate(sums, chunk):
        r, w, basis, values = (x.astype(jnp.float64) for x in residuals_and_basis(model, loss, theta, chunk))
        cost, projected, gram, squared_error = sums
        n, c = r.shape
        error = jnp.where(chunk.real[:, None], values - chunk.measured.astype(jnp.float64), 0.0)
        if basis.ndim == 3:  # a basis per channel (N, C, M): Q_c = Σ_n (w B)[n, c] (w B)[n, c]ᵀ, R_c = Σ_n r (w B)
            # One dot over the rows, batched over the channels: [r | w B]ᵀ (w B). As two einsums ("nc,ncm,ncl->cml"
            # and "nc,ncm->cm") the contraction took twice as long (3 × 11,520 × 5: 1.14 ms, this 0.53 ms).
            weighted = w[:, :, None] * basis
            both = jax.lax.dot_general(
                jnp.concatenate([r[:, :, None], weighted], axis=2), weighted, (((0,), (0,)), ((1,), (1,)))
            )  # (C, 1 + M, M)
            return (
                cost + jnp.sum(r * r),
                projected + both[:, 0],
                gram + both[:, 1:],
                squared_error + jnp.sum(error * error),
            ), None
        # Both sums come from one dot over the chunk's rows of row-major (n, ·) arrays: [w r | w² ⊗ B]ᵀ B.
        # Written as einsums of a (n, C, M) product, XLA transposed that product for the dot and recomputed the
        # basis inside it (one MERL-size Cook-Torrance pass: 170 ms); as two dots, ~110 ms; as one, ~100 ms
        # (2-core Xeon): each dot walks the basis once more.
        squared_weights_times_basis = ((w * w)[:, :, None] * basis[:, None, :]).reshape(n, -1)  # (n, C·M)
        both = _row_contraction(jnp.concatenate([w * r, squared_weights_times_basis], axis=1), basis)
        return (
            cost + jnp.sum(r * r),
            projected + both[:c],
            gram + both[c:].reshape(gram.shape),
            squared_error + jnp.sum(error * error),
        ), None

    c = problem.measured.shape[1]
    coefficients = jacobian_coefficients(model, theta, c)
    m = coefficients.shape[1]
    zero = jnp.zeros((), jnp.float64)
    start = (zero, jnp.zeros((c, m), jnp.float64), jnp.zeros((c, m, m), jnp.float64), zero)
    (cost, projected, gram, squared_error), _ = jax.lax.scan(accumulate, start, chunks(problem))
    gradient = jnp.einsum("cmp,cm->p", coefficients, projected)
    return Sums(cost, gradient, jnp.einsum("cmp,cml,clq->pq", coefficients, gram, coefficients), squared_error)


def _row_contraction(a, b):
    """``aᵀ b`` for ``a`` (n, p) and ``b`` (n, q): a dot over the leading axis, with no transposed copy."""
    return jax.lax.dot_general(a, b, (((0,), (0,)), ((), ())))


def cost(residual_fn, theta, problem: Problem):
    """``rᵀr`` at ``theta``, float64, chunk by chunk."""

    def accumulate(total, chunk):
        r = residual_fn(theta, chunk).astype(jnp.float64)
        return total + jnp.sum(r * r), None

    total, _ = jax.lax.scan(accumulate, jnp.zeros((), jnp.float64), chunks(problem))
    return total
