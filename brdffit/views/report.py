"""The fit report: one self-contained HTML file that says what the data are, which model suits them, and where it
misses.

The page holds, in order: the data summary of ``brdffit info`` (counts, coverage, reciprocity); the comparison of the
candidate models (``fitting/comparison/compare.py``: ranked by cross-validated loss, with AIC and BIC); then, for the
best model and the runner-up, the parameter table (with errors when an uncertainty method is asked for) and the fit's
warnings, and the figures: slices, the polar plot, each fit's residual map and the lit spheres. Images are PNG embedded
as base64 ``data:`` URIs and the style is inline, so the file opens offline, sent as it is, with no reference to
anything outside it.
"""

import base64
import datetime
import html
import io
import os
import re
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._files import write_text_atomic
from .._jax import float64
from .._version import __version__
from ..data.load import as_samples
from ..data.samples import Samples
from ..data.summary import describe
from ..errors import Argument, BrdfInputError, UncertaintyWarning
from ..fitting.comparison.compare import Comparison, compare
from ..fitting.options import Holding, Solving
from ..fitting.single.result import FitResult
from ..fitting.single.table import parameter_cells, uncertainty_line
from ..physics.models.model import Model
from ..uncertainty.mcmc import MCMC
from ..uncertainty.methods import check_options, with_uncertainty
from . import plots
from .figures import label, text_as_typed
from .residuals import colour_limit

#: Suffixes of the report file.
REPORT_SUFFIXES = (".html", ".htm")
#: How many of the best models the report shows in detail.
DETAILED = 2
#: Resolution of the embedded figures (dots per inch).
DPI = 96

PAGE_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 2em auto; max-width: 1200px;
       padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.5em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ccc; }
h3 { font-size: 1.1em; }
pre { background: #f6f6f6; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.5em 0; }
th, td { padding: 0.25em 0.7em; border-bottom: 1px solid #ddd; text-align: right; }
th { background: #f0f0f0; } td.name, th.name { text-align: left; font-family: monospace; }
tr.best td { background: #e8f4e8; font-weight: 600; } tr.near td { background: #f3f9f3; }
.warning { color: #8a4b00; } .note { color: #555; font-size: 0.9em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { color: #555; font-size: 0.9em; }
"""


@float64
def report(
    samples: Samples | str | os.PathLike,
    models: Sequence[str | Model] | None = None,
    loss: str = "log",
    *,
    folds: int = 5,
    seed: int = 0,
    uncertainty: str | None = None,
    mcmc: MCMC | None = None,
    max_theta: float | None = None,
    n_starts: int | None = None,
    max_steps: int | None = None,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    solving: Solving | None = None,
    holding: Holding | None = None,
    comparison: Comparison | None = None,
    path: str | os.PathLike | None = None,
    progress: bool | None = False,
) -> str:
    """The HTML report of ``samples`` (module docstring); also written to ``path`` (atomically) when given.

    ``models``, ``loss``, ``folds``, ``seed``, ``max_theta``, ``n_starts``, ``max_steps``, ``fixed``,
    ``bounds``, ``solving`` and ``holding`` are those of :func:`brdffit.compare`, which the report runs unless a
    ``comparison`` of these samples is given.
    ``uncertainty``: ``"laplace"`` or ``"mcmc"`` adds error bars to the parameter tables of the models shown;
    ``mcmc`` (:class:`brdffit.MCMC`: walkers, steps, burn, thin, seed) applies to ``"mcmc"``, as in :func:`brdffit.fit`.
    """
    check_options(uncertainty, mcmc)
    if path is not None:
        check_report_path(path)
    samples = as_samples(samples).within(max_theta)
    if comparison is None:
        comparison = compare(
            samples,
            models,
            loss,
            folds=folds,
            seed=seed,
            n_starts=n_starts,
            max_steps=max_steps,
            fixed=fixed,
            bounds=bounds,
            solving=solving,
            holding=holding,
            progress=progress,
        )
    shown = [score.result for score in comparison.models[:DETAILED]]
    if uncertainty is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UncertaintyWarning)  # the page shows them with each model
            shown = [with_uncertainty(result, samples, uncertainty, mcmc=mcmc) for result in shown]
    page = _page(samples, comparison, shown)
    if path is not None:
        write_text_atomic(path, page)
    return page


def check_report_path(path, argument: str = "path") -> Path:
    """``path`` if it ends in ``.html`` (or ``.htm``) and its folder exists."""
    path = Path(path)
    if path.suffix.lower() not in REPORT_SUFFIXES:
        raise BrdfInputError(Argument(argument, str(path)), f": the report must end in {', '.join(REPORT_SUFFIXES)}")
    if not path.parent.is_dir():
        raise BrdfInputError(Argument(argument, str(path)), f": folder {path.parent} does not exist")
    return path


def _page(samples: Samples, comparison: Comparison, shown: list[FitResult]) -> str:
    source = html.escape(samples.source)
    today = datetime.date.today().isoformat()
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>brdffit report: {source}</title><style>{PAGE_STYLE}</style></head><body>",
        f"<h1>brdffit report: {source}</h1>",
        f'<p class="note">brdffit {__version__}, {today}. {samples.n_samples} samples × {samples.n_channels}'
        f" channel(s), loss {html.escape(comparison.loss)}.</p>",
        "<h2>The data</h2>",
        f"<pre>{html.escape(describe(samples))}</pre>",
        "<h2>Which model</h2>",
        _comparison_table(comparison),
    ]
    names = " and ".join(f"<code>{html.escape(label(result))}</code>" for result in shown)
    parts.append(f"<h2>The best {'models' if len(shown) > 1 else 'model'}: {names}</h2>")
    for rank, result in enumerate(shown, 1):
        parts += [f"<h3>{rank}. <code>{html.escape(label(result))}</code></h3>", _parameter_table(result)]
        parts += [f'<p class="warning">warning: {html.escape(line)}</p>' for line in _warnings(result)]
    parts += [
        embedded_figure(
            plots.slices(shown, samples),
            "Slices: the data (points) and the fits (lines) against the viewer's"
            " signed zenith, in the plane of incidence and the perpendicular plane.",
        ),
        embedded_figure(
            plots.polar(shown, samples), "The plane of incidence as polar plots (radius: BRDF on a log scale)."
        ),
    ]
    limit = max(colour_limit(result, samples) for result in shown)  # one colour scale: the maps compare
    for result in shown:
        parts.append(
            embedded_figure(
                plots.residuals(result, samples, limit=limit),
                f"Where <code>{html.escape(label(result))}</code> misses: its residuals in the loss's units"
                " (red: the model above the data).",
            )
        )
    parts.append(
        embedded_figure(
            plots.sphere(shown, samples, lights="both"),
            "Lit spheres of the fits (and of the measured values, where the data cover the sphere), one exposure"
            " per row.",
        )
    )
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _comparison_table(comparison: Comparison) -> str:
    how = "whole light directions held out" if comparison.fold_kind == "light-direction" else "random"
    rows = [
        f'<p class="note">Ranked by the loss per residual on held-out samples: {comparison.folds} folds ({how}),'
        f" seed {comparison.seed}. Highlighted: the best and every model within one standard error of it.</p>",
        '<table><tr><th>rank</th><th class="name">model</th><th>k</th><th>cost</th><th>rmse (1/sr)</th>'
        "<th>AIC</th><th>BIC</th><th>CV loss ± s.e.</th><th>converged</th><th>warnings</th></tr>",
    ]
    for rank, score in enumerate(comparison.models, 1):
        kind = "best" if rank == 1 else "near" if comparison.within_one_stderr(score) else ""
        result = score.result
        rows.append(
            f'<tr class="{kind}"><td>{rank}</td><td class="name">{html.escape(score.spec)}</td><td>{score.k}</td>'
            f"<td>{result.cost:.5g}</td><td>{result.rmse:.4g}</td><td>{score.aic:.6g}</td><td>{score.bic:.6g}</td>"
            f"<td>{score.cv_loss:.4g} ± {score.cv_stderr:.2g}</td><td>{'yes' if result.converged else 'NO'}</td>"
            f"<td>{len(result.warnings)}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _parameter_table(result: FitResult) -> str:
    header = "".join(f"<th>{html.escape(channel)}</th>" for channel in result.channels)
    rows = [f'<table><tr><th class="name">parameter</th>{header}</tr>']
    for name, texts in parameter_cells(result).items():
        cells = "".join(f"<td>{html.escape(text)}</td>" for text in texts)
        rows.append(f'<tr><td class="name">{html.escape(name)}</td>{cells}</tr>')
    rows.append("</table>")
    status = "converged" if result.converged else f"NOT converged: {result.message}"
    method = f" · {uncertainty_line(result.uncertainty)}" if result.uncertainty else ""
    rows.append(
        f'<p class="note">cost {result.cost:.6g} · rmse {result.rmse:.4g} 1/sr · {result.n_steps} steps ·'
        f" {html.escape(status)}{html.escape(method)}</p>"
    )
    return "\n".join(rows)


def _warnings(result: FitResult) -> list[str]:
    return [*result.warnings, *(result.uncertainty["warnings"] if result.uncertainty else [])]


def embedded_figure(figure, caption: str) -> str:
    """A figure as an embedded PNG (base64 ``data:`` URI) with its caption (already HTML)."""
    buffer = io.BytesIO()
    text_as_typed(figure)
    figure.savefig(buffer, format="png", dpi=DPI)
    encoded = base64.b64encode(buffer.getvalue()).decode("ascii")
    return (
        f'<figure><img alt="{html.escape(re.sub("<[^>]+>", "", caption), quote=True)}"'
        f' src="data:image/png;base64,{encoded}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )
