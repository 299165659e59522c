"""What every model is: a diffuse term plus ``K`` specular lobes of one family.

Every model is a diffuse term plus one or more specular lobes; diffuse and specular albedos are per
channel, lobe-shape parameters are shared by all channels. So a model is::

    f(wi, wo)[c] = diffuse[c] / π + Σ_k specular[k, c] · lobe(shape[k]; wi, wo)

with ``lobe`` a unit-albedo lobe family (``lobe.py``: Ward, Cook-Torrance, Phong, …). The model is
linear in the albedos, which the fit's starting guess and its normal equations exploit
(``brdffit/fitting``).

Its parameters exist as arrays (:class:`~brdffit.physics.models.params.Params`, what :meth:`Model.brdf`
takes), as the result file's dictionary (:attr:`Model.dictionary`) and as flat vectors in three
coordinate systems (:attr:`Model.unconstrained`, :attr:`Model.sampling`, :attr:`Model.physical`;
``coordinates.py``).
"""

from __future__ import annotations  # jaxtyping's Array imports JAX: the annotations stay unevaluated

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from ..._jax import jax, jnp
from ..geometry import above_horizon
from .coordinates import PhysicalCoordinates, SamplingCoordinates, UnconstrainedCoordinates
from .dictionary import ParameterDictionary
from .lobe import Lobe
from .params import Params

if TYPE_CHECKING:
    from jaxtyping import Array, Float


@dataclass(frozen=True)
class Model:
    """A reflectance model: ``diffuse / π`` plus ``n_lobes`` lobes of one family.

    ``name`` is the model's registry name (``ward``); ``options`` the options that define it (``fresnel``,
    ``distribution``, ``shadowing``, ``lobes``) as ``(key, value)`` pairs in the order the model's builder takes
    them, written to the result file as ``model_options``.
    Frozen, hence hashable: JAX treats a model as static configuration.
    """

    name: str
    summary: str
    lobe: Lobe | None = None
    n_lobes: int = 0
    diffuse_name: str = "rho_d"
    specular_name: str = "rho_s"
    options: tuple[tuple[str, Any], ...] = ()
    isotropic: bool = True
    #: Lafortune writes its lobes as a list, ``"lobes": [{...}, ...]``.
    lobes_as_list: bool = False
    #: Whether :func:`brdffit.evaluate` computes it on the host (``host_brdf``) rather than in a JAX program.
    on_host: ClassVar[bool] = False
    #: Whether it is fitted by a solve of its own (the data-driven model: ``fitting/pca.py``), not the lobe models'.
    own_fit: ClassVar[bool] = False

    @property
    def model_options(self) -> dict[str, Any]:
        return dict(self.options)

    # ------------------------------------------------------------------ evaluation
    def brdf(self, params: Params, wi: Float[Array, "n 3"], wo: Float[Array, "n 3"]) -> Float[Array, "n C"]:
        """BRDF values (N, C) in 1/sr (JAX); zero where ``wi_z ≤ 0`` or ``wo_z ≤ 0``.

        The computation behind :func:`brdffit.evaluate` (which checks its inputs and returns float64 numpy)
        and :meth:`brdffit.FitResult.predict` (which evaluates a result's parameters). Called directly it is
        plain JAX in the caller's precision: float32 unless the caller has float64 on (``jax.enable_x64``).
        """
        visible, wi, wo = above_horizon(jnp.asarray(wi), jnp.asarray(wo))
        diffuse = jnp.asarray(params.diffuse)
        values = jnp.broadcast_to(diffuse / jnp.pi, (wi.shape[0], diffuse.shape[0]))
        if self.n_lobes:
            lobes = self.lobe_values(params.shape, wi, wo)
            values = values + lobes.T @ jnp.asarray(params.specular)
        return jnp.where(visible[:, None], values, 0.0)

    @property
    def prior_weight(self) -> float:
        """The weight ``W`` of a Gaussian prior that the fit's cost includes, ``Σ r² + W·Σ v²`` over the sampling
        vector ``v``: 0 (none) but for the data-driven model's ridge (``pca.py``). Its ``W·Σ v²`` counts as that
        many more residuals wherever the cost is turned into a likelihood (``uncertainty/density.py``)."""
        return 0.0

    def lobe_values(self, shape: Mapping[str, Any], wi, wo) -> Float[Array, "K n"]:
        """Unit-albedo lobe values (K, N), one row per lobe, for upper-hemisphere directions."""
        return jax.vmap(lambda one_shape: self.lobe(one_shape, wi, wo))(dict(shape))

    # ------------------------------------------------------------ parameter forms
    @property
    def dictionary(self) -> ParameterDictionary:
        """The parameters as the result file writes them (``{"rho_d": [...], "alpha": 0.1}``)."""
        return ParameterDictionary(self)

    @property
    def unconstrained(self) -> UnconstrainedCoordinates:
        """The flat vector the solver moves."""
        return UnconstrainedCoordinates(self)

    @property
    def sampling(self) -> SamplingCoordinates:
        """The flat vector the MCMC walkers move."""
        return SamplingCoordinates(self)

    @property
    def physical(self) -> PhysicalCoordinates:
        """The flat vector of the parameters themselves, in which covariances are reported."""
        return PhysicalCoordinates(self)
