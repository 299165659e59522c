"""A fit as people read it: the printed table (``brdffit fit`` prints it), lmfit's ``fit_report()`` and the HTML a
notebook shows for a bare result. Each takes a :class:`~brdffit.FitResult` (``result.py``, which imports this module
for its ``__str__``: the result is taken as it is, not imported).

``fit_report`` follows lmfit's (``[[Model]]``, ``[[Fit Statistics]]``, ``[[Variables]]``, ``[[Correlations]]``) with
brdffit's figures: ``ndata``, ``nvarys``, ``chisqr``, ``redchi``, ``aic``, ``bic`` (``criteria.py``), the parameters'
cells as the printed table writes them (``value ± error``, ``= value`` for a held one) and the correlations of the
uncertainty estimate above :data:`MIN_CORRELATION`, strongest first.
"""

import html
import math
from typing import Any


def result_table(result, source: str | None = None) -> str:
    """A readable report of ``result``; ``source`` names the samples in its first line."""
    what = f" of {source}" if source else ""
    options = ", ".join(f"{key} {_shown(key, value)}" for key, value in result.model_options.items())
    options = f" ({options})" if options else ""
    size = f"{result.n_samples} samples × {len(result.channels)} channel(s)"
    lines = [f"{result.model}{options} fit{what}: {size}, loss {result.loss}"]
    cells = parameter_cells(result)
    label_width = max(len("parameter"), *(len(label) for label in cells))
    columns = [str(c) for c in result.channels]
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
        lines.append("  " + uncertainty_line(result.uncertainty) + held)
    lines += [f"  warning: {caveat}" for caveat in result.warnings]
    return "\n".join(lines)


def parameter_cells(result) -> dict[str, list[str]]:
    """The text of each parameter's cells, one per channel (one for a shared parameter), by row label
    (:func:`parameter_rows`): ``value ± error``, ``value ± undetermined (why)``, or ``= value`` for a held one."""
    errors = dict(parameter_rows(result.uncertainty["stderr"])) if result.uncertainty else {}
    why = dict(parameter_rows(result.uncertainty.undetermined)) if result.uncertainty else {}
    fixed = {label for label, _ in parameter_rows(_nested(result.fixed))}

    def per_channel(table: dict, label: str, value) -> list:
        return _as_list(table.get(label, [None] * len(_as_list(value))))

    return {
        label: [
            f"= {v:.10g}" if label in fixed else value_with_error(v, e, bool(errors), reason)
            for v, e, reason in zip(
                _as_list(value), per_channel(errors, label, value), per_channel(why, label, value), strict=True
            )
        ]
        for label, value in parameter_rows(result.params)
    }


#: What the ``±`` of each method's errors is, as the table's footer and the report name them.
ERRORS_SHOWN = {
    "laplace": "Laplace standard errors",
    "laplace-robust": "Laplace robust errors, for every parameter",
    "mcmc": "posterior standard deviation",
}


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
    """A model option as the table's first line shows it: a file's digest by its first 12 digits, a yes or no as
    ``true`` or ``false`` (as a spec writes it)."""
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value[:12]}…" if key.endswith("_sha256") and isinstance(value, str) else str(value)


def _as_list(value) -> list:
    return value if isinstance(value, list) else [value]


def value_with_error(value: float, error: float | None = None, has_error: bool = False, why: str | None = None) -> str:
    """``value`` to 6 significant digits, or ``value ± error`` with the error to 2 digits and the value to match.

    ``has_error`` with ``error`` None (undetermined) gives ``value ± undetermined (why)`` (``± undetermined`` when a
    file says no reason).
    """
    if not math.isfinite(value):
        return str(value)
    if error is None or not math.isfinite(error) or error <= 0:
        reason = f" ({why})" if why else ""
        return f"{value:.6g}" + (f" ± undetermined{reason}" if has_error and error is None else "")
    decimals = max(0, 1 - math.floor(math.log10(error)))
    if decimals > 7 or abs(value) >= 1e6:  # fixed point would be long: the value to its error's digits, in e-form
        digits = max(0, math.floor(math.log10(abs(value))) - math.floor(math.log10(error))) + 1 if value else 1
        return f"{value:.{min(digits, 12)}e} ± {error:.1e}"
    return f"{value:.{decimals}f} ± {error:.{decimals}f}"


def uncertainty_line(block) -> str:
    """One line on which errors the ``±`` shows (:data:`ERRORS_SHOWN`) and how they were found."""
    diagnostics = block.get("diagnostics", {})
    if block.get("method") == "mcmc":
        tau = max((t for t in diagnostics.get("autocorr_time", []) if t is not None), default=float("nan"))
        ess = min((e for e in diagnostics.get("effective_samples", []) if e is not None), default=float("nan"))
        return (
            f"± {ERRORS_SHOWN['mcmc']} (emcee: {diagnostics.get('n_walkers')} walkers × "
            f"{diagnostics.get('n_steps')} steps, {diagnostics.get('burn')} burn-in; acceptance "
            f"{diagnostics.get('acceptance', float('nan')):.2f}, τ ≤ {tau:.0f} steps, ≥ {ess:.0f} effective samples)"
        )
    noise, chi2 = diagnostics.get("noise_scale"), diagnostics.get("reduced_chi2")
    if block.get("method") == "laplace-robust":
        return (
            f"± {ERRORS_SHOWN['laplace-robust']} (heteroscedasticity-robust: sandwich A⁻¹BA⁻¹ at the"
            " optimum), in place of the standard errors, which assume one scatter for every residual where the"
            " residuals' scatter varies; both are in uncertainty.diagnostics"
        )
    if noise is not None:
        how = f"no sigma: scaled by the residuals' scatter, {noise:.3g} in the loss's units"
    else:
        how = f"sigma given; reduced χ² {chi2:.4g}" if isinstance(chi2, float) else "sigma given"
    return f"± {ERRORS_SHOWN['laplace']} (Gauss-Newton covariance at the optimum; {how})"


#: Correlations at most this in magnitude are not listed (lmfit's ``min_correl`` default).
MIN_CORRELATION = 0.1


def fit_report(result, min_correlation: float = MIN_CORRELATION) -> str:
    """The text report of ``result`` (module docstring); correlations whose magnitude exceeds ``min_correlation``."""
    options = ", ".join(f"{key}={value}" for key, value in result.model_options.items())
    status = "converged" if result.converged else f"NOT converged: {result.message}"
    lines = [
        "[[Model]]",
        f"    {result.model}" + (f" ({options})" if options else ""),
        "[[Fit Statistics]]",
        f"    # fitting method   = Levenberg-Marquardt, loss {result.loss}",
        f"    # steps            = {result.n_steps} ({status})",
        f"    # data points      = {result.ndata}",
        f"    # variables        = {result.nvarys}",
        f"    chi-square         = {result.chisqr:.8g}",
        f"    reduced chi-square = {result.redchi:.8g}",
        f"    Akaike info crit   = {result.aic:.8g}",
        f"    Bayesian info crit = {result.bic:.8g}",
        f"    rmse               = {result.rmse:.8g} 1/sr",
        "[[Variables]]",
    ]
    for name, cell in _variables(result):
        lines.append(f"    {name}:".ljust(24) + cell + (" (fixed)" if cell.startswith("=") else ""))
    if result.uncertainty:
        lines.append("    " + uncertainty_line(result.uncertainty))
    pairs = _correlations(result, min_correlation)
    if pairs:
        lines.append(f"[[Correlations]] (unreported correlations are < {min_correlation:.3f})")
        lines += [f"    C({first}, {second})".ljust(40) + f"= {value:+.4f}" for first, second, value in pairs]
    if result.warnings:
        lines.append("[[Warnings]]")
        lines += [f"    {warning}" for warning in result.warnings]
    return "\n".join(lines)


def result_html(result) -> str:
    """An HTML table of ``result`` for a notebook: the parameters by channel (the printed table's cells), lmfit's
    figures and the warnings."""
    channels = [str(channel) for channel in result.channels]
    cells = parameter_cells(result)
    header = "".join(f"<th>{html.escape(channel)}</th>" for channel in channels)
    rows = "".join(
        f"<tr><td>{html.escape(label)}</td>"
        + "".join(_cell(text, len(channels) if len(texts) == 1 else 1) for text in texts)
        + "</tr>"
        for label, texts in cells.items()
    )
    options = ", ".join(f"{key}={value}" for key, value in result.model_options.items())
    status = "converged" if result.converged else f"NOT converged: {result.message}"
    figures = (
        f"{result.n_samples} samples × {len(channels)} channel(s), loss {result.loss} · cost {result.cost:.6g} · rmse"
        f" {result.rmse:.4g} 1/sr · {result.n_steps} steps · {status}",
        f"ndata {result.ndata} · nvarys {result.nvarys} · redchi {result.redchi:.4g} · aic {result.aic:.6g}"
        f" · bic {result.bic:.6g}",
    )
    warnings = "".join(f"<li>{html.escape(warning)}</li>" for warning in result.warnings)
    return (
        f"<div><b>{html.escape(result.model)}</b>{html.escape(f' ({options})' if options else '')} fit<br>"
        f"<table><tr><th>parameter</th>{header}</tr>{rows}</table>"
        + "<br>".join(html.escape(line) for line in figures)
        + (f"<ul>{warnings}</ul>" if warnings else "")
        + "</div>"
    )


def _cell(text: str, span: int) -> str:
    """A table cell; a shared parameter's spans every channel's column."""
    return f'<td colspan="{span}">{html.escape(text)}</td>' if span > 1 else f"<td>{html.escape(text)}</td>"


def _variables(result):
    """(name, cell) for each value: ``rho_d[r]`` for a per-channel row, the row's label for a shared one."""
    for label, texts in parameter_cells(result).items():
        if len(texts) == 1:
            yield label, texts[0]
        else:
            for channel, text in zip(result.channels, texts, strict=True):
                yield f"{label}[{channel}]", text


def _correlations(result, min_correlation: float) -> list[tuple[str, str, float]]:
    """Pairs of the estimate's correlation matrix above ``min_correlation`` in magnitude, strongest first."""
    if not result.uncertainty or "correlation" not in result.uncertainty:
        return []
    block = result.uncertainty["correlation"]
    names, matrix = block["names"], block["matrix"]
    pairs = [
        (names[i], names[j], float(matrix[i][j]))
        for i in range(len(names))
        for j in range(i + 1, len(names))
        if matrix[i][j] is not None and math.isfinite(matrix[i][j]) and abs(matrix[i][j]) > min_correlation
    ]
    return sorted(pairs, key=lambda pair: -abs(pair[2]))
