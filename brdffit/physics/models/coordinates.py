"""A model's parameters as one flat vector, in each of the three coordinate systems brdffit works in.

Every flat vector is laid out ``[diffuse (C), specular (K·C, lobe by lobe), lobe shapes (K·S, lobe by
lobe)]``; the systems differ only in how an albedo and a lobe's shape become coordinates:

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

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import final

from ..._jax import namespace
from ..domains import ALBEDO, Domain
from .lobe import BoundedShapeCoordinates, ShapeCoordinates
from .params import Layout, Params


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

    def size(self, n_channels: int) -> int:
        """The vector's length for ``n_channels`` channels."""
        k = self.model.n_lobes
        return (1 + k) * n_channels + (k * len(self.shape.names) if k else 0)

    def labels(self, channels: tuple[str, ...]) -> list[str]:
        """A name per entry: ``rho_d[r]``, …, ``lobes[0].rho_s[r]``, …, ``alpha`` or ``lobes[0].psi``."""
        model = self.model
        labels = [f"{model.diffuse_name}[{c}]" for c in channels]
        prefixes = [f"lobes[{k}]." if model.lobes_as_list else "" for k in range(model.n_lobes)]
        labels += [f"{prefix}{model.specular_name}[{c}]" for prefix in prefixes for c in channels]
        shape_names = self.shape.names if model.n_lobes else ()
        return labels + [f"{prefix}{name}" for prefix in prefixes for name in shape_names]

    def from_params(self, params: Params):
        """The flat vector of ``params`` (numpy for numpy parameters)."""
        xp = namespace(params.diffuse, params.specular, *params.shape.values())
        pieces = [self.albedo_to_vector(params.diffuse), self.albedo_to_vector(params.specular)]
        if self.model.n_lobes:
            pieces.append(xp.transpose(self.shape.to_vector(params.shape)))  # (S, K) → lobe by lobe
        return xp.concatenate([xp.ravel(xp.asarray(piece)) for piece in pieces])

    def to_params(self, vector, n_channels: int) -> Params:
        """The parameters at the flat ``vector`` (the inverse of :meth:`from_params`), traceable by JAX."""
        k = self.model.n_lobes
        n_albedos = (1 + k) * n_channels
        diffuse = self.albedo_from_vector(vector[:n_channels])
        specular = self.albedo_from_vector(vector[n_channels:n_albedos]).reshape(k, n_channels)
        if not k:
            return Params(diffuse, specular, {})
        per_lobe = vector[n_albedos:].reshape(k, len(self.shape.names))
        return Params(diffuse, specular, self.shape.from_vector(per_lobe.T))


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
        specular = [self.model.lobe.albedo_domain] * (k * n_channels)
        return diffuse + specular + list(self.shape.domains) * k


@final
class UnconstrainedCoordinates(FlatCoordinates):
    """What the solver moves: ``ln`` of each albedo, each shape parameter through its domain's map."""

    @property
    def shape(self) -> ShapeCoordinates:
        return self.model.lobe.unconstrained

    def albedo_to_vector(self, albedos):
        return ALBEDO.to_unconstrained(albedos)

    def albedo_from_vector(self, u):
        return ALBEDO.to_physical(u)


@final
class SamplingCoordinates(BoundedFlatCoordinates):
    """What the MCMC walkers move: the physical values, but a Lafortune direction as its angle ``ψ``."""

    @property
    def shape(self) -> BoundedShapeCoordinates:
        return self.model.lobe.sampling


@final
class PhysicalCoordinates(BoundedFlatCoordinates):
    """The parameters themselves, in which covariances are reported; :meth:`from_params` traces."""

    @property
    def shape(self) -> BoundedShapeCoordinates:
        return self.model.lobe.physical
