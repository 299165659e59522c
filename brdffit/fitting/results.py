"""The result of a fit: :class:`FitResult`, its JSON file (SPEC section 5) and its printed table."""

import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._files import write_text_atomic
from .._version import __version__
from ..errors import BrdfInputError
from ..physics.evaluate import evaluate


@dataclass(frozen=True)
class FitResult:
    """Fitted parameters and how the fit went.

    ``params`` is the SPEC-section-5 dictionary (per-channel albedos as lists in
    ``channels`` order). ``cost`` is the sum of squared residuals of ``loss``;
    ``rmse`` the root-mean-square of ``f - y`` over the fitted samples and
    channels, in 1/sr, whatever the loss. ``n_steps`` counts Levenberg-Marquardt
    steps of the winning start; ``converged`` is False when the solver stopped
    without meeting its tolerances, and ``message`` then says why. ``dtype`` is
    the precision the model was evaluated in (``float32``: solved in single
    precision, then refined in double, so the optimum is float64's).
    ``uncertainty`` is the SPEC-section-5 block when one was asked for
    (``laplace.py``, ``mcmc.py``); ``posterior`` the MCMC draws of the physical
    parameters (S, p), in the order of ``uncertainty["covariance"]["names"]``,
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
    uncertainty: dict[str, Any] | None = None
    brdffit_version: str = field(default=__version__)
    posterior: np.ndarray | None = field(default=None, repr=False, compare=False)

    def with_posterior(self, draws: np.ndarray) -> "FitResult":
        """This result carrying the posterior ``draws`` (S, p)."""
        return replace(self, posterior=draws)

    def predict(self, wi, wo) -> np.ndarray:
        """The fitted model's BRDF (N, C) in 1/sr at directions ``wi``, ``wo`` (N, 3)."""
        return evaluate(self.model, self.params, wi, wo, **self.model_options)

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """The result file's content (SPEC section 5) as plain Python objects."""
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
            },
        }
        if self.uncertainty is not None:
            result["uncertainty"] = self.uncertainty
        return result

    def to_json(self) -> str:
        """The result file's text: indented objects, lists of numbers on one line."""
        return _to_json(self.to_dict()) + "\n"

    def save(self, path: str | os.PathLike) -> None:
        """Write the result file atomically (a temporary file renamed into place)."""
        write_text_atomic(path, self.to_json())

    @classmethod
    def from_dict(cls, content: dict[str, Any], source: str = "result") -> "FitResult":
        try:
            fit = content["fit"]
            return cls(
                model=content["model"],
                model_options=dict(content.get("model_options", {})),
                channels=tuple(content["channels"]),
                params=content["params"],
                loss=fit["loss"],
                cost=float(fit["cost"]),
                rmse=float(fit["rmse"]),
                n_samples=int(fit["n_samples"]),
                n_steps=int(fit["n_steps"]),
                converged=bool(fit["converged"]),
                message=str(fit.get("message", "")),
                dtype=str(fit.get("dtype", "float64")),
                uncertainty=content.get("uncertainty"),
                brdffit_version=str(content.get("brdffit_version", "")),
            )
        except (KeyError, TypeError, ValueError) as error:
            raise BrdfInputError(f"{source}: not a brdffit result file (missing or bad {error})") from None

    # ------------------------------------------------------------ the table
    def table(self, source: str | None = None) -> str:
        """A readable report: one row per parameter, one column per channel, and the fit's figures."""
        what = f" of {source}" if source else ""
        options = ", ".join(f"{key} {value}" for key, value in self.model_options.items())
        options = f" ({options})" if options else ""
        size = f"{self.n_samples} samples × {len(self.channels)} channel(s)"
        lines = [f"{self.model}{options} fit{what}: {size}, loss {self.loss}"]
        rows = list(_parameter_rows(self.params))
        errors = dict(_parameter_rows(self.uncertainty["stderr"])) if self.uncertainty else {}
        label_width = max(len("parameter"), *(len(label) for label, _ in rows))
        columns = [str(c) for c in self.channels]
        cells = {
            label: [
                _number(v, e, bool(errors))
                for v, e in zip(
                    _as_list(value), _as_list(errors.get(label, [None] * len(_as_list(value)))), strict=True
                )
            ]
            for label, value in rows
        }
        cell = max(12, *(len(c) + 2 for c in columns), *(len(text) + 2 for texts in cells.values() for text in texts))
        lines.append("  " + "parameter".ljust(label_width) + "".join(c.rjust(cell) for c in columns))
        for label, texts in cells.items():
            lines.append("  " + label.ljust(label_width) + "".join(text.rjust(cell) for text in texts))
        status = "converged" if self.converged else f"NOT converged: {self.message}"
        precision = " · float32, refined in float64" if self.dtype == "float32" else ""
        lines.append(f"  cost {self.cost:.6g} · rmse {self.rmse:.4g} 1/sr · {self.n_steps} steps{precision} · {status}")
        if self.uncertainty:
            lines.append("  " + _uncertainty_line(self.uncertainty))
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()


def load_result(path: str | os.PathLike) -> FitResult:
    """Read a result file written by :meth:`FitResult.save` or ``brdffit fit``."""
    path = Path(path)
    try:
        content = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BrdfInputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise BrdfInputError(f"{path}: not a readable JSON file ({error})") from None
    if not isinstance(content, dict):
        raise BrdfInputError(f"{path}: not a brdffit result file (not a JSON object)")
    return FitResult.from_dict(content, str(path))


def _to_json(value: Any, indent: str = "") -> str:
    # allow_nan=False: a NaN or infinity must never reach a file that claims to be JSON.
    if isinstance(value, dict) and value:
        inner = indent + "  "
        items = [f"{inner}{json.dumps(str(key))}: {_to_json(item, inner)}" for key, item in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and any(isinstance(item, dict | list) for item in value):
        inner = indent + "  "
        return "[\n" + ",\n".join(inner + _to_json(item, inner) for item in value) + "\n" + indent + "]"
    return json.dumps(value, allow_nan=False)


def _parameter_rows(params: dict[str, Any]):
    """(label, value) pairs in file order; Lafortune lobes become ``lobe 1 rho_s`` and so on."""
    for name, value in params.items():
        if name == "lobes":
            for index, lobe in enumerate(value, start=1):
                for lobe_name, lobe_value in lobe.items():
                    yield f"lobe {index} {lobe_name}", lobe_value
        else:
            yield name, value


def _as_list(value) -> list:
    return value if isinstance(value, list) else [value]


def _number(value: float, error: float | None = None, has_error: bool = False) -> str:
    """``value`` to 6 significant digits, or ``value ± error`` with the error to 2 digits and the value to match.

    ``has_error`` with ``error`` None (undetermined) gives ``value ± ?``.
    """
    if not math.isfinite(value):
        return str(value)
    if error is None or not math.isfinite(error) or error <= 0:
        return f"{value:.6g}" + (" ± ?" if has_error and error is None else "")
    decimals = max(0, 1 - math.floor(math.log10(error)))
    if decimals > 7 or abs(value) >= 1e6:  # fixed point would be long: the value to its error's digits, in e-form
        digits = max(0, math.floor(math.log10(abs(value))) - math.floor(math.log10(error))) + 1 if value else 1
        return f"{value:.{min(digits, 12)}e} ± {error:.1e}"
    return f"{value:.{decimals}f} ± {error:.{decimals}f}"


def _uncertainty_line(block: dict[str, Any]) -> str:
    """One line on how the errors were found."""
    diagnostics = block.get("diagnostics", {})
    if block.get("method") == "mcmc":
        tau = max((t for t in diagnostics.get("autocorr_time", []) if t is not None), default=float("nan"))
        ess = min((e for e in diagnostics.get("effective_samples", []) if e is not None), default=float("nan"))
        return (
            f"± posterior standard deviation (emcee: {diagnostics.get('n_walkers')} walkers × "
            f"{diagnostics.get('n_steps')} steps, {diagnostics.get('burn')} burn-in; acceptance "
            f"{diagnostics.get('acceptance', float('nan')):.2f}, τ ≤ {tau:.0f} steps, ≥ {ess:.0f} effective samples)"
        )
    noise, chi2 = diagnostics.get("noise_scale"), diagnostics.get("reduced_chi2")
    if noise is not None:
        how = f"no sigma: scaled by the residuals' scatter, {noise:.3g} in the loss's units"
    else:
        how = f"sigma given; reduced χ² {chi2:.4g}" if isinstance(chi2, float) else "sigma given"
    return f"± Laplace standard error (Gauss-Newton covariance at the optimum; {how})"
