"""A model's parameters as arrays, the form every computation takes."""

from __future__ import annotations  # jaxtyping's Array imports JAX: the annotations stay unevaluated

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from jaxtyping import Array, Float


class Params(NamedTuple):
    """A model's parameters as arrays (a JAX pytree).

    ``diffuse``: (C,) albedos; ``specular``: (K, C) albedos; ``shape``: lobe-shape parameters, each of
    shape (K,), keyed by their names (``alpha``, ``m``, ``f0``, …). Leading batch axes are allowed
    where a caller vmaps.
    """

    diffuse: Float[Array, "*batch C"] | Float[np.ndarray, "*batch C"]
    specular: Float[Array, "*batch K C"] | Float[np.ndarray, "*batch K C"]
    shape: dict[str, Float[Array, "*batch K"] | Float[np.ndarray, "*batch K"]]
