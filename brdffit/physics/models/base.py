"""What every model shares: a diffuse term plus ``K`` specular lobes.

SPEC section 1: *every model is a diffuse term plus one or more specular lobes;
diffuse and specular albedos are per channel; lobe-shape parameters are shared
by all channels.* So a model is::

    f(wi, wo)[c] = diffuse[c] / π + Σ_k specular[k, c] · lobe(shape[k]; wi, wo)

with ``lobe`` a unit-albedo lobe family (Ward, Cook-Torrance, Phong, …). The
model is linear in the albedos, which the fit's starting guess exploits.

Parameters exist in three forms:

* the *dictionary* of SPEC section 5 (``{"rho_d": [...], "alpha": 0.1}``), what
  users read and write;
* :class:`Params`, arrays ``diffuse (C,)``, ``specular (K, C)`` and
  ``shape[name] (K,)``, what :meth:`Model.evaluate` takes;
* a flat *unconstrained* vector, what the solver moves (see ``domains.py``);
* a flat *sampling* vector, what the MCMC walkers move (``posterior.py``): the
  physical values themselves, except a Lafortune lobe's direction, which is its
  angle ``psi``; and the flat *physical* vector (labels ``rho_d[r]``, ``alpha``,
  ``lobes[0].cxy``) in which covariances are reported.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ... import _jax  # noqa: F401  (float64 before any array)
from ...errors import BrdfInputError
from ..domains import NON_NEGATIVE
from ..geometry import NORMAL


class Params(NamedTuple):
    """A model's parameters as arrays (a JAX pytree).

    ``diffuse``: (C,) albedos; ``specular``: (K, C) albedos; ``shape``: lobe-shape
    parameters, each of shape (K,), keyed by their SPEC names.
    """

    diffuse: Any
    specular: Any
    shape: dict[str, Any]


@dataclass(frozen=True)
class Lobe:
    """A family of specular lobes of unit albedo, ``lobe(shape; wi, wo)`` in 1/sr.

    Subclasses give ``parameters`` (name → domain, in SPEC order), ``grid``
    (starting shapes for the fit, coarse but spanning realistic materials) and
    ``__call__``. Instances are frozen, hence hashable: JAX treats them as
    static configuration.
    """

    #: Short description of the lobe for ``brdffit models``.
    summary = ""

    @property
    def parameters(self) -> tuple[tuple[str, Any], ...]:
        raise NotImplementedError

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.parameters)

    @property
    def grid(self) -> tuple[dict[str, float], ...]:
        raise NotImplementedError

    def __call__(self, shape: Mapping[str, Any], wi, wo):
        """Lobe values (N,) for directions (N, 3) with positive ``z``."""
        raise NotImplementedError

    # -- the unconstrained coordinates; one per parameter unless a subclass says otherwise
    @property
    def n_unconstrained(self) -> int:
        return len(self.parameters)

    @property
    def unconstrained_names(self) -> tuple[str, ...]:
        return self.names

    def shape_to_unconstrained(self, shape: Mapping[str, float]) -> np.ndarray:
        return np.array([float(domain.to_unconstrained(shape[name])) for name, domain in self.parameters])

    def shape_from_unconstrained(self, u) -> dict[str, Any]:
        return {name: domain.to_physical(u[i]) for i, (name, domain) in enumerate(self.parameters)}

    # -- the sampling coordinates (MCMC): the physical parameters unless a subclass says otherwise
    @property
    def sampling_parameters(self) -> tuple[tuple[str, Any], ...]:
        return self.parameters

    def shape_to_sampling(self, shape: Mapping[str, float]) -> np.ndarray:
        return np.array([float(shape[name]) for name, _ in self.sampling_parameters])

    def shape_from_sampling(self, values) -> dict[str, Any]:
        return {name: values[i] for i, (name, _) in enumerate(self.sampling_parameters)}

    def checked_shape(self, shape: Mapping[str, float], where: str) -> dict[str, float]:
        """The shape with each value checked against its domain; ``where`` prefixes errors."""
        for name, domain in self.parameters:
            if not domain.contains(shape[name]):
                raise BrdfInputError(f"{where}{name} = {shape[name]!r} is outside its domain {domain.text}")
        return {name: float(shape[name]) for name in self.names}


@dataclass(frozen=True)
class Model:
    """A reflectance model: ``diffuse / π`` plus ``n_lobes`` lobes of one family.

    ``name`` is the ``--model`` name; ``options`` the model options that define
    it (``fresnel``, ``lobes``) as sorted ``(key, value)`` pairs, written to the
    result file as ``model_options``.
    """

    name: str
    summary: str
    lobe: Lobe | None = None
    n_lobes: int = 0
    diffuse_name: str = "rho_d"
    specular_name: str = "rho_s"
    options: tuple[tuple[str, Any], ...] = ()
    isotropic: bool = True
    #: Lafortune writes its lobes as a list, ``"lobes": [{...}, ...]`` (SPEC section 5).
    lobes_as_list: bool = False

    @property
    def model_options(self) -> dict[str, Any]:
        return dict(self.options)

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, params: Params, wi, wo):
        """BRDF values (N, C) in 1/sr; zero where ``wi_z ≤ 0`` or ``wo_z ≤ 0``.

        Directions that are not in the upper hemisphere are replaced by the
        normal before the lobes see them, so that neither their values nor
        their derivatives can turn into NaN (the ``where`` that zeroes them
        would otherwise multiply an infinite derivative by 0).
        """
        wi = jnp.asarray(wi)
        wo = jnp.asarray(wo)
        visible = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        normal = jnp.asarray(NORMAL, dtype=wi.dtype)
        wi = jnp.where(visible[:, None], wi, normal)
        wo = jnp.where(visible[:, None], wo, normal)
        diffuse = jnp.asarray(params.diffuse)
        values = jnp.broadcast_to(diffuse / jnp.pi, (wi.shape[0], diffuse.shape[0]))
        if self.n_lobes:
            lobes = self.lobe_values(params.shape, wi, wo)
            values = values + lobes.T @ jnp.asarray(params.specular)
        return jnp.where(visible[:, None], values, 0.0)

    def lobe_values(self, shape: Mapping[str, Any], wi, wo):
        """Unit-albedo lobe values (K, N), one row per lobe, for upper-hemisphere directions."""
        return jax.vmap(lambda one_shape: self.lobe(one_shape, wi, wo))(dict(shape))

    def value_and_basis(self, theta, wi, wo, n_channels: int, dtype=None):
        """BRDF values (N, C) and the per-sample basis (N, M) of their derivatives at the unconstrained ``theta``.

        The basis is ``[1/π, lobe_k, ∂lobe_k/∂u_ks]`` (M = 1 + K + K·S): the
        albedos enter linearly, so the derivatives of every channel with respect
        to every parameter are combinations of these M functions, with the
        coefficients of :meth:`jacobian_coefficients`. Only the S shape
        coordinates of each lobe are differentiated (forward mode), once per
        sample. The model is evaluated in ``dtype`` (default: that of ``wi``).
        """
        dtype = dtype or wi.dtype
        visible = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        normal = jnp.asarray(NORMAL, dtype=wi.dtype)
        wi = jnp.where(visible[:, None], wi, normal)
        wo = jnp.where(visible[:, None], wo, normal)
        n, c = wi.shape[0], n_channels
        diffuse = NON_NEGATIVE.to_physical(theta[:c]).astype(dtype)
        values = jnp.broadcast_to(diffuse / jnp.pi, (n, c))
        columns = [jnp.full((n, 1), 1.0 / jnp.pi, dtype=dtype)]
        if self.n_lobes:
            k, s = self.n_lobes, self.lobe.n_unconstrained
            specular = NON_NEGATIVE.to_physical(theta[c : (1 + k) * c].reshape(k, c)).astype(dtype)

            def lobe_and_derivatives(u):
                def lobe(v):
                    shape = jax.tree.map(lambda x: x.astype(dtype), self.lobe.shape_from_unconstrained(v))
                    value = self.lobe(shape, wi, wo)
                    return value, value

                derivatives, value = jax.jacfwd(lobe, has_aux=True)(u)
                return value, derivatives.astype(dtype)

            lobes, lobe_derivatives = jax.vmap(lobe_and_derivatives)(theta[(1 + k) * c :].reshape(k, s))
            values = values + lobes.T @ specular
            columns += [lobes.T, jnp.transpose(lobe_derivatives, (1, 0, 2)).reshape(n, k * s)]
        basis = jnp.concatenate(columns, axis=1)
        return jnp.where(visible[:, None], values, 0.0), jnp.where(visible[:, None], basis, 0.0)

    def jacobian_coefficients(self, theta, n_channels: int):
        """``A`` (C, M, k) with ``∂f[n, c]/∂theta = Σ_m basis[n, m] · A[c, m]`` (see :meth:`value_and_basis`).

        Row 0 (the diffuse basis) carries ``d rho_d/du``; the lobe rows carry
        ``d rho_s/du``; the shape-derivative rows carry the specular albedos.
        """
        c, k = n_channels, self.n_lobes
        eye_c = jnp.eye(c, dtype=theta.dtype)
        _, diffuse_slope = jax.jvp(NON_NEGATIVE.to_physical, (theta[:c],), (jnp.ones(c, theta.dtype),))
        if not k:
            return (eye_c * diffuse_slope)[:, None, :]
        s = self.lobe.n_unconstrained
        u_specular = theta[c : (1 + k) * c].reshape(k, c)
        specular, specular_slope = jax.jvp(NON_NEGATIVE.to_physical, (u_specular,), (jnp.ones_like(u_specular),))
        eye_k, eye_s = jnp.eye(k, dtype=theta.dtype), jnp.eye(s, dtype=theta.dtype)
        diffuse_rows = (eye_c * diffuse_slope)[:, None, :]
        lobe_rows = specular_slope.T[:, :, None, None] * eye_k[None, :, :, None] * eye_c[:, None, None, :]
        shape_rows = specular.T[:, :, None, None, None] * eye_k[None, :, None, :, None] * eye_s[None, None, :, None, :]
        zeros = lambda rows, cols: jnp.zeros((c, rows, cols), theta.dtype)
        return jnp.concatenate(
            [
                jnp.concatenate([diffuse_rows, zeros(1, k * c), zeros(1, k * s)], axis=2),
                jnp.concatenate([zeros(k, c), lobe_rows.reshape(c, k, k * c), zeros(k, k * s)], axis=2),
                jnp.concatenate([zeros(k * s, c), zeros(k * s, k * c), shape_rows.reshape(c, k * s, k * s)], axis=2),
            ],
            axis=1,
        )

    # ------------------------------------------------------------ parameter forms
    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Top-level names of the parameter dictionary, in SPEC order."""
        if not self.n_lobes:
            return (self.diffuse_name,)
        if self.lobes_as_list:
            return (self.diffuse_name, "lobes")
        return (self.diffuse_name, self.specular_name, *self.lobe.names)

    def params_from_dict(self, values: Mapping[str, Any]) -> Params:
        """Check a SPEC-section-5 parameter dictionary and convert it to :class:`Params`.

        Per-channel albedos may be a number (one channel) or a list; every
        per-channel entry must have the same length.
        """
        if not isinstance(values, Mapping):
            raise BrdfInputError(f"{self.name}: parameters must be a JSON object, got {type(values).__name__}")
        _check_keys(values, self.parameter_names, f"{self.name}: ")
        diffuse = _albedo(values[self.diffuse_name], f"{self.name}: {self.diffuse_name}")
        if not self.n_lobes:
            return Params(diffuse, np.zeros((0, diffuse.size)), {})
        if self.lobes_as_list:
            lobes = values["lobes"]
            if not isinstance(lobes, list | tuple) or len(lobes) != self.n_lobes:
                got = len(lobes) if isinstance(lobes, list | tuple) else type(lobes).__name__
                raise BrdfInputError(f"{self.name}: 'lobes' must be a list of {self.n_lobes} lobe(s), got {got}")
            names = (self.specular_name, *self.lobe.names)
            for index, lobe in enumerate(lobes):
                if not isinstance(lobe, Mapping):
                    raise BrdfInputError(f"{self.name}: lobes[{index}] must be a JSON object")
                _check_keys(lobe, names, f"{self.name}: lobes[{index}]: ")
            prefixes = [f"{self.name}: lobes[{index}]." for index in range(self.n_lobes)]
        else:
            lobes, prefixes = [values], [f"{self.name}: "]
        specular = np.stack(
            [
                _albedo(lobe[self.specular_name], prefix + self.specular_name)
                for lobe, prefix in zip(lobes, prefixes, strict=True)
            ]
        )
        if specular.shape[1] != diffuse.size:
            raise BrdfInputError(
                f"{self.name}: {self.specular_name} has {specular.shape[1]} channel(s)"
                f" but {self.diffuse_name} has {diffuse.size}"
            )
        shapes = [
            self.lobe.checked_shape(_shape_numbers(lobe, self.lobe.names, prefix), prefix)
            for lobe, prefix in zip(lobes, prefixes, strict=True)
        ]
        shape = {name: np.array([one[name] for one in shapes]) for name in self.lobe.names}
        return Params(diffuse, specular, shape)

    def params_to_dict(self, params: Params) -> dict[str, Any]:
        """The SPEC-section-5 dictionary (plain Python floats and lists) of ``params``."""
        result: dict[str, Any] = {self.diffuse_name: _floats(params.diffuse)}
        if not self.n_lobes:
            return result
        lobes = [
            {self.specular_name: _floats(params.specular[k])}
            | {name: float(params.shape[name][k]) for name in self.lobe.names}
            for k in range(self.n_lobes)
        ]
        if self.lobes_as_list:
            result["lobes"] = lobes
        else:
            result.update(lobes[0])
        return result

    # ------------------------------------------------------- unconstrained vector
    def n_parameters(self, n_channels: int) -> int:
        """Length of the unconstrained vector for ``n_channels`` channels."""
        return (1 + self.n_lobes) * n_channels + (self.lobe.n_unconstrained * self.n_lobes if self.n_lobes else 0)

    def to_unconstrained(self, params: Params) -> np.ndarray:
        """Flat vector ``[diffuse (C), specular (K·C), shape (K·S)]`` in unconstrained coordinates."""
        pieces = [NON_NEGATIVE.to_unconstrained(params.diffuse).ravel()]
        if self.n_lobes:
            pieces.append(NON_NEGATIVE.to_unconstrained(params.specular).ravel())
            for k in range(self.n_lobes):
                one = {name: float(params.shape[name][k]) for name in self.lobe.names}
                pieces.append(self.lobe.shape_to_unconstrained(one))
        return np.concatenate(pieces)

    def from_unconstrained(self, theta, n_channels: int) -> Params:
        """Inverse of :meth:`to_unconstrained`, traceable by JAX."""
        n_albedos = (1 + self.n_lobes) * n_channels
        diffuse = NON_NEGATIVE.to_physical(theta[:n_channels])
        specular = NON_NEGATIVE.to_physical(theta[n_channels:n_albedos]).reshape(self.n_lobes, n_channels)
        if not self.n_lobes:
            return Params(diffuse, specular, {})
        per_lobe = theta[n_albedos:].reshape(self.n_lobes, self.lobe.n_unconstrained)
        shape = jax.vmap(self.lobe.shape_from_unconstrained)(per_lobe)
        return Params(diffuse, specular, shape)

    def unconstrained_labels(self, channels: tuple[str, ...]) -> list[str]:
        """A name for each entry of the unconstrained vector, e.g. ``rho_d[r]``, ``alpha``, ``lobes[0].psi``."""
        return self._labels(channels, self.lobe.unconstrained_names if self.n_lobes else ())

    # ------------------------------------------------------------ sampling vector
    def sampling_domains(self, n_channels: int) -> list[Any]:
        """The domain (with its prior, ``domains.py``) of each entry of the sampling vector."""
        domains = [NON_NEGATIVE] * ((1 + self.n_lobes) * n_channels)
        if self.n_lobes:
            domains += [domain for _ in range(self.n_lobes) for _, domain in self.lobe.sampling_parameters]
        return domains

    def physical_domains(self, n_channels: int) -> list[Any]:
        """The domain of each entry of the physical vector (:meth:`physical_labels` order)."""
        domains = [NON_NEGATIVE] * ((1 + self.n_lobes) * n_channels)
        if self.n_lobes:
            domains += [domain for _ in range(self.n_lobes) for _, domain in self.lobe.parameters]
        return domains

    def sampling_labels(self, channels: tuple[str, ...]) -> list[str]:
        """A name for each entry of the sampling vector, e.g. ``rho_d[r]``, ``alpha``, ``lobes[0].psi``."""
        return self._labels(channels, [name for name, _ in self.lobe.sampling_parameters] if self.n_lobes else ())

    def to_sampling(self, params: Params) -> np.ndarray:
        """Flat vector ``[diffuse (C), specular (K·C), sampling shape (K·S')]``."""
        pieces = [np.asarray(params.diffuse, dtype=float).ravel(), np.asarray(params.specular, dtype=float).ravel()]
        for k in range(self.n_lobes):
            pieces.append(self.lobe.shape_to_sampling({name: float(params.shape[name][k]) for name in self.lobe.names}))
        return np.concatenate(pieces)

    def from_sampling(self, v, n_channels: int) -> Params:
        """Inverse of :meth:`to_sampling`, traceable by JAX."""
        n_albedos = (1 + self.n_lobes) * n_channels
        diffuse, specular = v[:n_channels], v[n_channels:n_albedos].reshape(self.n_lobes, n_channels)
        if not self.n_lobes:
            return Params(diffuse, specular, {})
        per_lobe = v[n_albedos:].reshape(self.n_lobes, len(self.lobe.sampling_parameters))
        return Params(diffuse, specular, jax.vmap(self.lobe.shape_from_sampling)(per_lobe))

    # ------------------------------------------------------------ physical vector
    def physical_labels(self, channels: tuple[str, ...]) -> list[str]:
        """A name for each physical parameter, flat, in SPEC order: ``rho_d[r]``, …, ``lobes[0].cxy``."""
        return self._labels(channels, self.lobe.names if self.n_lobes else ())

    def to_physical_vector(self, params: Params):
        """The physical parameters as one flat vector in the order of :meth:`physical_labels` (JAX)."""
        shape = [jnp.stack([params.shape[name][k] for name in self.lobe.names]) for k in range(self.n_lobes)]
        return jnp.concatenate([jnp.ravel(params.diffuse), jnp.ravel(params.specular), *shape])

    def dict_from_physical_vector(self, values, n_channels: int) -> dict[str, Any]:
        """The SPEC-section-5 dictionary layout filled from a flat physical vector (standard errors, quantiles)."""
        values = np.asarray(values, dtype=float)
        n_albedos = (1 + self.n_lobes) * n_channels
        specular = values[n_channels:n_albedos].reshape(self.n_lobes, n_channels)
        names = self.lobe.names if self.n_lobes else ()
        per_lobe = values[n_albedos:].reshape(self.n_lobes, len(names))
        shape = {name: per_lobe[:, i] for i, name in enumerate(names)}
        return self.params_to_dict(Params(values[:n_channels], specular, shape))

    def _labels(self, channels: tuple[str, ...], shape_names) -> list[str]:
        """Labels of a flat ``[diffuse (C), specular (K·C), shape (K·S)]`` vector."""
        labels = [f"{self.diffuse_name}[{c}]" for c in channels]
        prefixes = [f"lobes[{k}]." if self.lobes_as_list else "" for k in range(self.n_lobes)]
        labels += [f"{prefix}{self.specular_name}[{c}]" for prefix in prefixes for c in channels]
        return labels + [f"{prefix}{name}" for prefix in prefixes for name in shape_names]

    def describe_parameters(self) -> list[str]:
        """One line per parameter with its shape and domain, for ``brdffit models``."""
        lines = [f"{self.diffuse_name}: [C] {NON_NEGATIVE.text}"]
        if self.n_lobes:
            lines.append(f"{self.specular_name}: [C] {NON_NEGATIVE.text}")
            lines += [f"{name}: {domain.text}" for name, domain in self.lobe.parameters]
        return lines


def _check_keys(values: Mapping[str, Any], expected: tuple[str, ...], prefix: str) -> None:
    for key in values:
        if key not in expected:
            raise BrdfInputError(f"{prefix}unknown parameter {key!r}; expected {', '.join(expected)}")
    for key in expected:
        if key not in values:
            raise BrdfInputError(f"{prefix}missing parameter {key!r}; expected {', '.join(expected)}")


def _albedo(value: Any, where: str) -> np.ndarray:
    """A per-channel albedo as a float array (C,); a single number is one channel."""
    try:
        array = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        raise BrdfInputError(f"{where} must be a number or a list of numbers, got {value!r}") from None
    if array.ndim != 1 or array.size == 0:
        raise BrdfInputError(f"{where} must be a number or a flat list of numbers, got {value!r}")
    if not NON_NEGATIVE.contains(array):
        raise BrdfInputError(f"{where} = {value!r} is outside its domain {NON_NEGATIVE.text}")
    return array


def _shape_numbers(values: Mapping[str, Any], names: tuple[str, ...], where: str) -> dict[str, float]:
    numbers = {}
    for name in names:
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
            raise BrdfInputError(f"{where}{name} must be a single number, got {value!r}")
        numbers[name] = float(value)
    return numbers


def _floats(array) -> list[float]:
    return [float(x) for x in np.asarray(array).ravel()]
