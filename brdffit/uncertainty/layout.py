"""An uncertainty estimate laid out as the result file holds it, from draws or a covariance.

Standard errors and quantiles take the layout of ``params`` (per-channel
values as lists in channel order, Lafortune lobes as a list); the covariance
and correlation matrices are over the flat physical parameters
(``Model.physical``). Values that cannot be determined (a parameter the
data do not constrain) are written as ``null``.
"""

import math
from typing import Any

import numpy as np

from ..fitting.single.result import Uncertainty
from ..physics.models.model import Model
from .findings import Finding

#: The quantiles written for every parameter: the median and the central 68% and 95% intervals.
QUANTILES = (0.025, 0.16, 0.5, 0.84, 0.975)


def params_layout(model: Model, values: np.ndarray, n_channels: int) -> dict[str, Any]:
    """A flat physical vector (one value per ``model.physical.labels``) in the layout of ``params``."""
    physical = model.physical.to_params(np.asarray(values, dtype=float), n_channels)
    return model.dictionary.from_params(physical)


def stderr_dict(model: Model, stderr: np.ndarray, n_channels: int) -> dict[str, Any]:
    """Standard errors in the layout of ``params``."""
    return json_ready(params_layout(model, stderr, n_channels))


def quantile_dict(model: Model, values_per_quantile: np.ndarray, n_channels: int) -> dict[str, Any]:
    """``{name: {"0.16": value-or-list, …}}`` from a (len(QUANTILES), p) array of physical vectors."""
    layouts = [params_layout(model, row, n_channels) for row in values_per_quantile]

    def nest(items):
        first = items[0]
        if isinstance(first, dict):
            return {key: nest([item[key] for item in items]) for key in first}
        if isinstance(first, list) and first and isinstance(first[0], dict):  # Lafortune's lobes
            return [nest([item[i] for item in items]) for i in range(len(first))]
        return {f"{q:g}": item for q, item in zip(QUANTILES, items, strict=True)}

    return json_ready(nest(layouts))


def reasons_dict(model: Model, reasons: list[str | None], n_channels: int) -> dict[str, Any]:
    """Why each error is null (one reason or None per ``model.physical.labels``), in the layout of ``params``; ``{}``
    when every error is determined."""
    distinct = list(dict.fromkeys(reason for reason in reasons if reason is not None))
    if not distinct:
        return {}
    codes = np.array([0.0 if reason is None else distinct.index(reason) + 1.0 for reason in reasons])

    def named(value):
        if isinstance(value, dict):
            return {key: named(item) for key, item in value.items()}
        if isinstance(value, list | tuple):
            return [named(item) for item in value]
        code = round(float(value))
        return distinct[code - 1] if code else None

    return named(params_layout(model, codes, n_channels))


def matrix_block(names: list[str], matrix: np.ndarray) -> dict[str, Any]:
    return {"names": list(names), "matrix": json_ready(np.asarray(matrix).tolist())}


def correlation(covariance: np.ndarray) -> np.ndarray:
    """The correlation matrix of ``covariance``; NaN where a variance is 0, infinite or undetermined."""
    stderr = np.sqrt(np.diag(covariance))
    with np.errstate(divide="ignore", invalid="ignore"):
        result = covariance / np.outer(stderr, stderr)
    result[~np.isfinite(result)] = np.nan
    np.fill_diagonal(result, np.where(np.isfinite(stderr) & (stderr > 0), 1.0, np.nan))
    return result


def strongest_correlation(names: list[str], matrix: np.ndarray) -> tuple[str, str, float] | None:
    """The pair of distinct parameters with the largest ``|correlation|`` (None for fewer than two)."""
    best = None
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            value = matrix[i, j]
            if np.isfinite(value) and (best is None or abs(value) > abs(best[2])):
                best = (names[i], names[j], float(value))
    return best


def json_ready(value: Any) -> Any:
    """``value`` with numpy numbers as floats and NaN or infinities as None (JSON has neither)."""
    if isinstance(value, dict):
        return {key: json_ready(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(item) for item in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, bool | str | int) or value is None:
        return value
    value = float(value)
    return value if math.isfinite(value) else None


def estimate(
    method: str,
    model: Model,
    channels: tuple[str, ...],
    *,
    stderr: np.ndarray,
    quantiles: np.ndarray,
    covariance: np.ndarray,
    diagnostics: dict[str, Any],
    findings: list[Finding],
    undetermined: list[str | None] | None = None,
) -> Uncertainty:
    """An :class:`Uncertainty` from flat physical vectors: ``stderr`` (p,), ``quantiles`` (len(QUANTILES), p) and
    the ``covariance`` (p, p), laid out as the result file holds them (NaN becomes None); ``undetermined``: why each
    null error is null (None for a determined one)."""
    names, n_channels = model.physical.labels(tuple(channels)), len(channels)
    return Uncertainty(
        method=method,
        stderr=stderr_dict(model, stderr, n_channels),
        quantiles=quantile_dict(model, quantiles, n_channels),
        covariance=matrix_block(names, covariance),
        correlation=matrix_block(names, correlation(covariance)),
        diagnostics=json_ready(diagnostics),
        warnings=[finding.message for finding in findings],
        warning_codes=[finding.code for finding in findings],
        undetermined=reasons_dict(model, undetermined or [None] * len(names), n_channels),
    )
