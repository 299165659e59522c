"""Synthetic samples from any model and parameters: evaluate, add noise, package as Samples."""

from typing import Any

import numpy as np

from brdffit.data.samples import Samples
from brdffit.data_synth.noise import add_noise
from brdffit.errors import BrdfInputError
from brdffit.physics.evaluate import evaluate


def synthesize(
    model: str,
    params: dict[str, Any],
    wi: np.ndarray,
    wo: np.ndarray,
    *,
    noise: float = 0.0,
    noise_kind: str = "multiplicative",
    seed: int = 0,
    with_sigma: bool = False,
    channels: tuple[str, ...] | None = None,
    **model_options: Any,
) -> Samples:
    """Samples of ``model`` with ``params`` (a result file's parameter dictionary) at pairs ``wi``, ``wo`` (N, 3).

    ``noise``/``noise_kind``/``seed`` as in :func:`brdffit.data_synth.noise.add_noise`;
    ``with_sigma`` stores the noise's 1-σ as the samples' ``sigma``. Channels
    are named ``r, g, b`` for three, ``value`` for one, ``c0, c1, …`` otherwise.
    """
    clean = evaluate(model, params, wi, wo, **model_options)
    values, sigma = add_noise(clean, noise, noise_kind, seed)
    if with_sigma and not np.all(sigma > 0):
        raise BrdfInputError("a sigma column needs noise > 0 and, for multiplicative noise, values > 0 everywhere")
    if channels is None:
        channels = {1: ("value",), 3: ("r", "g", "b")}.get(values.shape[1])
    return Samples.from_arrays(
        wi, wo, values, channels=channels, sigma=sigma if with_sigma else None, source="synthetic"
    )
