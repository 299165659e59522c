"""Lobe families: specular lobes of unit albedo, ``lobe(shape; wi, wo)`` in 1/sr, and their shape's coordinates.

A :class:`Lobe` says which shape parameters it has (names and domains), where the fit starts from (a
coarse ``grid`` of shapes spanning real materials) and how to evaluate it. Its shape exists in three
coordinate systems (:class:`ShapeCoordinates`): the *physical* values themselves; the *unconstrained*
ones the solver moves (through each domain's smooth map, ``domains.py``); and the *sampling* ones the
MCMC walkers move (the physical values unless a lobe says otherwise). A Lafortune lobe's direction is
one angle ``ψ`` in the last two (``lafortune.py``).

Abstract classes here, final concrete classes in the family modules (equinox's abstract/final pattern: an
abstract class may implement methods, a concrete one never overrides them). Most families are a
:class:`MappedLobe`; Lafortune's is a :class:`Lobe` with coordinates of its own; the anisotropic microfacet lobe
a :class:`MappedShapeLobe` with a canonical form of its own (``cook_torrance.py``); a renderer's own material, the whole
BRDF as one lobe, a :class:`WholeLobe` (``physics/renderers``).
"""

from __future__ import annotations  # jaxtyping's Array imports JAX: the annotations stay unevaluated

import functools
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, final

import numpy as np

from ..._jax import namespace
from ..._programs.keys import dataclass_key
from ...errors import BrdfInputError
from ..domains import ALBEDO, Domain, MappedDomain

if TYPE_CHECKING:
    from jaxtyping import Array, Float

    from ..geometry import Directions

#: A lobe's shape: each parameter's value, an array (K,) for K lobes or a number for one; a parameter with one value
#: per channel (:attr:`Lobe.channel_names`) an array (K, C), or (C,) for one lobe.
Shape = Mapping[str, Any]


class ShapeCoordinates(ABC):
    """A lobe's shape parameters in one coordinate system, one coordinate per entry of :attr:`names`.

    Both maps work elementwise, so one call serves all K lobes of a model: :meth:`to_vector` turns a
    shape of (K,) arrays into an (S, K) array, :meth:`from_vector` an (S, …) array back into a shape.
    """

    @property
    @abstractmethod
    def names(self) -> tuple[str, ...]:
        """The coordinates' names, e.g. ``("psi", "n")``."""

    @abstractmethod
    def to_vector(self, shape: Shape):
        """The coordinates (S, …) of physical ``shape`` (numpy on the host; traceable where documented)."""

    @abstractmethod
    def from_vector(self, u) -> dict[str, Any]:
        """The physical shape at coordinates ``u`` (S, …), traceable by JAX."""


class BoundedShapeCoordinates(ShapeCoordinates):
    """Coordinates that live in domains of their own (the physical and the sampling ones)."""

    @property
    @abstractmethod
    def domains(self) -> tuple[Domain, ...]:
        """Each coordinate's domain, with the prior the posterior puts on it."""


@final
@dataclass(frozen=True)
class PhysicalShape(BoundedShapeCoordinates):
    """The parameters themselves; :meth:`to_vector` also traces (the delta method differentiates it)."""

    parameters: tuple[tuple[str, Domain], ...]

    @functools.cached_property
    def names(self) -> tuple[str, ...]:
        """The parameters' names, made once (a capture's texels ask for them several times each)."""
        return tuple(name for name, _ in self.parameters)

    @property
    def domains(self) -> tuple[Domain, ...]:
        return tuple(domain for _, domain in self.parameters)

    def to_vector(self, shape: Shape):
        xp = namespace(*(shape[name] for name in self.names))
        return xp.stack([xp.asarray(shape[name]) for name in self.names])

    def from_vector(self, u) -> dict[str, Any]:
        return {name: u[i] for i, name in enumerate(self.names)}


@final
@dataclass(frozen=True)
class UnconstrainedShape(ShapeCoordinates):
    """Each parameter through its domain's smooth map from the real line (``x = to_physical(u)``)."""

    parameters: tuple[tuple[str, MappedDomain], ...]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.parameters)

    def to_vector(self, shape: Shape) -> np.ndarray:
        xp = namespace(*(shape[name] for name, _ in self.parameters))
        return xp.stack([domain.to_unconstrained(shape[name]) for name, domain in self.parameters])

    def from_vector(self, u) -> dict[str, Any]:
        return {name: domain.to_physical(u[i]) for i, (name, domain) in enumerate(self.parameters)}


class Lobe(ABC):
    """A family of specular lobes of unit albedo, ``lobe(shape; wi, wo)`` in 1/sr.

    Concrete lobes are frozen dataclasses, hence hashable: JAX treats them as static configuration.
    """

    #: The shape parameters that make the lobe of an isotropic model (``LobeModel.isotropic``) anisotropic, which the
    #: model holds by default at values that keep it isotropic (glTF's ``anisotropy_strength`` 0, and its rotation): a
    #: fit that frees them, or holds them elsewhere, is checked as an anisotropic model's (``caveats.py``).
    anisotropy_names: tuple[str, ...] = ()

    @property
    def channel_names(self) -> tuple[str, ...]:
        """The shape parameters that take one value per channel (a conductor's complex index ``eta``, ``k``), the last
        of :attr:`names`; with any, the lobe's values are (N, C), one lobe per channel. Every coordinate map of a lobe
        with such parameters is elementwise (a :class:`MappedLobe`'s), so one map serves all channels. None by
        default; a lobe overrides it with a class attribute or a property."""
        return ()

    @property
    def meaningful_ends(self) -> tuple[str, ...]:
        """The shape parameters whose domain's ends are values of their own, not limits a fit runs into (glTF's
        ``metallic``: 0 is a dielectric, 1 a metal): a fit ending there is not warned about. None by default."""
        return ()

    @property
    def channels_coupled(self) -> bool:
        """Whether a channel's value depends on other channels' parameters (principled's tints divide the colour by
        its luminance): then the fit takes the model's whole Jacobian, one forward-mode tangent per parameter and
        channel, where a lobe of per-channel parameters otherwise takes one tangent per parameter for every channel at
        once. False by default."""
        return False

    def channel_grid(self, channels: tuple[str, ...]) -> tuple[dict[str, Any], ...]:
        """Starting shapes beside :attr:`grid` whose :attr:`channel_names` have one value per channel (a list in the
        order of ``channels``, the data's channel names): measured materials. None by default."""
        return ()

    @property
    def fusion_emitters(self) -> bool:
        """Whether XLA's CPU fusion emitters compile the programs that fit this lobe into faster code than the classic
        emitters brdffit compiles with otherwise (``_programs/jit.py``, where the measurements are): glTF's and
        ``roughplastic``'s whole-lobe materials. False by default."""
        return False

    @property
    def separable(self) -> bool:
        """Whether the lobe, one with :attr:`channel_names`, is the product of a factor of its other parameters alone
        (:meth:`shared_factor`, (N,)) and one of its per-channel parameters alone (:meth:`channel_factor`, (N, C)): a
        microfacet lobe's ``D·G/(4 ci co)`` and its Fresnel term. A start search then evaluates each distinct factor
        of its grid once, not once a grid shape (``fitting/starts/grid.py``). False by default."""
        return False

    def shared_factor(self, shape: Shape, wi: Directions, wo: Directions) -> Float[Array, " n"]:
        """The factor (N,) of a :attr:`separable` lobe that its shared (not per-channel) parameters determine."""
        raise NotImplementedError(f"{type(self).__name__} is not separable")

    def channel_factor(self, shape: Shape, wi: Directions, wo: Directions) -> Float[Array, "n C"]:
        """The factor (N, C) of a :attr:`separable` lobe that its :attr:`channel_names` determine."""
        raise NotImplementedError(f"{type(self).__name__} is not separable")

    @property
    @abstractmethod
    def summary(self) -> str:
        """The lobe's formula in a line, for ``brdffit models``."""

    @property
    @abstractmethod
    def parameters(self) -> tuple[tuple[str, Domain], ...]:
        """The shape parameters (name, domain), in the order of the result file."""

    @property
    @abstractmethod
    def albedo_domain(self) -> Domain:
        """The domain of the lobe's albedo: ``ALBEDO`` (at most 1 is plausible) where the albedo is the lobe's
        reflectance, a plain non-negative scale where a Fresnel term or an approximate normalisation also scales it."""

    @property
    @abstractmethod
    def peaks_at_mirror(self) -> bool:
        """Whether the lobe is largest at the mirror direction of the incidence, for every incidence: then a coarse
        grid with the value there added bounds its directional albedo (``fitting/single/caveats.py``'s screen);
        Lafortune's lobes, which may point anywhere, are not."""

    @property
    @abstractmethod
    def grid(self) -> tuple[dict[str, float], ...]:
        """Starting shapes for the fit: coarse, but spanning realistic materials."""

    @abstractmethod
    def __call__(
        self,
        shape: Shape,
        wi: Directions,
        wo: Directions,
    ) -> Float[Array, " n"]:
        """Lobe values (N,) in 1/sr for directions (N, 3) with positive ``z``; ``shape`` of scalars (of arrays (C,)
        for the :attr:`channel_names`, and then values (N, C))."""

    @property
    @abstractmethod
    def unconstrained(self) -> ShapeCoordinates:
        """What the solver moves."""

    @property
    @abstractmethod
    def sampling(self) -> BoundedShapeCoordinates:
        """What the MCMC walkers move."""

    @abstractmethod
    def checked_shape(self, shape: Shape, where: str) -> dict[str, float]:
        """The shape (numbers) with each value checked against its domain; ``where`` prefixes errors."""

    @abstractmethod
    def shape_holding(self, given: Shape, where: str) -> dict[str, float]:
        """A valid shape (numbers) with the ``given`` values (a user's fixed values or bounds, checked against their
        domains), the family's first grid shape elsewhere; ``where`` prefixes errors (``lobes[1].``)."""

    @abstractmethod
    def canonical(self, shape: Shape) -> dict[str, Any]:
        """``shape`` (numpy, a (K,) array per name) in the family's canonical form: where two shapes give the same
        lobe (an anisotropic lobe's ``α_u ↔ α_v`` with its tangent turned by 90°), the one a fit reports."""

    @abstractmethod
    def coordinate_index(self, name: str) -> int:
        """Which of the solver's (and the walkers') shape coordinates carries the shape parameter ``name``: a user
        who fixes or bounds ``name`` holds that coordinate."""

    @functools.cached_property
    def names(self) -> tuple[str, ...]:
        """The shape parameters' names, made once a lobe: a capture's texels ask for them ~50 times each."""
        return tuple(name for name, _ in self.parameters)

    @property
    def physical(self) -> BoundedShapeCoordinates:
        return PhysicalShape(self.parameters)

    def cache_key(self) -> list | None:
        """What the lobe's programs depend on (``brdffit/_programs/keys.py``): its fields (a lobe family is a frozen
        dataclass; its class, and that class's source if it is not brdffit's, are added by ``key_of``)."""
        return dataclass_key(self)


class MappedShapeLobe(Lobe):
    """A lobe whose every shape parameter lives in a :class:`~brdffit.physics.domains.MappedDomain`: the solver
    moves each through its domain's map, the walkers move the values themselves. Most families are a
    :class:`MappedLobe`; the anisotropic microfacet lobe, whose shapes come in twins, says its canonical one."""

    @property
    @abstractmethod
    def parameters(self) -> tuple[tuple[str, MappedDomain], ...]: ...

    @property
    def unconstrained(self) -> ShapeCoordinates:
        return UnconstrainedShape(self.parameters)

    @property
    def sampling(self) -> BoundedShapeCoordinates:
        return self.physical

    def coordinate_index(self, name: str) -> int:
        return self.names.index(name)

    def shape_holding(self, given: Shape, where: str) -> dict[str, float]:
        return self.checked_shape(dict(self.grid[0]) | dict(given), where)

    def checked_shape(self, shape: Shape, where: str) -> dict[str, Any]:
        for name, domain in self.parameters:
            if not domain.contains(shape[name]):
                raise BrdfInputError(f"{where}{name} = {shape[name]!r} is outside its domain {domain.text}")
        per_channel = lambda name: np.asarray(shape[name], float)  # a list of one value per channel stays one
        return {name: per_channel(name) if name in self.channel_names else float(shape[name]) for name in self.names}


class MappedLobe(MappedShapeLobe):
    """A lobe whose every shape parameter lives in a :class:`~brdffit.physics.domains.MappedDomain` (the solver
    moves each through its domain's map, the walkers move the values themselves: :class:`MappedShapeLobe`) and whose
    every shape is a lobe of its own: the usual base of a family."""

    def canonical(self, shape: Shape) -> dict[str, Any]:
        return dict(shape)


class WholeLobe(MappedLobe):
    """A lobe that is a whole material, the one lobe of a whole-lobe model (``LobeModel.whole``: a renderer's own,
    ``physics/renderers``): every parameter is its shape's, its colour among them (:attr:`channel_names`), and no albedo
    scales it."""

    @property
    def albedo_domain(self) -> Domain:
        """Never asked of a whole material, which has no albedo: the plain albedo's domain."""
        return ALBEDO
