"""How uncertain a fit's prediction is: the 1-σ band of the fitted BRDF at given directions.

The delta method (lmfit's ``ModelResult.eval_uncertainty``): with ``J = ∂f/∂p`` the derivative of the model's
values at the fitted parameters with respect to the flat physical parameters ``p`` (``Model.physical``, the
covariance's own coordinates, ``uncertainty/layout.py``) and ``C`` the estimate's covariance, the variance of each
predicted value is ``(J C Jᵀ)ᵢᵢ``. It is exact for a parameter that enters linearly (an albedo) and first-order for
the others; for an MCMC estimate ``C`` is the draws' covariance, and the band the same first-order summary of it.
A held parameter's row and column of ``C`` are 0 (no error); an undetermined one's are ``null`` in the file, so a
value that depends on it gets a band of NaN.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ..._jax import float64
from ...errors import Argument, BrdfInputError
from ...physics.evaluate import evaluate
from ...physics.models.registry import model_for

#: Pairs whose derivatives are taken at once: (pairs × channels × parameters) float64 values, ~16 MB for 7 parameters
#: and 3 channels.
CHUNK = 100_000


def prediction_band(result, wi, wo, sigma: float = 1.0) -> np.ndarray:
    """``sigma`` times the standard deviation (N, C) of the predicted BRDF (1/sr) of ``result`` (a
    :class:`~brdffit.FitResult`, which calls this as ``eval_uncertainty``; not imported here) at directions ``wi``,
    ``wo`` (N, 3), from its uncertainty's covariance (module docstring). A result without an uncertainty estimate is
    a one-line error."""
    if not result.uncertainty or "covariance" not in result.uncertainty:
        raise BrdfInputError(
            "this result has no uncertainty estimate: fit with ",
            Argument("uncertainty", "'laplace'"),
            " (or 'mcmc'), or brdffit.laplace_uncertainty(result, samples)",
        )
    if not (isinstance(sigma, int | float) and np.isfinite(sigma) and sigma > 0):
        raise BrdfInputError(Argument.given("sigma", sigma), " must be a positive number (the band's width in σ)")
    values = evaluate(result.model, result.params, wi, wo, **result.model_options)  # checks and normalises
    wi, wo = (np.asarray(w, dtype=np.float64) / np.linalg.norm(w, axis=-1, keepdims=True) for w in (wi, wo))
    model = model_for(result.model, result.params, **result.model_options)
    block = result.uncertainty["covariance"]
    covariance = np.array(
        [[np.nan if item is None else item for item in row] for row in block["matrix"]], dtype=np.float64
    ).reshape(len(block["names"]), len(block["names"]))
    n_channels = len(result.channels)
    with float64():
        point = jnp.asarray(model.physical.from_params(model.dictionary.to_params(result.params)), jnp.float64)

        @jax.jit
        def derivatives(light, viewer):
            def brdf(vector):
                return model.brdf(model.physical.to_params(vector, n_channels), light, viewer)

            return jax.jacfwd(brdf)(point)

        variances = []
        for start in range(0, len(values), CHUNK):
            jacobian = np.asarray(
                derivatives(jnp.asarray(wi[start : start + CHUNK]), jnp.asarray(wo[start : start + CHUNK]))
            )
            variances.append(_variance(jacobian, covariance))
    return sigma * np.sqrt(np.concatenate(variances).reshape(values.shape))


def _variance(jacobian: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """``(J C Jᵀ)ᵢᵢ`` for each value: ``jacobian`` (N, C, p), ``covariance`` (p, p) with NaN for an undetermined
    entry (which reaches only the values that depend on it: a zero derivative leaves it out)."""
    used = jacobian != 0.0
    known = np.where(np.isnan(covariance), 0.0, covariance)
    variance = np.einsum("ncp,pq,ncq->nc", jacobian, known, jacobian)
    unknown = np.isnan(covariance).any(axis=1)
    return np.where((used & unknown).any(axis=-1), np.nan, np.maximum(variance, 0.0))
