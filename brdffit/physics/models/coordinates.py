"""A model's parameters as one flat vector, in each of the three coordinate systems brdffit works in.

Every flat vector is laid out ``[diffuse (C), specular (K·C, lobe by lobe), lobe shapes (K·S, lobe by
lobe), per-channel shapes (K·P·C: lobe, parameter, channel)]``, the last only for a lobe whose P last shape
parameters take one value per channel (``Lobe.channel_names``: a conductor's ``eta``, ``k``; labels ``eta[r]``);
a whole-lobe model (a renderer's own: ``LobeModel.whole``) has no albedos, only its lobe's shapes. The systems differ
only in how an albedo and a lobe's shape become coordinates:

=================  ===================================  ================================================
system             albedos                              shape (``Lobe`` coordinates, ``lobe.py``)
=================  ===================================  ================================================
unconstrained      ``ln rho`` (``ALBEDO``'s map)  each domain's map; Lafortune: ``ψ, ln n``
sampling           the values                           the values; Lafortune: ``ψ, n``
physical           the values                           the values (``cxy, cz, n`` for Lafortune)
=================  ===================================  ================================================

The solver moves the *unconstrained* vector, so every step is physically valid; the MCMC walkers move
the *sampling* vector (where a Lafortune direction stays on ``2 cxy² + cz² = 1``); covariances are
reported in the *physical* one (labels ``rho_d[r]``, ``alpha``, ``lobes[0].cxy``).
"""

import functools
from abc import ABC, abstractmethod
from dataclasses import dataclass, replace
from typing import TypeVar, final

from ..._jax import namespace
from ..domains import ALBEDO, Domain
from .lobe import BoundedShapeCoordinates, PhysicalShape, ShapeCoordinates, UnconstrainedShape
from .params import Layout, Params, albedo_size, lobe_family, whole_albedos


@dataclass(frozen=True)
class FlatCoordinates(ABC):
    """``model``'s parameters as one flat vector in one coordinate system."""

    model: Layout

    @property
    @abstractmethod
    def shape(self) -> ShapeCoordinates:
        """How a lobe's shape becomes coordinates in this system."""

    @abstractmethod
    def albedo_to_vector(self, albedos):
        """The coordinates of albedos."""

    @abstractmethod
    def albedo_from_vector(self, u):
        """Albedos at coordinates ``u`` (JAX-traceable)."""

    @property
    def shared(self) -> ShapeCoordinates:
        """The coordinates of the shape parameters all channels share (all of them, but a lobe's ``channel_names``)."""
        return self._parts[0]

    @property
    def per_channel(self) -> ShapeCoordinates | None:
        """The coordinates of the shape parameters with one value per channel, or None for a lobe without any."""
        return self._parts[1]

    @functools.cached_property
    def _parts(self) -> tuple[ShapeCoordinates, ShapeCoordinates | None]:
        """The shared and the per-channel shape coordinates (None for a lobe without per-channel parameters), made
        once: a capture's texels ask for them several times each."""
        lobe = self.model.lobe
        if lobe is None or not lobe.channel_names:
            return self.shape, None
        # A lobe with per-channel parameters has elementwise coordinates over named parameters (lobe.py).
        shape = self.shape
        if isinstance(shape, PhysicalShape):
            return _split_named(shape, lobe.channel_names)
        assert isinstance(shape, UnconstrainedShape)
        return _split_named(shape, lobe.channel_names)

    def size(self, n_channels: int) -> int:
        """The vector's length for ``n_channels`` channels."""
        k = self.model.n_lobes
        if not k:
            return n_channels
        n_per_channel = len(self.per_channel.names) if self.per_channel else 0
        shapes = k * len(self.shared.names) + k * n_per_channel * n_channels
        return albedo_size(self.model, n_channels) + shapes

    def labels(self, channels: tuple[str, ...]) -> list[str]:
        """A name per entry: ``rho_d[r]``, …, ``lobes[0].rho_s[r]``, …, ``alpha`` or ``lobes[0].psi``, ``eta[r]``."""
        model = self.model
        prefixes = [f"lobes[{k}]." if model.lobes_as_list else "" for k in range(model.n_lobes)]
        labels = [] if model.whole else [f"{model.diffuse_name}[{c}]" for c in channels]
        labels += (
            [] if model.whole else [f"{prefix}{model.specular_name}[{c}]" for prefix in prefixes for c in channels]
        )
        shape_names = self.shared.names if model.n_lobes else ()
        labels += [f"{prefix}{name}" for prefix in prefixes for name in shape_names]
        per_channel = self.per_channel.names if model.n_lobes and self.per_channel else ()
        return labels + [f"{prefix}{name}[{c}]" for prefix in prefixes for name in per_channel for c in channels]

    def from_params(self, params: Params):
        """The flat vector of ``params`` (numpy for numpy parameters)."""
        xp = namespace(params.diffuse, params.specular, *params.shape.values())
        pieces = (
            [] if self.model.whole else [self.albedo_to_vector(params.diffuse), self.albedo_to_vector(params.specular)]
        )
        if self.model.n_lobes:
            shared, per_channel = self._parts
            pieces.append(xp.transpose(shared.to_vector(params.shape)))  # (S, K) → lobe by lobe
            if per_channel is not None:  # (P, K, C) → lobe, parameter, channel
                pieces.append(xp.transpose(per_channel.to_vector(params.shape), (1, 0, 2)))
        return xp.concatenate([xp.ravel(xp.asarray(piece)) for piece in pieces])

    def to_params(self, vector, n_channels: int) -> Params:
        """The parameters at the flat ``vector`` (the inverse of :meth:`from_params`), traceable by JAX."""
        k, n_albedos = self.model.n_lobes, albedo_size(self.model, n_channels)
        if self.model.whole:  # no albedos: a diffuse one of 0, the lobe's 1
            diffuse, specular = whole_albedos(n_channels, namespace(vector), vector.dtype)
        else:
            diffuse = self.albedo_from_vector(vector[:n_channels])
            specular = self.albedo_from_vector(vector[n_channels:n_albedos]).reshape(k, n_channels)
        if not k:
            return Params(diffuse, specular, {})
        shared, per_channel = self._parts
        n_shared = k * len(shared.names)
        per_lobe = vector[n_albedos : n_albedos + n_shared].reshape(k, len(shared.names))
        shape = shared.from_vector(per_lobe.T)
        if per_channel is not None:
            rest = vector[n_albedos + n_shared :].reshape(k, len(per_channel.names), n_channels)
            shape = shape | per_channel.from_vector(rest.transpose(1, 0, 2))  # (P, K, C)
        return Params(diffuse, specular, shape)


_Named = TypeVar("_Named", PhysicalShape, UnconstrainedShape)


def _split_named(shape: _Named, channel_names: tuple[str, ...]) -> tuple[_Named, _Named]:
    """``shape``'s coordinates split into those all channels share and those with one value per channel."""
    shared = tuple(one for one in shape.parameters if one[0] not in channel_names)
    per_channel = tuple(one for one in shape.parameters if one[0] in channel_names)
    return replace(shape, parameters=shared), replace(shape, parameters=per_channel)


class BoundedFlatCoordinates(FlatCoordinates):
    """Coordinates whose entries live in domains (with priors): the sampling and the physical ones, where an
    albedo is its own value."""

    @property
    @abstractmethod
    def shape(self) -> BoundedShapeCoordinates: ...

    def albedo_to_vector(self, albedos):
        return albedos

    def albedo_from_vector(self, u):
        return u

    def domains(self, n_channels: int) -> list[Domain]:
        """The domain of each entry, in :meth:`labels` order."""
        k, diffuse = self.model.n_lobes, [self.model.diffuse.albedo_domain] * n_channels
        if not k:
            return diffuse
        specular = [lobe_family(self.model).albedo_domain] * (k * n_channels)
        shared, per_channel_shape = self._parts  # bounded, as self.shape is
        assert isinstance(shared, BoundedShapeCoordinates)
        assert per_channel_shape is None or isinstance(per_channel_shape, BoundedShapeCoordinates)
        per_channel = [d for d in per_channel_shape.domains for _ in range(n_channels)] if per_channel_shape else []
        albedos = [] if self.model.whole else diffuse + specular
        return albedos + list(shared.domains) * k + per_channel * k


@final
class UnconstrainedCoordinates(FlatCoordinates):
    """What the solver moves: ``ln`` of each albedo, each shape parameter through its domain's map."""

    @property
    def shape(self) -> ShapeCoordinates:
        return lobe_family(self.model).unconstrained

    def albedo_to_vector(self, albedos):
        return ALBEDO.to_unconstrained(albedos)

    def albedo_from_vector(self, u):
        return ALBEDO.to_physical(u)


@final
class SamplingCoordinates(BoundedFlatCoordinates):
    """What the MCMC walkers move: the physical values, but a Lafortune direction as its angle ``ψ``."""

    @property
    def shape(self) -> BoundedShapeCoordinates:
        return lobe_family(self.model).sampling


@final
class PhysicalCoordinates(BoundedFlatCoordinates):
    """The parameters themselves, in which covariances are reported; :meth:`from_params` traces."""

    @property
    def shape(self) -> BoundedShapeCoordinates:
        return lobe_family(self.model).physical
