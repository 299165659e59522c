"""Evaluate a model with the result file's parameters at given directions: the public, checked entry point."""

from typing import Any

import numpy as np

from ..errors import BrdfInputError
from .geometry import UNIT_LENGTH_TOLERANCE, normalised
from .models.model import Model
from .models.registry import model_for


def evaluate(model: str | Model, params: dict[str, Any], wi, wo, **options: Any) -> np.ndarray:
    """BRDF values (N, C) in 1/sr of ``model`` with ``params`` at directions ``wi``, ``wo`` (N, 3).

    ``params`` is the result file's parameter dictionary; ``options`` are the model's options
    (``fresnel=``, ``lobes=``; Lafortune's number of lobes is that of ``params["lobes"]`` unless given).
    Directions are unit vectors in the local frame (within 1e-3, then normalised; any other length is an
    error); pairs with either ``z ≤ 0`` give 0. Returns a float64 numpy array (the model's ``host_brdf``, whose JAX
    computation is :meth:`Model.brdf`).
    """
    model = model_for(model, params, **options)
    checked = model.dictionary.to_params(params)
    wi = _directions(wi, "wi")
    wo = _directions(wo, "wo")
    if wi.shape != wo.shape:
        raise BrdfInputError(f"wi and wo must have the same shape, got {wi.shape} and {wo.shape}")
    return model.host_brdf(checked, wi, wo)


def _directions(value, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise BrdfInputError(f"{name} must be an (N, 3) array of numbers") from None
    if array.ndim != 2 or array.shape[1] != 3:
        raise BrdfInputError(f"{name} must have shape (N, 3), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise BrdfInputError(f"{name} contains NaN or infinite values")
    return normalised(
        array,
        lambda row, length: (
            f"{name} row {row}: length {length:.6g} is not 1 (directions must be unit vectors,"
            f" within {UNIT_LENGTH_TOLERANCE:g})"
        ),
    )
