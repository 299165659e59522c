"""The result of a fit: :class:`FitResult` and its :class:`Uncertainty`, the result file and the printed table.

The file is JSON (``docs/results.md``): the model, its options and channels, the fitted ``params``, how the
fit went (``fit``: loss, cost, rmse, counts, convergence) and, when asked for, the ``uncertainty`` block.
``cost`` is the sum of squared residuals ``Σ r²`` (scipy's ``least_squares`` and optimistix report ``½ Σ r²``).
"""

import functools
import json
import math
import os
import typing
from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..._files import parse_json, read_json_text, write_text_atomic
from ..._version import __version__
from ...errors import BrdfInputError
from ...physics.evaluate import evaluate
from ...physics.models.registry import get_model
from .constraints import constraints_for
from .criteria import Criteria, criteria
from .table import result_table


@dataclass(frozen=True)
class Uncertainty(Mapping[str, Any]):
    """The uncertainty of a fit's parameters, by one ``method`` (``laplace`` or ``mcmc``), as the result file holds it.

    ``stderr`` and ``quantiles`` (0.025, 0.16, 0.5, 0.84, 0.975) take the layout of ``params`` (an undetermined
    value is None); ``covariance`` and ``correlation`` are ``{"names": [...], "matrix": [[...]]}`` over the flat
    physical parameters (``rho_d[r]``, ``lobes[0].cxy``); ``diagnostics`` depend on the method; ``warnings`` say
    what a user must know about the estimate, and ``warning_codes`` (``brdffit/uncertainty/findings.py``) which
    finding each is, for programs. ``undetermined``: why each null error of ``stderr`` is null, in its layout (a
    reason where the error is null, None elsewhere; ``{}`` when every error is determined, and in files written before
    it). Also a read-only mapping of those names, as the JSON has them (``result.uncertainty["stderr"]``).
    """

    method: str
    stderr: dict[str, Any]
    quantiles: dict[str, Any]
    covariance: dict[str, Any]
    correlation: dict[str, Any]
    diagnostics: dict[str, Any]
    warnings: list[str]
    warning_codes: list[str]
    undetermined: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, content: Any, source: str = "result") -> "Uncertainty":
        """The ``uncertainty`` block of a result file, checked; an entry an older file lacks is empty."""
        if not isinstance(content, Mapping) or not isinstance(content.get("method"), str):
            raise BrdfInputError(f"{source}: 'uncertainty' must be an object with a 'method'")
        values = {}
        for item in fields(cls):
            kind: Any = (
                typing.get_origin(item.type) or item.type
            )  # dict[str, Any] → dict (``is`` never matches an alias)
            if kind is str:
                values[item.name] = content[item.name]
                continue
            value = content.get(item.name, kind())
            json_name = {dict: "object", list: "list"}[kind]
            if not isinstance(value, kind):
                raise BrdfInputError(f"{source}: uncertainty.{item.name} must be a JSON {json_name}")
            if typing.get_args(item.type) == (str,) and not all(isinstance(entry, str) for entry in value):
                raise BrdfInputError(f"{source}: uncertainty.{item.name} must be a JSON list of strings")
            values[item.name] = value
        return cls(**values)

    def __getitem__(self, name: str) -> Any:
        if name not in self.__dataclass_fields__:
            raise KeyError(name)
        return getattr(self, name)

    def __iter__(self) -> Iterator[str]:
        return iter(self.__dataclass_fields__)

    def __len__(self) -> int:
        return len(self.__dataclass_fields__)


@dataclass(frozen=True)
class FitResult:
    """Fitted parameters and how the fit went.

    ``params`` is the model's parameter dictionary (per-channel albedos as lists in
    ``channels`` order). ``cost`` is the sum of squared residuals of ``loss``, ``Σ r²``;
    ``rmse`` the root-mean-square of ``f - y`` over the fitted samples and
    channels, in 1/sr, whatever the loss. ``n_steps`` counts Levenberg-Marquardt
    steps of the winning start; ``converged`` is False when the solver stopped
    without meeting its tolerances, and ``message`` then says why. ``dtype`` is
    the precision the model was evaluated in (``float32``: solved in single
    precision, then refined in double, so the optimum is float64's). ``warnings``
    say what a user must know before trusting the fit (a dead lobe, a parameter
    at a plausible bound, data that are not reciprocal), one line each.
    ``quantity`` and ``max_theta`` say how the samples were read and selected
    (what their values were taken as, ``docs/quantities.md``; None for samples
    made from arrays), so that they can be read the same way again, as does ``reading``: the options the samples
    file was read with that were not their defaults (``Provenance.reading``: ``format``, ``angles``, ``spectral_to``
    with its ``illuminant`` and ``observer``, ``bin_centres``; empty for the defaults and for arrays). ``fixed``
    and ``bounds`` are the parameters the fit held (``fitting/single/constraints.py``):
    name → value (a list per channel for an albedo), and name → ``[lo, hi]``.
    ``n_values``: the values fitted (samples with a nonzero weight × channels; None in files written before it was
    recorded: then ``n_samples`` × channels); ``sigma``: whether the residuals were divided by the samples' sigma
    (False in such files). ``ndata``, ``nvarys``, ``chisqr``, ``redchi``, ``aic`` and ``bic`` are lmfit's figures of
    the fit, as ``brdffit compare`` counts them (``criteria.py``).
    ``uncertainty`` is the :class:`Uncertainty` when one was asked for
    (``brdffit/uncertainty``); ``draws`` the MCMC draws of the physical
    parameters (S, p), in the order of ``uncertainty.covariance["names"]``,
    kept in memory only.
    """

    model: str
    model_options: dict[str, Any]
    channels: tuple[str, ...]
    params: dict[str, Any]
    loss: str
    cost: float
    rmse: float
    n_samples: int
    n_steps: int
    converged: bool
    message: str = ""
    dtype: str = "float64"
    warnings: list[str] = field(default_factory=list)
    quantity: str | None = None
    max_theta: float | None = None
    fixed: dict[str, Any] = field(default_factory=dict)
    bounds: dict[str, Any] = field(default_factory=dict)
    n_values: int | None = None
    sigma: bool = False
    uncertainty: Uncertainty | None = None
    brdffit_version: str = field(default=__version__)
    draws: np.ndarray | None = field(default=None, repr=False, compare=False)
    reading: dict[str, Any] = field(default_factory=dict)  # last: the fields before it keep their positions

    # ------------------------------------------------------------------ lmfit's figures
    @functools.cached_property
    def criteria(self) -> Criteria:
        """:class:`~brdffit.fitting.single.criteria.Criteria`: ``ndata``, ``nvarys``, ``chisqr``, ``redchi``, ``aic``
        and ``bic`` of this fit, by one function with ``brdffit compare``'s; built once per result (it builds the
        model, which for the data-driven one reads its basis file)."""
        model = get_model(self.model, **self.model_options)
        constraints = constraints_for(model, len(self.channels), self.fixed, self.bounds, defaults=False)
        n_free = model.unconstrained.size(len(self.channels)) if constraints is None else constraints.n_free
        n_values = self.n_samples * len(self.channels) if self.n_values is None else self.n_values
        return criteria(self.cost, n_values, n_free, self.sigma)

    @property
    def ndata(self) -> int:
        """The values fitted: samples with a nonzero weight × channels (lmfit's ``ndata``)."""
        return self.criteria.ndata

    @property
    def nvarys(self) -> int:
        """The parameters the fit varied: the model's, less those it held (``fixed``; lmfit's ``nvarys``)."""
        return self.criteria.nvarys

    @property
    def chisqr(self) -> float:
        """``Σr²`` of the loss's residuals, the ``cost`` (lmfit's ``chisqr``; a χ² where the samples have sigma)."""
        return self.cost

    @property
    def redchi(self) -> float:
        """``chisqr / (ndata − nvarys)`` (lmfit's ``redchi``), NaN where ``ndata ≤ nvarys``."""
        return self.criteria.redchi

    @property
    def aic(self) -> float:
        """Akaike's information criterion (``criteria.py``; lmfit's ``aic``, ``brdffit compare``'s)."""
        return self.criteria.aic

    @property
    def bic(self) -> float:
        """Schwarz's Bayesian information criterion (``criteria.py``; lmfit's ``bic``, ``brdffit compare``'s)."""
        return self.criteria.bic

    def with_estimate(self, uncertainty: Uncertainty, draws: np.ndarray | None = None) -> "FitResult":
        """This result carrying an ``uncertainty`` estimate (and the MCMC ``draws`` (S, p) it came from)."""
        return replace(self, uncertainty=uncertainty, draws=draws)

    def predict(self, wi, wo) -> np.ndarray:
        """The fitted model's BRDF (N, C) in 1/sr at directions ``wi``, ``wo`` (N, 3)."""
        return evaluate(self.model, self.params, wi, wo, **self.model_options)

    def eval_uncertainty(self, wi, wo, sigma: float = 1.0) -> np.ndarray:
        """``sigma`` times the standard deviation (N, C), in 1/sr, of the predicted BRDF at ``wi``, ``wo`` (N, 3), from
        the uncertainty estimate's covariance by the delta method (lmfit's name; ``prediction.py``)."""
        from .prediction import prediction_band

        return prediction_band(self, wi, wo, sigma)

    def residuals(self, samples) -> np.ndarray:
        """The fit's residuals (N, C) on ``samples`` (a :class:`~brdffit.Samples` with this result's channels), in
        the units of its loss: ``sqrt(weight)·(T(f) − T(y))``, divided by ``sigma·|T'(y)|`` where the samples have
        sigma (``docs/losses.md``). Their sum of squares over the fitted samples is ``cost``."""
        from ..objective.losses import get_loss
        from ..objective.problem import sample_residuals

        if tuple(samples.channels) != tuple(self.channels):
            raise BrdfInputError(
                f"{samples.source}: channels {', '.join(samples.channels)} are not the result's"
                f" ({', '.join(self.channels)})"
            )
        model = get_model(self.model, **self.model_options)
        return sample_residuals(model, get_loss(self.loss), model.dictionary.to_params(self.params), samples)

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """The result file's content as plain Python objects."""
        result = {
            "brdffit_version": self.brdffit_version,
            "model": self.model,
            "model_options": dict(self.model_options),
            "channels": list(self.channels),
            "params": self.params,
            "fit": {
                "loss": self.loss,
                "cost": self.cost,
                "rmse": self.rmse,
                "n_samples": self.n_samples,
                "n_steps": self.n_steps,
                "converged": self.converged,
                "message": self.message,
                "dtype": self.dtype,
                "warnings": list(self.warnings),
                "quantity": self.quantity,
                "max_theta": self.max_theta,
                "reading": dict(self.reading),
                "fixed": dict(self.fixed),
                "bounds": dict(self.bounds),
                "n_values": self.n_values,
                "sigma": self.sigma,
            },
        }
        if self.uncertainty is not None:
            result["uncertainty"] = self.uncertainty.to_dict()
        return result

    def non_finite(self) -> str | None:
        """What of the result is not a finite number (``"the fit's rmse is inf, …"``), which no result file holds; None
        when every number is finite. Data out of float64's range make it so: a value whose square overflows
        (above ~1.3e154), a sigma whose inverse square does (below ~7.5e-155)."""
        found = first_non_finite(self.to_dict())
        if found is None:
            return None
        where, value = found
        return (
            f"the fit's {where} is {value}, not a finite number: values or sigma beyond float64's range"
            " (a value whose square overflows, a sigma whose inverse square does)"
        )

    def to_json(self) -> str:
        """The result file's text: indented objects, lists of numbers on one line. A result that is not finite
        (:meth:`non_finite`) is a :class:`~brdffit.errors.BrdfInputError`: no file claims to be JSON and is not."""
        problem = self.non_finite()
        if problem is not None:
            raise BrdfInputError(problem)
        return json_text(self.to_dict()) + "\n"

    def save(self, path: str | os.PathLike) -> None:
        """Write the result file atomically (:func:`save_result`)."""
        save_result(self, path)

    @classmethod
    def from_dict(cls, content: dict[str, Any], source: str = "result") -> "FitResult":
        try:
            fit = _object(content["fit"], "fit")
            return cls(
                model=_string(content["model"], "model"),
                model_options=_object(content.get("model_options", {}), "model_options"),
                channels=tuple(_string(channel, "channels") for channel in _list(content["channels"], "channels")),
                params=_object(content["params"], "params"),
                loss=fit["loss"],
                cost=float(fit["cost"]),
                rmse=float(fit["rmse"]),
                n_samples=int(fit["n_samples"]),
                n_steps=int(fit["n_steps"]),
                converged=bool(fit["converged"]),
                message=str(fit.get("message", "")),
                dtype=str(fit.get("dtype", "float64")),
                warnings=list(fit.get("warnings", [])),
                quantity=None if fit.get("quantity") is None else str(fit["quantity"]),
                max_theta=None if fit.get("max_theta") is None else float(fit["max_theta"]),
                reading=reading_of(fit.get("reading", {})),
                fixed=_object(fit.get("fixed", {}), "fit.fixed"),
                bounds=_object(fit.get("bounds", {}), "fit.bounds"),
                n_values=None if fit.get("n_values") is None else int(fit["n_values"]),
                sigma=bool(fit.get("sigma", False)),
                uncertainty=None
                if content.get("uncertainty") is None
                else Uncertainty.from_dict(content["uncertainty"], source),
                brdffit_version=str(content.get("brdffit_version", "")),
            )
        except (KeyError, TypeError, ValueError, OverflowError) as error:
            raise BrdfInputError(f"{source}: not a brdffit result file (missing or bad {error})") from None

    # ------------------------------------------------------------ the table
    def table(self, source: str | None = None) -> str:
        """The printed report (:func:`result_table`): one row per parameter, one column per channel, and the fit's
        figures."""
        return result_table(self, source)

    def __str__(self) -> str:
        return self.table()

    def fit_report(self, min_correlation: float = 0.1) -> str:
        """lmfit's report of a fit: the model, the fit's figures, the parameters with their errors and the correlations
        above ``min_correlation`` (``table.py``)."""
        from .table import fit_report

        return fit_report(self, min_correlation)

    def _repr_html_(self) -> str:
        """What a notebook shows for a bare result: the table as HTML (``table.result_html``)."""
        from .table import result_html

        return result_html(self)


def reading_of(value: Any) -> dict[str, Any]:
    """``fit.reading`` of a result file, checked (``data.load.checked_reading``)."""
    from ...data.load import checked_reading

    return checked_reading(_object(value, "fit.reading"))


def _object(value: Any, name: str) -> dict[str, Any]:
    """A JSON object of the result file, as a dict (a missing entry of an older file is empty)."""
    if not isinstance(value, dict):
        raise TypeError(f"{name} must be a JSON object")
    return dict(value)


def _list(value: Any, name: str) -> list:
    """A JSON list of the result file."""
    if not isinstance(value, list):
        raise TypeError(f"{name} must be a JSON list")
    return value


def _string(value: Any, name: str) -> str:
    """A JSON string of the result file (a model name, a channel)."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a JSON string")
    return value


def save_result(result: FitResult, path: str | os.PathLike) -> None:
    """Write ``result``'s file atomically (a temporary file renamed into place); :func:`load_result` reads it."""
    write_text_atomic(path, result.to_json())


def load_result(path: str | os.PathLike) -> FitResult:
    """Read a result file written by :func:`save_result` or ``brdffit fit``."""
    return FitResult.from_dict(read_json_object(path, "brdffit result file"), str(path))


def is_comparison(content: dict[str, Any]) -> bool:
    """Whether a JSON object is a comparison file (``brdffit compare -o``) rather than a result file."""
    return "criterion" in content and "models" in content


def read_json_object(path: str | os.PathLike, what: str) -> dict[str, Any]:
    """The JSON object in the file ``path``, or a one-line error naming the file and ``what`` it should be."""
    path = Path(path)
    try:
        content = parse_json(read_json_text(path))
    except FileNotFoundError:
        raise BrdfInputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise BrdfInputError(f"{path}: is a folder; give a {what}") from None
    except (OSError, ValueError) as error:  # ValueError: JSON's, and UnicodeDecodeError
        raise BrdfInputError(f"{path}: not a readable JSON file ({error})") from None
    if not isinstance(content, dict):
        raise BrdfInputError(f"{path}: not a {what} (not a JSON object)")
    return content


def first_non_finite(value: Any, where: str = "") -> tuple[str, float] | None:
    """The first number in ``value`` (nested dicts and lists) that is an infinity or NaN, with where it is
    (``rmse``, ``params.rho_s[0]``; a result's ``fit`` object is named by its fields alone), or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where, value
    if isinstance(value, dict):
        items = ((f"{where}.{key}" if where and where != "fit" else str(key), item) for key, item in value.items())
    elif isinstance(value, list | tuple):
        items = ((f"{where}[{index}]", item) for index, item in enumerate(value))
    else:
        return None
    for inner, item in items:
        found = first_non_finite(item, inner)
        if found is not None:
            return found
    return None


def json_text(value: Any, indent: str = "") -> str:
    """``value`` as brdffit's files write JSON: objects indented, lists of numbers on one line; strict (a NaN or
    infinity never reaches a file that claims to be JSON: ``allow_nan=False``)."""
    if isinstance(value, dict) and value:
        inner = indent + "  "
        items = [
            f"{inner}{json.dumps(str(key), ensure_ascii=False)}: {json_text(item, inner)}"
            for key, item in value.items()
        ]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and any(isinstance(item, dict | list) for item in value):
        inner = indent + "  "
        return "[\n" + ",\n".join(inner + json_text(item, inner) for item in value) + "\n" + indent + "]"
    return json.dumps(value, allow_nan=False, ensure_ascii=False)
