"""What a model is: :class:`Model`, what every part of brdffit asks of one, and its two kinds.

Abstract and final, as in equinox (``docs/pattern.md`` there): :class:`Model` is abstract, and the kinds of model are
final siblings, none a subclass of another:

* :class:`LobeModel` (here): a diffuse term plus ``K`` specular lobes of one family, linear in its albedos::

      f(wi, wo)[c] = diffuse[c] · d(wi, wo) + Σ_k specular[k, c] · lobe(shape[k]; wi, wo)

  with ``d`` the diffuse term (``diffuse.py``: Lambert's ``1/π``) and ``lobe`` a unit-albedo lobe family
  (``lobe.py``: Ward, Cook-Torrance, Phong, …). Diffuse and specular albedos are per channel, lobe shapes shared by
  all channels but the parameters a lobe takes per channel (``Lobe.channel_names``: a conductor's index), with which
  ``lobe`` is one per channel, ``lobe_c``. The fit's starts and its normal equations use the linearity
  (``brdffit/fitting``). A renderer's own model (glTF's metallic-roughness, Mitsuba's ``principled``) is a *whole*
  lobe model: its one lobe is the whole BRDF, every parameter a shape parameter (``base_color`` per channel), with
  no albedos to fit or write (``whole``).
* ``PcaModel`` (``brdffit/datadriven/model.py``): the coefficients of a basis learned from measured tables.

Code that needs a kind's own parts (lobes, a basis) dispatches on the kind (``isinstance``), never on flags. A
model's parameters exist in several forms, each with its conversions on one object (``coordinates.py`` has the
table of which form is used where). :class:`ModelEntry` is what the registry (``registry.py``) knows about a model
beyond the model itself: the specs ``brdffit compare`` tries, the options' choices ``brdffit models`` lists, and the
exact exports to renderers.
"""

from __future__ import annotations  # jaxtyping's Array imports JAX: the annotations stay unevaluated

import functools
import importlib
import inspect
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, final

import numpy as np

from ..._jax import jax, jnp
from ..._programs import jit
from ..._programs.keys import key_of
from ...errors import BrdfInputError
from ..geometry import above_horizon
from .coordinates import PhysicalCoordinates, SamplingCoordinates, UnconstrainedCoordinates
from .dictionary import ParameterDictionary
from .diffuse import LAMBERTIAN
from .lobe import Lobe, WholeLobe
from .params import Params, lobe_family

if TYPE_CHECKING:
    from jaxtyping import Array, Float

    from ..geometry import Directions


class Model(ABC):
    """A reflectance model, as every part of brdffit sees it (abstract: :class:`LobeModel` and ``PcaModel`` are its
    kinds).

    ``name`` is the model's registry name (``ward``); ``options`` the options that define it (``fresnel``,
    ``lobes``, …) as ``(key, value)`` pairs in the order its builder takes them, written to the result file as
    ``model_options``; ``isotropic``: whether rotating both directions about the normal changes nothing. A model is
    hashable: JAX treats it as static configuration, and its :meth:`cache_key` names it to programs stored on disk.
    """

    name: str
    summary: str
    options: tuple[tuple[str, Any], ...]
    isotropic: bool

    @property
    def model_options(self) -> dict[str, Any]:
        return dict(self.options)

    # ------------------------------------------------------------------ evaluation
    @abstractmethod
    def brdf(
        self,
        params: Params,
        wi: Directions,
        wo: Directions,
    ) -> Float[Array, "n C"]:
        """BRDF values (N, C) in 1/sr (JAX) at directions ``wi``, ``wo`` (N, 3), JAX or numpy arrays; zero where
        ``wi_z ≤ 0`` or ``wo_z ≤ 0``; plain JAX in the caller's precision (float32 unless the caller has float64 on)."""

    @abstractmethod
    def host_brdf(self, params: Params, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        """:meth:`brdf` as float64 numpy, for unit directions (N, 3) on the host: what :func:`brdffit.evaluate`
        returns."""

    @property
    @abstractmethod
    def prior_weight(self) -> float:
        """The weight ``W`` of a Gaussian prior that the fit's cost includes, ``Σ r² + W·Σ v²`` over the sampling
        vector ``v`` (0: none). Its ``W·Σ v²`` counts as that many more residuals wherever the cost is turned into a
        likelihood (``uncertainty/density.py``)."""

    @property
    def fusion_emitters(self) -> bool:
        """Whether the model's programs compile with XLA's fusion emitters (``Lobe.fusion_emitters``). False by
        default."""
        return False

    # ------------------------------------------------------------ parameter forms
    @property
    @abstractmethod
    def dictionary(self):
        """The parameters as the result file writes them: ``to_params``, ``from_params``, ``names``."""

    @property
    @abstractmethod
    def unconstrained(self):
        """The flat vector the solver moves: ``from_params``, ``to_params``, ``size``, ``labels``."""

    @property
    @abstractmethod
    def sampling(self):
        """The flat vector the MCMC walkers move; also ``domains``, with their priors."""

    @property
    @abstractmethod
    def physical(self):
        """The flat vector of the parameters themselves, in which covariances are reported."""

    @abstractmethod
    def cache_key(self) -> list | None:
        """What this model's compiled programs depend on, as JSON (``brdffit/_programs/keys.py``): two models that
        compute differently never share a key. None: its programs are compiled in each process, never stored."""


@final
@dataclass(frozen=True)
class LobeModel(Model):
    """A diffuse term plus ``n_lobes`` lobes of one family (module docstring).

    ``diffuse_name`` and ``specular_name`` name the albedos in the result file (``rho_d``, ``rho_s``; Cook-Torrance's
    ``kd``, ``ks``); ``lobes_as_list``: the result file writes the lobes as a list, ``"lobes": [{...}, ...]``
    (Lafortune's); ``diffuse``: the diffuse term, a lobe without shape parameters (Lambert's); ``held``: parameters
    the fit holds unless a user frees them, ``(name, value)`` by the result file's names (a conductor's ``ks`` at 1:
    its Fresnel term is its reflectance; ``fitting/single/constraints.py``). Frozen, hence hashable: JAX treats a
    model as static configuration.
    """

    name: str
    summary: str
    lobe: Lobe | None = None
    n_lobes: int = 0
    diffuse_name: str = "rho_d"
    specular_name: str = "rho_s"
    options: tuple[tuple[str, Any], ...] = ()
    isotropic: bool = True
    lobes_as_list: bool = False
    diffuse: Lobe = LAMBERTIAN
    held: tuple[tuple[str, Any], ...] = ()
    whole: bool = False

    def __post_init__(self):
        if self.whole and (self.n_lobes != 1 or not isinstance(self.lobe, WholeLobe) or not self.lobe.channel_names):
            raise BrdfInputError(
                f"model {self.name}: a whole-lobe model has one lobe, a WholeLobe with a parameter per channel"
                " (its colour)"
            )
        if (self.lobe is None) != (self.n_lobes == 0):
            raise BrdfInputError(f"model {self.name}: give a lobe family exactly when n_lobes > 0")
        if self.diffuse.names:
            raise BrdfInputError(
                f"model {self.name}: a diffuse term with shape parameters ({', '.join(self.diffuse.names)}) is not"
                " supported yet; fit it as a lobe"
            )

    # ------------------------------------------------------------------ evaluation
    def brdf(self, params: Params, wi, wo):
        visible, wi, wo = above_horizon(jnp.asarray(wi), jnp.asarray(wo))
        lobes = self.lobe_values(params.shape, wi, wo) if self.n_lobes else None
        return self.combined(params, visible, self.diffuse({}, wi, wo), lobes)

    def combined(self, params: Params, visible, diffuse, lobes) -> Float[Array, "n C"]:
        """:meth:`brdf` (N, C) from its parts at directions :func:`above_horizon` made: which pairs are ``visible``
        (N,), the diffuse term's basis (N,) and the lobes' unit-albedo values (:meth:`lobe_values`, or None without
        lobes), weighted by the albedos of ``params``."""
        values = diffuse[:, None] * jnp.asarray(params.diffuse)
        if lobes is not None:
            if lobes.ndim == 3:  # one lobe per channel (K, N, C)
                values = values + jnp.einsum("knc,kc->nc", lobes, jnp.asarray(params.specular))
            else:
                values = values + lobes.T @ jnp.asarray(params.specular)
        return jnp.where(visible[:, None], values, 0.0)

    def host_brdf(self, params: Params, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return np.asarray(_compiled_brdf(self, params, wi, wo))

    @property
    def prior_weight(self) -> float:
        return 0.0

    def lobe_values(self, shape: Mapping[str, Any], wi, wo) -> Float[Array, "K n"] | Float[Array, "K n C"]:
        """Unit-albedo lobe values (K, N), one row per lobe, for upper-hemisphere directions; (K, N, C) for a lobe
        with per-channel parameters (``Lobe.channel_names``)."""
        lobe = lobe_family(self)
        return jax.vmap(lambda one_shape: lobe(one_shape, wi, wo))(dict(shape))

    @property
    def fusion_emitters(self) -> bool:
        return self.lobe is not None and self.lobe.fusion_emitters

    # ------------------------------------------------------------ parameter forms
    # Each made once a model (cached_property writes past the frozen dataclass's guard): a capture's texels ask for
    # them tens of times each.
    @functools.cached_property
    def dictionary(self) -> ParameterDictionary:
        return ParameterDictionary(self)

    @functools.cached_property
    def unconstrained(self) -> UnconstrainedCoordinates:
        return UnconstrainedCoordinates(self)

    @functools.cached_property
    def sampling(self) -> SamplingCoordinates:
        return SamplingCoordinates(self)

    @functools.cached_property
    def physical(self) -> PhysicalCoordinates:
        return PhysicalCoordinates(self)

    def cache_key(self) -> list | None:
        parts = [self.name, self.options, self.n_lobes, self.diffuse_name, self.specular_name, self.isotropic]
        key = key_of((*parts, self.lobes_as_list, self.lobe, self.diffuse, self.whole))  # None if any part has no key
        return None if key is None else key[1]


@jit(static_argnums=0)
def _compiled_brdf(model: Model, params: Params, wi, wo):
    return model.brdf(params, wi, wo)


@dataclass(frozen=True, eq=False)
class ModelEntry:
    """What the registry knows about a model besides the model: ``build(**options)`` makes it (calling the entry
    does the same).

    ``compare``: the specs ``brdffit compare`` fits by default (``("lafortune:lobes=1", …)``). ``choices``: for each
    option with a fixed set of values, each value and what it means (``brdffit models`` lists them). ``listing``:
    the lines ``brdffit models`` prints for a model it cannot build without a file (the data-driven one).
    ``exports``: per export target (``mitsuba``), the function that maps a fit of this model onto the target's own
    model exactly (``mapping(result)``: the target's description, or None for options it cannot express), or that
    function's ``"module:name"`` (an exporter sits above the models, so it is imported when used); a target missing
    here approximates the model by fitting its own. ``recorded``: options a result records that a user never gives
    (a basis file's digest); ``files``: options that name a file (a label shows its name, not its path).
    """

    build: Callable[..., Model]
    compare: tuple[str, ...] = ()
    choices: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    listing: tuple[str, ...] = ()
    exports: Mapping[str, str | Callable] = field(default_factory=dict)
    recorded: frozenset[str] = frozenset()
    files: frozenset[str] = frozenset()

    def __call__(self, **options: Any) -> Model:
        return self.build(**options)

    @property
    def option_defaults(self) -> dict[str, Any]:
        """Each option the builder takes, with its default (``{"fresnel": "schlick", …}``)."""
        return {key: parameter.default for key, parameter in inspect.signature(self.build).parameters.items()}

    def exact_export(self, target: str) -> Callable | None:
        """The function that maps a fit exactly onto ``target``'s model, or None."""
        mapping = self.exports.get(target)
        if isinstance(mapping, str):
            module, _, name = mapping.partition(":")
            mapping = getattr(importlib.import_module(module), name)
        return mapping
