"""Laplace (Gauss-Newton) covariance of a fit's parameters.

At the optimum ``v̂`` the posterior is approximated by a Gaussian with
covariance ``s² (JᵀJ)⁻¹``, with ``J`` the exact Jacobian of the residuals
(``density.py``) and ``s² = Σ r² / (n - k)`` (the reduced χ², n fitted
values, k parameters) when the samples carry no ``sigma``; ``s² = 1`` when
they do, since the residuals are then already in units of σ (Bard 1974,
*Nonlinear Parameter Estimation*, ch. 7; Press et al., *Numerical Recipes*,
§15.5).

``J`` is taken in the sampling coordinates (physical values, Lafortune
directions as the angle ψ), chunk by chunk in forward mode. Since the solver's
coordinates ``u`` map to these by ``v = g(u)`` elementwise,
``(J_vᵀJ_v)⁻¹ = G (J_uᵀJ_u)⁻¹ Gᵀ`` with ``G = dv/du``: this *is* the delta
method, evaluated where it stays finite when an albedo sits at 0 (``G → 0``
there). Lafortune's ``(cxy, cz)`` then follow from ψ by the delta method
proper. Parameters the fit held fixed (``fit.fixed``) have error 0: the
inverse is taken over the free coordinates only, ``k`` counts those. The
inverse is taken in correlation scaling, so parameters of any units are
treated alike. A parameter is *undetermined* when its Jacobian column is zero or it has weight in a
direction in which ``JᵀJ`` is singular (no curvature), or when its error exceeds
:data:`UNDETERMINED_SPREAD` times the width of its plausible range (where it has a bounded one): correlation
scaling hides a column that is tiny in every sample (a dead lobe's roughness
and Fresnel indices, ``1 ± 3e14``), and no Gaussian that wide says anything about the data. An
undetermined error is reported as null, with its reason in the block's ``undetermined``, and a warning
names it; the errors of the others are then those with the undetermined ones held (the inverse over
the determined ones alone). Correlations of |ρ| ≥ :data:`DEGENERATE_CORRELATION` are reported as a
degenerate pair.
"""

from statistics import NormalDist
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._jax import float64
from .._programs import built_once, jit
from ..data.samples import Samples
from ..errors import warn
from ..fitting.objective.losses import Loss
from ..fitting.objective.problem import Problem, chunks, residuals_at
from ..fitting.single.result import FitResult, Uncertainty
from ..physics.models.model import Model
from . import findings as codes
from .density import Density, compiled_chi_squared, counted_values, density_of, n_free
from .findings import Finding
from .layout import QUANTILES, correlation, estimate, stderr_dict, strongest_correlation

#: |correlation| from which a pair of parameters is reported as degenerate (the data fix a combination of them).
DEGENERATE_CORRELATION = 0.99
#: Without sigma, when a sandwich (robust) error exceeds the Gauss-Newton one by this factor, the robust errors are
#: reported instead (method ``laplace-robust``) and a warning says why.
HETEROSCEDASTIC_RATIO = 2.0
#: Eigenvalues of the correlation-scaled JᵀJ below this fraction of the largest count as zero.
SINGULAR = 1e-12
#: An error above this many times the width of a parameter's (bounded) plausible range is undetermined: the 1-σ
#: interval then spans every plausible value ten times over.
UNDETERMINED_SPREAD = 10.0
#: Why an error is null, for a parameter with no curvature (its Jacobian zero, or in a singular direction).
NO_CURVATURE = "no curvature: zero or singular Jacobian"


def _mapped(gradient: np.ndarray, covariance_v: np.ndarray) -> np.ndarray:
    """``G C Gᵀ``, with NaN for every physical parameter that depends on an undetermined one (NaN in ``C``)."""
    unknown = np.isnan(np.diag(covariance_v))
    covariance = gradient @ np.nan_to_num(covariance_v) @ gradient.T
    affected = np.any((gradient != 0) & unknown[None, :], axis=1)
    covariance[affected, :] = np.nan
    covariance[:, affected] = np.nan
    return covariance


def gauss_newton_matrix(density: Density, v) -> np.ndarray:
    """``JᵀJ`` (k, k) of the residuals with respect to the sampling vector, exact (forward mode), chunk by chunk."""
    return gauss_newton_and_meat(density, v)[0]


def gauss_newton_and_meat(density: Density, v) -> tuple[np.ndarray, np.ndarray]:
    """``JᵀJ`` and ``Σ_i r_i² J_iᵀJ_i`` (the "meat" of the sandwich covariance), both (k, k); ``JᵀJ`` with the
    model's prior (``Model.prior_weight · I``)."""
    hessian, meat = compiled_gauss_newton(density.model, density.loss)(v, density.problem)
    # The prior's residuals sqrt(W)·v are linear: their JᵀJ is W·I. They are no data, so no meat.
    return np.asarray(hessian) + density.model.prior_weight * np.eye(np.size(v)), np.asarray(meat)


@built_once
def compiled_gauss_newton(model: Model, loss: Loss):
    """``(v, problem) -> (JᵀJ, Σ r² JᵢᵀJᵢ)``, compiled once per model and loss (and problem shape)."""

    @jit(closes_over=(model, loss))  # the model's compiler options (``_programs/jit.py``)
    def gauss_newton(v, problem: Problem):
        c = problem.measured.shape[1]

        def residual(w, chunk):
            return residuals_at(model, loss, model.sampling.to_params(w, c), chunk).ravel().astype(jnp.float64)

        def accumulate(totals, chunk):
            r = residual(v, chunk)
            jacobian = jax.jacfwd(residual)(v, chunk).astype(jnp.float64)
            weighted = jacobian * r[:, None]
            return (totals[0] + jacobian.T @ jacobian, totals[1] + weighted.T @ weighted), None

        zeros = jnp.zeros((v.shape[0], v.shape[0]), jnp.float64)
        totals, _ = jax.lax.scan(accumulate, (zeros, zeros), chunks(problem))
        return totals

    return gauss_newton


def inverse_with_null_space(matrix: np.ndarray, labels: list[str]) -> tuple[np.ndarray, list[str], float]:
    """``matrix⁻¹`` in correlation scaling, NaN in the rows and columns of undetermined parameters.

    Returns the inverse, the labels of the undetermined parameters and the
    condition number of the scaled matrix (over the determined ones).
    """
    k = matrix.shape[0]
    scale = np.sqrt(np.diag(matrix))
    determined = np.isfinite(scale) & (scale > 0)
    index = np.flatnonzero(determined)
    inverse = np.full((k, k), np.nan)
    condition = float("inf")
    if index.size:
        scaled = matrix[np.ix_(index, index)] / np.outer(scale[index], scale[index])
        eigenvalues, vectors = np.linalg.eigh(scaled)
        null = eigenvalues <= SINGULAR * eigenvalues[-1]
        condition = float(eigenvalues[-1] / eigenvalues[0]) if eigenvalues[0] > 0 else float("inf")
        kept = ~null
        scaled_inverse = (vectors[:, kept] / eigenvalues[kept]) @ vectors[:, kept].T
        inverse[np.ix_(index, index)] = scaled_inverse / np.outer(scale[index], scale[index])
        # A parameter with weight in a null direction has unbounded variance.
        in_null = np.any(np.abs(vectors[:, null]) > 1e-6, axis=1) if null.any() else np.zeros(index.size, bool)
        determined[index[in_null]] = False
    inverse[~determined, :] = np.nan
    inverse[:, ~determined] = np.nan
    return inverse, [label for label, ok in zip(labels, determined, strict=True) if not ok], condition


def laplace_uncertainty(result: FitResult, samples: Samples) -> FitResult:
    """``result`` with its Laplace :class:`~brdffit.fitting.single.result.Uncertainty`; ``samples`` are those it was
    fitted to.

    Warns (:class:`~brdffit.UncertaintyWarning`) about degenerate pairs, undetermined parameters and a fit
    that did not converge; the warnings are also the block's ``warnings``.
    """
    with float64():
        estimate, found = laplace_estimate(result, density_of(result, samples))
    for finding in found:
        warn(finding.warning())
    return result.with_estimate(estimate)


class Curvature(NamedTuple):
    """What one pass at the optimum gives: ``Σ r²``, ``(JᵀJ)⁻¹`` and the sandwich's meat, in sampling coordinates."""

    chi2: float
    inverse: np.ndarray  # (JᵀJ)⁻¹, NaN in the rows and columns of undetermined parameters
    meat: np.ndarray  # Σ_i r_i² J_iᵀJ_i
    undetermined: dict[str, str]  # label of the sampling vector → why its error is null
    condition: float  # of the correlation-scaled JᵀJ


@float64
def curvature_at_optimum(density: Density) -> Curvature:
    """The curvature at the optimum over the free coordinates: a fixed one's rows and columns of the inverse are 0
    (it has no error), and it takes no part in the null space or the condition number.

    Undetermined coordinates (no curvature, or an error beyond :data:`UNDETERMINED_SPREAD` times their plausible
    range; :func:`too_wide`) are found one round at a time: after each, the inverse is taken again over those left,
    until none is newly undetermined."""
    v = np.asarray(density.optimum)
    chi2 = float(compiled_chi_squared(density.model, density.loss)(v, density.problem, density.model.prior_weight))
    hessian, meat = gauss_newton_and_meat(density, v)
    noise2 = 1.0 if density.has_sigma else chi2 / max(counted_values(density) - n_free(density), 1)
    domains = density.model.sampling.domains(density.n_channels)
    undetermined: dict[str, str] = {}
    kept = np.flatnonzero(density.free)
    while True:
        labels = [density.labels[i] for i in kept]
        inverse = np.zeros_like(hessian)
        inverse[np.ix_(kept, kept)], singular, condition = inverse_with_null_space(hessian[np.ix_(kept, kept)], labels)
        undetermined |= dict.fromkeys(singular, NO_CURVATURE)
        wide = {
            density.labels[i]: why for i in kept if (why := too_wide(noise2 * inverse[i, i], domains[i])) is not None
        }
        undetermined |= wide
        if not wide:
            break
        kept = np.array([i for i in kept if density.labels[i] not in undetermined], dtype=int)
    unknown = [i for i, label in enumerate(density.labels) if label in undetermined]
    inverse[unknown, :] = np.nan
    inverse[:, unknown] = np.nan
    return Curvature(chi2, inverse, meat, undetermined, condition)


def too_wide(variance: float, domain) -> str | None:
    """Why an error of ``sqrt(variance)`` leaves a parameter in ``domain`` undetermined, or None: an error above
    :data:`UNDETERMINED_SPREAD` times the width of its plausible range. A parameter without a bounded plausible
    range (a data-driven model's coefficient) is never judged so: an error large beside its value says only that the
    value is not far from 0 (a coefficient of 0.01 ± 0.2 is measured), not that the data leave it free."""
    if not np.isfinite(variance):
        return None
    low, high = domain.plausible
    width = high - low
    error = float(np.sqrt(variance))
    if not np.isfinite(width) or width <= 0 or error <= UNDETERMINED_SPREAD * width:
        return None
    return f"error {error:.2g} > {UNDETERMINED_SPREAD:g}× plausible range [{low:g}, {high:g}]"


#: What a varying scatter means for each method's errors (the end of the ``heteroscedastic`` warning).
VARYING_SCATTER_MEANS = {
    "laplace": "so Laplace reports the robust errors (method laplace-robust)",
    "mcmc": "so the posterior, whose likelihood assumes one scatter, may be too narrow",
}


@float64
def laplace_estimate(
    result: FitResult, density: Density, curvature: Curvature | None = None, *, for_method: str = "laplace"
) -> tuple[Uncertainty, list[Finding]]:
    """The Laplace estimate and what it warns about; ``curvature``: :func:`curvature_at_optimum`, when known.
    ``for_method``: the method whose warnings these are (MCMC reuses what the curvature at the optimum finds)."""
    model, c, labels = density.model, density.n_channels, density.labels
    v = jnp.asarray(density.optimum)
    k = n_free(density)
    chi2, inverse, meat, undetermined, condition = curvature or curvature_at_optimum(density)
    dof = counted_values(density) - k
    reduced = chi2 / dof if dof > 0 else float("nan")
    variance_scale = 1.0 if density.has_sigma else reduced
    covariance_v = variance_scale * inverse
    # The delta method from the sampling coordinates to the physical ones (a no-op except for Lafortune's ψ).
    to_physical = lambda w: model.physical.from_params(model.sampling.to_params(w, c))
    physical = np.asarray(to_physical(v))
    gradient = np.asarray(jax.jacfwd(to_physical)(v))
    covariance = _mapped(gradient, covariance_v)
    stderr = np.sqrt(np.diag(covariance))
    # Without sigma, s² assumes one variance for every residual; the sandwich A⁻¹BA⁻¹ (White 1980) does not.
    # (NaN, an undetermined coordinate's, taken as 0 in the product, so that it spreads to no other; _mapped puts it
    # back where it belongs.)
    held = np.nan_to_num(inverse)
    robust_covariance = _mapped(gradient, np.where(np.isnan(inverse), np.nan, held @ np.nan_to_num(meat) @ held))
    robust = np.sqrt(np.diag(robust_covariance))
    robust[np.isnan(stderr)] = np.nan

    found = []
    if not result.converged:
        found.append(
            Finding(
                codes.NOT_CONVERGED, "the fit did not converge: the uncertainty describes the point where it stopped"
            )
        )
    if dof <= 0 and not density.has_sigma:
        found.append(
            Finding(
                codes.NO_DEGREES_OF_FREEDOM,
                f"{density.n_values} values cannot estimate the noise of {k} parameters; give a sigma column",
            )
        )
    if undetermined:
        why = "; ".join(f"{label} ({reason})" for label, reason in undetermined.items())
        found.append(
            Finding(
                codes.UNDETERMINED,
                f"not determined by these samples: {why}; its error is reported as null (the others' are those with"
                " it held)",
            )
        )
    names = model.physical.labels(tuple(result.channels))
    # Why each physical parameter's error is null: the reason of the first undetermined coordinate it depends on.
    reasons = [
        next((undetermined[labels[j]] for j in np.flatnonzero(row != 0) if labels[j] in undetermined), None)
        for row in gradient
    ]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.isfinite(robust / stderr), robust / stderr, 0.0)
    gauss_newton = stderr
    method = "laplace"
    if not density.has_sigma and ratio.max(initial=0.0) >= HETEROSCEDASTIC_RATIO:
        worst = int(np.argmax(ratio))
        found.append(
            Finding(
                codes.HETEROSCEDASTIC,
                "without sigma the Gauss-Newton errors assume the same scatter for every residual, but the"
                " residuals' scatter varies (e.g. noise proportional to the signal): the heteroscedasticity-robust"
                f" (sandwich) error of {names[worst]} is {ratio[worst]:.1f}× the Gauss-Newton one,"
                f" {VARYING_SCATTER_MEANS[for_method]}; give a sigma column for calibrated errors",
            )
        )
        method, stderr, covariance = "laplace-robust", robust, robust_covariance
    pair = strongest_correlation(labels, correlation(covariance_v))
    if pair is not None and abs(pair[2]) >= DEGENERATE_CORRELATION:
        found.append(
            Finding(
                codes.DEGENERATE,
                f"{pair[0]} and {pair[1]} are nearly degenerate (correlation {pair[2]:+.4f}): the samples fix a"
                " combination of them, so their errors are large and shared; samples at other angles would separate"
                " them",
            )
        )
    z = np.array([NormalDist().inv_cdf(q) for q in QUANTILES])
    quantiles = physical[None, :] + z[:, None] * stderr[None, :]
    # The Gaussian knows no bounds; its quantiles are clipped to each parameter's domain (an albedo stays ≥ 0).
    bounds = np.array([domain.bounds for domain in model.physical.domains(c)])
    quantiles = np.clip(quantiles, bounds[:, 0], bounds[:, 1])
    diagnostics = {
        "reduced_chi2": reduced,
        "dof": dof,
        "noise_scale": None if density.has_sigma else float(np.sqrt(reduced)),
        "condition_number": condition,
        "robust_stderr": None if density.has_sigma else stderr_dict(model, robust, c),
        "gauss_newton_stderr": stderr_dict(model, gauss_newton, c),
        "strongest_correlation": None if pair is None else {"pair": [pair[0], pair[1]], "value": pair[2]},
        "fixed": sorted(result.fixed),
    }
    laid_out = estimate(
        method,
        model,
        tuple(result.channels),
        stderr=stderr,
        quantiles=quantiles,
        covariance=covariance,
        diagnostics=diagnostics,
        findings=found,
        undetermined=reasons,
    )
    return laid_out, found
