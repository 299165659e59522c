"""The printed report of a fit: one row per parameter, one column per channel, ``value ± error`` where known."""

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .results import FitResult


def result_table(result: "FitResult", source: str | None = None) -> str:
    """A readable report of ``result``; ``source`` names the samples in its first line."""
    what = f" of {source}" if source else ""
    options = ", ".join(f"{key} {_shown(key, value)}" for key, value in result.model_options.items())
    options = f" ({options})" if options else ""
    size = f"{result.n_samples} samples × {len(result.channels)} channel(s)"
    lines = [f"{result.model}{options} fit{what}: {size}, loss {result.loss}"]
    rows = list(parameter_rows(result.params))
    errors = dict(parameter_rows(result.uncertainty["stderr"])) if result.uncertainty else {}
    fixed = {label for label, _ in parameter_rows(_nested(result.fixed))}
    label_width = max(len("parameter"), *(len(label) for label, _ in rows))
    columns = [str(c) for c in result.channels]
    cells = {
        label: [
            f"= {v:.10g}" if label in fixed else value_with_error(v, e, bool(errors))
            for v, e in zip(_as_list(value), _as_list(errors.get(label, [None] * len(_as_list(value)))), strict=True)
        ]
        for label, value in rows
    }
    cell = max(12, *(len(c) + 2 for c in columns), *(len(text) + 2 for texts in cells.values() for text in texts))
    lines.append("  " + "parameter".ljust(label_width) + "".join(c.rjust(cell) for c in columns))
    for label, texts in cells.items():
        lines.append("  " + label.ljust(label_width) + "".join(text.rjust(cell) for text in texts))
    status = "converged" if result.converged else f"NOT converged: {result.message}"
    precision = " · float32, refined in float64" if result.dtype == "float32" else ""
    figures = f"cost {result.cost:.6g} · rmse {result.rmse:.4g} 1/sr · {result.n_steps} steps"
    lines.append(f"  {figures}{precision} · {status}")
    if result.bounds:
        bounds = ", ".join(f"{name} in [{low:g}, {high:g}]" for name, (low, high) in result.bounds.items())
        lines.append(f"  bounds: {bounds}")
    if result.uncertainty:
        held = "; fixed parameters (= value) have no error" if result.fixed else ""
        lines.append("  " + _uncertainty_line(result.uncertainty) + held)
    lines += [f"  warning: {caveat}" for caveat in result.warnings]
    return "\n".join(lines)


def parameter_rows(params: dict[str, Any]):
    """(label, value) pairs in file order; Lafortune lobes become ``lobe 1 rho_s`` and so on, pca's coefficients
    ``coefficients[0]`` and so on."""
    for name, value in params.items():
        if name == "lobes":
            for index, lobe in enumerate(value, start=1):
                for lobe_name, lobe_value in lobe.items():
                    yield f"lobe {index} {lobe_name}", lobe_value
        elif isinstance(value, list) and value and isinstance(value[0], list):  # pca's coefficients, one row each
            for index, row in enumerate(value):
                yield f"{name}[{index}]", row
        else:
            yield name, value


def _nested(names: dict[str, Any]) -> dict[str, Any]:
    """Held parameters by name (``lobes[1].cxy``) nested as ``params`` is, for :func:`parameter_rows`' labels."""
    nested: dict[str, Any] = {}
    for name, value in names.items():
        lobe, dot, inner = name.partition("].")
        if name.startswith("lobes[") and dot:
            index = int(lobe[len("lobes[") :])
            lobes = nested.setdefault("lobes", [])
            lobes += [{} for _ in range(index + 1 - len(lobes))]
            lobes[index][inner] = value
        else:
            nested[name] = value
    return nested


def _shown(key: str, value) -> str:
    """A model option as the table's first line shows it: a file's digest by its first 12 digits."""
    return f"{value[:12]}…" if key.endswith("_sha256") and isinstance(value, str) else str(value)


def _as_list(value) -> list:
    return value if isinstance(value, list) else [value]


def value_with_error(value: float, error: float | None = None, has_error: bool = False) -> str:
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


def _uncertainty_line(block) -> str:
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
    if block.get("method") == "laplace-robust":
        return (
            "± Laplace standard error, heteroscedasticity-robust (sandwich A⁻¹BA⁻¹ at the optimum: the residuals'"
            " scatter varies, so the Gauss-Newton errors would be too small)"
        )
    if noise is not None:
        how = f"no sigma: scaled by the residuals' scatter, {noise:.3g} in the loss's units"
    else:
        how = f"sigma given; reduced χ² {chi2:.4g}" if isinstance(chi2, float) else "sigma given"
    return f"± Laplace standard error (Gauss-Newton covariance at the optimum; {how})"
