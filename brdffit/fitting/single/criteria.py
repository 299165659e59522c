"""How well a fit explains its data, counted as lmfit counts it: ``ndata``, ``nvarys``, ``chisqr``, ``redchi``, and
the information criteria AIC and BIC (Akaike 1974; Schwarz 1978) by which ``brdffit compare`` ranks models.

With ``n`` fitted values (samples with a nonzero weight × channels) and ``k`` free parameters (``nvarys``: not those
the fit held), the residuals ``r`` of the fit's loss and ``Σr²`` its ``cost`` (``chisqr``):

* without ``sigma`` the noise scale is unknown and profiled out of a Gaussian likelihood, the same for every model:
  ``AIC = n ln(Σr²/n) + 2k``, ``BIC = n ln(Σr²/n) + k ln n`` (lmfit's ``aic`` and ``bic``);
* with ``sigma`` the residuals are in units of σ and ``−2 ln L = χ² = Σr²``: ``AIC = χ² + 2k``, ``BIC = χ² + k ln n``.

``redchi = Σr²/(n − k)``, NaN where ``n ≤ k``.
"""

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Criteria:
    """lmfit's figures of one fit (module docstring)."""

    ndata: int
    nvarys: int
    chisqr: float
    redchi: float
    aic: float
    bic: float


def criteria(cost: float, n_values: int, n_free: int, sigma: bool) -> Criteria:
    """The :class:`Criteria` of a fit of ``cost`` (``Σr²``) to ``n_values`` values with ``n_free`` free parameters;
    ``sigma``: whether its residuals were divided by the samples' sigma."""
    n, k = int(n_values), int(n_free)
    deviance = cost if sigma else n * math.log(max(cost, np.finfo(float).tiny) / n)
    redchi = cost / (n - k) if n > k else math.nan
    return Criteria(n, k, float(cost), redchi, deviance + 2 * k, deviance + k * math.log(n))


def fitted_values(n_samples: int, n_channels: int, weight: np.ndarray | None) -> int:
    """How many values a fit of samples with ``weight`` (N,) (None: all 1) counts: the samples with a nonzero weight
    times the channels."""
    counted = n_samples if weight is None else int(np.sum(np.asarray(weight) > 0))
    return counted * n_channels
