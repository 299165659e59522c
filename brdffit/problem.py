"""A fitting problem as arrays, and its residual vector.

The residual of sample ``n``, channel ``c`` is
``scale[n, c] · (T(f(wi_n, wo_n))[c] - T(y)[n, c])`` with ``T`` the loss transform
(``losses.py``) and ``f`` the model at the parameters the unconstrained vector
``theta`` maps to (``models/base.py``).
"""

from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np

from .losses import Loss, residual_scale
from .models import Model
from .samples import Samples


class Problem(NamedTuple):
    """The data of one fit, as arrays (a JAX pytree, so one compiled solver serves every dataset of a shape)."""

    wi: Any  # (N, 3)
    wo: Any  # (N, 3)
    measured: Any  # (N, C) BRDF, 1/sr
    target: Any  # (N, C) T(measured)
    scale: Any  # (N, C)


def build_problem(loss: Loss, samples: Samples) -> Problem:
    cos_i = samples.wi[:, 2]
    measured = samples.values
    target = np.asarray(loss.transform(jnp.asarray(measured), measured, cos_i[:, None]))
    scale = residual_scale(loss, measured, cos_i, samples.sigma, samples.weight)
    return Problem(*(jnp.asarray(a) for a in (samples.wi, samples.wo, measured, target, scale)))


def residuals(model: Model, loss: Loss, theta, problem: Problem):
    """Residuals (N, C) at the unconstrained parameters ``theta``."""
    params = model.from_unconstrained(theta, problem.measured.shape[1])
    predicted = model.evaluate(params, problem.wi, problem.wo)
    transformed = loss.transform(predicted, problem.measured, problem.wi[:, 2:3])
    return (transformed - problem.target) * problem.scale
