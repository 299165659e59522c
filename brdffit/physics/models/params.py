"""A model's parameters as arrays, the form every computation takes, and the layout of a lobe model's parameters."""

from __future__ import annotations  # jaxtyping's Array imports JAX: the annotations stay unevaluated

from collections.abc import Mapping
from typing import TYPE_CHECKING, NamedTuple, Protocol

import numpy as np

from .lobe import Lobe

if TYPE_CHECKING:
    from jaxtyping import Array, Float


class Params(NamedTuple):
    """A model's parameters as arrays (a JAX pytree).

    ``diffuse``: (C,) albedos; ``specular``: (K, C) albedos; ``shape``: lobe-shape parameters, each of
    shape (K,), keyed by their names (``alpha``, ``m``, ``f0``, …), (K, C) for those the lobe takes per channel
    (``Lobe.channel_names``: a conductor's ``eta``, ``k``). Leading batch axes are allowed where a caller vmaps.
    """

    diffuse: Float[Array, "*batch C"] | Float[np.ndarray, "*batch C"]
    specular: Float[Array, "*batch K C"] | Float[np.ndarray, "*batch K C"]
    shape: Mapping[str, Float[Array, "*batch K"] | Float[np.ndarray, "*batch K"] | Float[Array, "*batch K C"]]


class Layout(Protocol):
    """How a lobe model's parameters are laid out, which is all its parameter forms (``dictionary.py``,
    ``coordinates.py``) need of it: a :class:`~brdffit.physics.models.model.LobeModel` is one."""

    # read-only properties: a frozen dataclass (``LobeModel``) satisfies them
    @property
    def name(self) -> str: ...
    @property
    def diffuse(self) -> Lobe: ...
    @property
    def lobe(self) -> Lobe | None: ...
    @property
    def n_lobes(self) -> int: ...
    @property
    def diffuse_name(self) -> str: ...
    @property
    def specular_name(self) -> str: ...
    @property
    def lobes_as_list(self) -> bool: ...
    @property
    def whole(self) -> bool: ...


def albedo_size(model: Layout, n_channels: int) -> int:
    """How many albedos lead a flat vector of ``model`` (``coordinates.py``): a diffuse one and one per lobe in each
    channel, none for a whole-lobe model (its parameters are its lobe's shape)."""
    return 0 if model.whole else (1 + model.n_lobes) * n_channels


def whole_albedos(n_channels: int, xp=np, dtype=float):
    """The albedos a whole-lobe model's :class:`Params` carry: diffuse 0 (C,), the lobe's 1 (1, C); ``xp`` numpy, or
    ``jax.numpy`` inside a program."""
    return xp.zeros(n_channels, dtype), xp.ones((1, n_channels), dtype)


def lobe_family(model: Layout) -> Lobe:
    """``model``'s lobe family, for code that runs only where it has one (``n_lobes > 0``, or a whole-lobe model)."""
    assert model.lobe is not None, f"model {model.name} has no lobes"
    return model.lobe
