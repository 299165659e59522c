"""The data-driven model: a material as coefficients of a basis learned from a library of tables.

The basis is ``basis.py``'s, learned by ``build.py``.

``f(wi, wo)[c] = ρ(mean + Σ_k coefficients[k][c] · components[k])``, the basis interpolated at the pair
(``datadriven/basis.py``) and ``ρ(m)`` its mapping's inverse (``datadriven/mapping.py``; Matusik et al. 2003,
Nielsen et al. 2015). The parameters are the coefficients, ``K × C`` real numbers in library standard deviations
(``K`` the basis's components); the result file writes them as ``{"coefficients": [[c_r, c_g, c_b], …]}``, one list
per component. Options: ``basis`` (the ``.npz`` file), ``ridge`` (the weight of the library prior, :data:`RIDGE`)
and ``basis_sha256`` (the file's digest, which a result records so that it is never evaluated with another basis).

The model fits the machinery of every other model through its own parameter forms: one flat vector of the
coefficients in every coordinate system (they are unbounded, so the solver and the sampler move them as they
are), ``Params.specular`` (K, C) carrying them. The ridge is a Gaussian prior on the coefficients,
``Σ r² + ridge · ridge_scale · Σ c²`` (``prior_weight``), which the fit, Laplace's curvature and the sampler all
include; ``ridge_scale`` carries a residual of the mapped space into the loss's units (``datadriven/fit.py``).

Two models of one basis are equal whatever their ridge: the ridge reaches every compiled program as data, so a
program compiled for one fit serves the next.
"""

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, final

import numpy as np

from .._jax import jax, jnp, namespace
from ..errors import Argument, BrdfInputError
from ..physics.domains import Interval
from ..physics.geometry import above_horizon
from ..physics.models.model import Model, ModelEntry
from ..physics.models.params import Params

#: Default weight of the library prior, ``Σ r² + ridge·s·Σ c²``: coefficients in library standard deviations,
#: ``s`` the square of a residual of 1 in the basis's mapped space (≈ a relative error of 1) in the loss's units,
#: measured by the fit. So ``ridge`` is the variance, in the mapped space, of the noise and of what the basis
#: leaves out, per unit library variance: 1e-3 is 3%.
RIDGE = 1e-3
#: A coefficient: any real number, with a flat prior (the ridge is the prior that matters).
COEFFICIENT = Interval(-math.inf, math.inf)
NAME = "coefficients"


def pca(
    basis: str | None = None, ridge: float = RIDGE, basis_sha256: str | None = None, ridge_scale: float | None = None
) -> "PcaModel":
    """The ``pca`` model of the basis file ``basis`` (required); ``basis_sha256``, when given, must be the file's digest
    (a result records it). ``ridge_scale``: a mapped residual's square in the loss's units, which the fit measures on
    its samples (``datadriven/fit.py``) and the result records; the prior's weight is ``ridge·ridge_scale``."""
    from .basis import load_basis

    if basis is None:
        raise BrdfInputError(
            "model pca needs ", Argument("basis"), " FILE: a basis file made by brdffit basis build from a library"
        )
    try:
        ridge = float(ridge) if not isinstance(ridge, bool) else math.nan
    except (TypeError, ValueError):
        raise BrdfInputError(Argument("ridge", ridge), " must be a number ≥ 0") from None
    if not (ridge >= 0 and math.isfinite(ridge)):
        raise BrdfInputError(Argument("ridge", ridge), " must be a finite number ≥ 0")
    if ridge_scale is not None and (
        isinstance(ridge_scale, bool)
        or not isinstance(ridge_scale, int | float)
        or not (math.isfinite(ridge_scale) and ridge_scale > 0)
    ):
        raise BrdfInputError(Argument("ridge_scale", ridge_scale), " must be a finite number > 0")
    if not isinstance(basis, str | os.PathLike):
        raise BrdfInputError(
            Argument("basis"), f" must be the basis file's path, got {type(basis).__name__} (save_basis a Basis first)"
        )
    path = os.path.abspath(os.fspath(basis))
    loaded = load_basis(path)
    if basis_sha256 is not None and basis_sha256 != loaded.digest:
        raise BrdfInputError(
            f"{path}: this basis is not the one the parameters were fitted with (its SHA-256 differs);"
            " give the basis file of the fit"
        )
    return PcaModel(
        "pca",
        f"data-driven: {loaded.n_components} principal components of a library ({loaded.mapping} mapping)",
        options=(("basis", path), ("ridge", ridge), ("basis_sha256", loaded.digest))
        + ((("ridge_scale", float(ridge_scale)),) if ridge_scale is not None else ()),
        basis=loaded,
    )


@final
@dataclass(frozen=True, eq=False)
class PcaModel(Model):
    """The data-driven kind of :class:`~brdffit.physics.models.model.Model`: its parameters are a basis's
    coefficients; ``basis`` (a :class:`~brdffit.datadriven.basis.Basis`) is left out of the repr. Its identity
    (equality, hash: what JAX compiles a program for) is its basis file and that file's digest; pickled, it is its
    options, and the unpickling process reads the basis again (a Dask worker gets a few bytes, not the basis).

    What sets it apart, each where the kind is asked: it is evaluated on the host (:meth:`host_brdf`: a table's
    interpolation does not fit in one program's memory); it is fitted by a solve of its own, a ridge start in the
    mapped space and then Levenberg-Marquardt (``datadriven/fit.py``); its programs call the host for the basis (a
    callback), which a program stored on disk cannot carry to another process (``brdffit/_programs``)."""

    name: str
    summary: str
    options: tuple[tuple[str, Any], ...] = ()
    isotropic: bool = True

    def __eq__(self, other) -> bool:
        return isinstance(other, PcaModel) and self.identity == other.identity

    def __hash__(self) -> int:
        return hash(self.identity)

    def __reduce__(self):
        options = self.model_options
        return pca, (options["basis"], options["ridge"], options["basis_sha256"], options.get("ridge_scale"))

    @property
    def identity(self) -> tuple[str, str]:
        return self.model_options["basis"], self.model_options["basis_sha256"]

    basis: Any = field(default=None, compare=False, repr=False)

    def cache_key(self) -> None:
        """None: its programs call the host for the basis (a callback), which a program stored on disk cannot carry
        to another process, nor run outside float64; they are compiled in each process instead."""
        return None

    @property
    def ridge(self) -> float:
        return self.model_options["ridge"]

    @property
    def n_components(self) -> int:
        return self.basis.n_components

    # ------------------------------------------------------------------ evaluation
    def brdf(self, params: Params, wi, wo):
        """BRDF values (N, C) in 1/sr (JAX); the basis is interpolated on the host (a callback) and combined with
        the coefficients in JAX, so derivatives with respect to the coefficients are exact.

        The callback hands its float64 arrays over as pairs of float32 (``x = hi + lo`` to ~1e-14): XLA may run a
        callback on a thread of its own, where JAX's float64 switch is off and a float64 result would be refused."""
        from .basis import Corners

        wi, wo = jnp.asarray(wi), jnp.asarray(wo)
        visible, wi, wo = above_horizon(wi, wo)
        n, k = wi.shape[0], self.n_components
        shapes = [jax.ShapeDtypeStruct(shape, jnp.float32) for shape in _split_shapes(n, k)]

        def on_host(wi, wo):
            corners = self.basis.corners(np.asarray(wi, np.float64), np.asarray(wo, np.float64))
            return [*(half for part in corners[:4] for half in _split(part)), corners.components.astype(np.float32)]

        parts = jax.pure_callback(on_host, shapes, wi, wo, vmap_method="sequential")
        weight, mean, reference, cosine = (
            parts[2 * i].astype(wi.dtype) + parts[2 * i + 1].astype(wi.dtype) for i in range(4)
        )
        corners = Corners(weight, mean, reference, cosine, parts[8].astype(wi.dtype))
        values = corners.brdf(self.basis.mapping, jnp.asarray(params.specular, wi.dtype))
        return jnp.where(visible[:, None], values, 0.0)

    def host_brdf(self, params: Params, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        """:meth:`brdf` in numpy, block by block (a MERL table's 1.46·10⁶ pairs)."""
        return self.basis.brdf(np.asarray(params.specular, float), wi, wo)

    @property
    def prior_weight(self) -> float:
        """The ridge in the loss's units, ``ridge · ridge_scale`` (the scale is 1 until a fit has measured it): the
        prior adds ``prior_weight · Σ c²`` to the cost."""
        return self.ridge * self.model_options.get("ridge_scale", 1.0)

    # ------------------------------------------------------------ parameter forms
    @property
    def dictionary(self) -> "CoefficientDictionary":
        return CoefficientDictionary(self)

    @property
    def unconstrained(self) -> "CoefficientVector":
        return CoefficientVector(self)

    @property
    def sampling(self) -> "CoefficientVector":
        return CoefficientVector(self)

    @property
    def physical(self) -> "CoefficientVector":
        return CoefficientVector(self)


#: The data-driven model in the registry: it needs a basis file to be built, so ``brdffit models`` describes it; a
#: result records the basis file's digest and the ridge's scale its fit measured; no renderer has it (exports
#: approximate it); ``compare`` tries it when given a basis (``brdffit compare --basis``).
PCA = ModelEntry(
    pca,
    listing=(
        "data-driven: principal components of a library of measured tables (brdffit basis build)",
        "parameters: coefficients: [K][C] real, in library standard deviations (K: the basis's components)",
    ),
    recorded=frozenset({"basis_sha256", "ridge_scale"}),
    files=frozenset({"basis"}),
)


def _split_shapes(n: int, k: int) -> list[tuple[int, ...]]:
    """The callback's results: weight, mean, reference and cosine, each as two halves (n, 8); components (n, 8, k)."""
    return [(n, 8)] * 8 + [(n, 8, k)]


def _split(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float64 ``x`` as float32 ``hi``, ``lo`` with ``hi + lo = x`` to float64's precision (~1e-14 relative)."""
    hi = x.astype(np.float32)
    return hi, (x - hi.astype(np.float64)).astype(np.float32)


@dataclass(frozen=True)
class CoefficientVector:
    """The coefficients as one flat vector, component by component (``coefficients[0][r]``, ``[0][g]``, …): the
    same in every coordinate system, since a coefficient is any real number."""

    model: PcaModel

    def size(self, n_channels: int) -> int:
        return self.model.n_components * n_channels

    def labels(self, channels: tuple[str, ...]) -> list[str]:
        return [f"{NAME}[{k}][{c}]" for k in range(self.model.n_components) for c in channels]

    def domains(self, n_channels: int) -> list:
        return [COEFFICIENT] * self.size(n_channels)

    def from_params(self, params: Params):
        return namespace(params.specular).ravel(params.specular)

    def to_params(self, vector, n_channels: int) -> Params:
        xp = namespace(vector)
        coefficients = vector.reshape(self.model.n_components, n_channels)
        return Params(xp.zeros(n_channels, dtype=coefficients.dtype), coefficients, {})


@dataclass(frozen=True)
class CoefficientDictionary:
    """The coefficients as the result file writes them: ``{"coefficients": [[c_r, c_g, c_b], …]}``, K lists."""

    model: PcaModel
    names: tuple[str, ...] = (NAME,)

    def to_params(self, values: Mapping[str, Any]) -> Params:
        model, k = self.model, self.model.n_components
        if not isinstance(values, Mapping) or set(values) != {NAME}:
            got = sorted(values) if isinstance(values, Mapping) else type(values).__name__
            raise BrdfInputError(f"pca: parameters must be {{{NAME!r}: [[…], …]}}, got {got}")
        try:
            coefficients = np.asarray(values[NAME], dtype=float)
        except (TypeError, ValueError):
            raise BrdfInputError(f"pca: {NAME} must be {k} lists of numbers, one per component") from None
        if coefficients.ndim == 1:  # one channel written flat
            coefficients = coefficients[:, None]
        if coefficients.ndim != 2 or coefficients.shape[0] != k or coefficients.shape[1] == 0:
            raise BrdfInputError(
                f"pca: {NAME} must be {k} lists (one per component of"
                f" {os.path.basename(model.model_options['basis'])}),"
                f" each with a value per channel; got shape {coefficients.shape}"
            )
        if not np.all(np.isfinite(coefficients)):
            raise BrdfInputError(f"pca: {NAME} must be finite numbers")
        return Params(np.zeros(coefficients.shape[1]), coefficients, {})

    def from_params(self, params: Params) -> dict[str, Any]:
        return {NAME: [[float(x) for x in row] for row in np.asarray(params.specular)]}
