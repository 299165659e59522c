"""The HTML report of fitted maps (``brdffit report MAPS/``): what was fitted, every parameter map, where the fits
end badly, and the maps relit beside photographs, one self-contained page.

The page shows:

* the summary ``maps.json`` holds (model, texels fitted and converged, the rmse's median, the neighbour starts, the
  caveats);
* each parameter's map: a colour (``rho_d``, ``base_color``, …) as the sRGB image of its values, any other parameter
  on a colour scale with its bar, per channel where it has one value per channel;
* the cost map (log scale), the texels that did not converge and those with caveats;
* for photographs (``held_back``: a capture of the same plane and channels whose photographs the fit did not see, or
  else a few of the fitted capture's own, which says so): the photograph, the image the maps predict for its light
  and camera (``relight.py``), both at one exposure (the photograph's 99th percentile to white), and their relative
  difference in each texel's channel that differs most (NaN where the photograph is 0).
"""

import datetime
import html
import os
from pathlib import Path

import numpy as np

from .._files import write_text_atomic
from .._version import __version__
from ..errors import BrdfInputError, needs
from .capture import Capture, read_capture
from .images import srgb_encoded
from .maps import COLOUR_PARAMETERS, Maps, read_maps
from .relight import relight
from .texels import read_photographs

#: How many photographs of the fitted capture the report relights when none are held back.
SHOWN_PHOTOGRAPHS = 3


def maps_report(
    maps: Maps | str | os.PathLike,
    path: str | os.PathLike,
    held_back: Capture | str | os.PathLike | None = None,
) -> Path:
    """Write the report of ``maps`` (a :class:`~brdffit.svbrdf.maps.Maps` or a maps folder) to ``path`` (``.html``)
    atomically (module docstring); ``held_back``: a capture of photographs the fit did not see (default: a few of the
    fitted capture's own, as ``maps.json`` names it, where it is still there)."""
    needs("matplotlib", "plots", "the maps' report")
    from ..views.report import PAGE_STYLE, check_report_path

    path = check_report_path(path)
    maps = maps if isinstance(maps, Maps) else read_maps(maps)
    own = held_back is None
    capture = None
    if own and maps.capture and Path(maps.capture).exists():
        capture = read_capture(maps.capture)
    elif not own:
        capture = held_back if isinstance(held_back, Capture) else read_capture(held_back)  # type: ignore[arg-type]
        mine = (capture.shape, capture.width_mm, capture.height_mm, capture.channels)
        theirs = (maps.shape, maps.width_mm, maps.height_mm, maps.channels)
        if mine != theirs:
            raise BrdfInputError(
                f"{capture.file}: its plane ({capture.shape[0]} × {capture.shape[1]} texels of {capture.width_mm:g} ×"
                f" {capture.height_mm:g} mm, channels {', '.join(capture.channels)}) is not the maps' ({maps.shape[0]}"
                f" × {maps.shape[1]} of {maps.width_mm:g} × {maps.height_mm:g} mm, {', '.join(maps.channels)})"
            )
    title = html.escape(f"{maps.model} maps of {maps.capture or 'a capture'}")
    parts = [
        "<!DOCTYPE html>",
        f'<html lang="en"><head><meta charset="utf-8"><title>brdffit report: {title}</title>',
        f"<style>{PAGE_STYLE}</style></head><body>",
        f"<h1>brdffit report: {title}</h1>",
        f'<p class="note">brdffit {__version__}, {datetime.date.today().isoformat()}.</p>',
        _summary(maps),
        "<h2>The maps</h2>",
        *_parameter_figures(maps),
        "<h2>Where the fits end badly</h2>",
        _fit_figure(maps),
        "<h2>Relit beside photographs</h2>",
        *_relit_figures(maps, capture, own),
        "</body></html>\n",
    ]
    write_text_atomic(path, "\n".join(parts))
    return path


def _summary(maps: Maps) -> str:
    summary = maps.summary()
    rows, columns = maps.shape
    median = summary["median_rmse"]
    lines = [
        f"<p>{rows} × {columns} texels of a {maps.width_mm:g} × {maps.height_mm:g} mm sample; model"
        f" <code>{html.escape(maps.model)}</code> {html.escape(str(maps.model_options or ''))}, loss"
        f" <code>{html.escape(maps.loss)}</code>, channels {html.escape(', '.join(maps.channels))}.</p>",
        f"<p>{summary['fitted']:,} texels fitted, {summary['converged']:,} converged"
        + (f"; median rmse {median:.3g} in the loss's units" if median is not None else "")
        + (
            f"; {maps.neighbour_starts.get('improved', 0):,} of {maps.neighbour_starts.get('retried', 0):,} texels"
            " refitted from a neighbour's parameters ended lower"
            if maps.neighbour_starts
            else ""
        )
        + ".</p>",
    ]
    if maps.caveats():
        lines.append(f'<p class="warning">warning: {html.escape(maps.caveats() or "")}</p>')
    return "\n".join(lines)


def _parameter_figures(maps: Maps) -> list[str]:
    import matplotlib.pyplot as plt

    from ..views.report import embedded_figure

    figures = []
    for name, array in maps.params.items():
        if array.ndim == 3 and name in COLOUR_PARAMETERS and array.shape[-1] == 3:
            figure, axis = plt.subplots(figsize=(4, 4 * array.shape[0] / array.shape[1]), layout="constrained")
            axis.imshow(srgb_encoded(np.nan_to_num(array)), interpolation="nearest")
            axis.set_title(name)
            axis.set_axis_off()
            caption = f"<code>{html.escape(name)}</code> as a colour (sRGB; values above 1 clipped)."
        else:
            channels = [array] if array.ndim == 2 else [array[..., c] for c in range(array.shape[-1])]
            names = [name] if array.ndim == 2 else [f"{name}[{channel}]" for channel in maps.channels]
            figure, axes = plt.subplots(1, len(channels), figsize=(4 * len(channels), 3.4), layout="constrained")
            for axis, values, label in zip(np.atleast_1d(axes), channels, names, strict=True):
                shown = axis.imshow(values, interpolation="nearest", cmap="viridis")
                axis.set_title(label)
                axis.set_axis_off()
                figure.colorbar(shown, ax=axis, shrink=0.8)
            caption = f"<code>{html.escape(name)}</code>: each texel's fitted value (white: not fitted)."
        figures.append(embedded_figure(figure, caption))
        plt.close(figure)
    return figures


def _fit_figure(maps: Maps) -> str:
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    from ..views.report import embedded_figure

    cost, fitted = maps.fit["cost"], maps.fitted
    figure, axes = plt.subplots(1, 3, figsize=(12, 3.4), layout="constrained")
    positive = cost[fitted & (cost > 0)]
    norm = LogNorm(vmin=positive.min(), vmax=positive.max()) if positive.size else None
    shown = axes[0].imshow(np.where(cost > 0, cost, np.nan), norm=norm, interpolation="nearest", cmap="magma")
    figure.colorbar(shown, ax=axes[0], shrink=0.8)
    axes[0].set_title("cost (log scale)")
    axes[1].imshow(fitted & ~maps.fit["converged"], interpolation="nearest", cmap="gray_r", vmin=0, vmax=1)
    axes[1].set_title(f"not converged: {int(np.sum(fitted & ~maps.fit['converged']))}")
    most = max(1, int(maps.fit["n_caveats"].max()))
    caveats = axes[2].imshow(maps.fit["n_caveats"], interpolation="nearest", cmap="Reds", vmin=0, vmax=most)
    figure.colorbar(caveats, ax=axes[2], shrink=0.8)
    axes[2].set_title(f"caveats: {int(np.sum(maps.fit['n_caveats'] > 0))} texels")
    for axis in axes:
        axis.set_axis_off()
    caption = "Each texel's cost, the texels whose fit did not converge (black) and how many caveats each fit has."
    figure_html = embedded_figure(figure, caption)
    plt.close(figure)
    return figure_html


def _relit_figures(maps: Maps, capture: Capture | None, own: bool) -> list[str]:
    import matplotlib.pyplot as plt

    from ..views.report import embedded_figure

    if capture is None:
        return ['<p class="note">The capture the maps were fitted to is not where maps.json says; give the'
                " photographs with --held-back to compare.</p>"]  # fmt: skip
    photographs = read_photographs(capture)
    rows, columns = maps.shape
    chosen = np.linspace(0, len(capture.shots) - 1, min(SHOWN_PHOTOGRAPHS, len(capture.shots))).astype(int)
    chosen = np.arange(len(capture.shots)) if not own else np.unique(chosen)
    parts = [
        '<p class="note">'
        + (
            "Photographs of the capture the maps were fitted to: they saw these, so this shows the fit, not a"
            " prediction; give --held-back for photographs the fit did not see."
            if own
            else f"Held-back photographs ({html.escape(str(capture.file))}), which the fit did not see."
        )
        + "</p>"
    ]
    for index in chosen:
        shot = capture.shots[index]
        photograph = photographs.radiance[index].reshape(rows, columns, -1).astype(float)
        predicted = relight(maps, shot.light_mm, shot.camera_mm, shot.intensity)
        finite = photograph[np.isfinite(photograph)]
        exposure = 1.0 / max(float(np.percentile(finite, 99)), 1e-300) if finite.size else 1.0
        with np.errstate(invalid="ignore", divide="ignore"):  # a photograph's 0 has no relative difference: NaN
            relative = np.where(
                photograph > 0, (predicted - photograph) / np.where(photograph > 0, photograph, 1), np.nan
            )
        # signed where the channels agree in sign, the largest in size: opposite channels' errors do not cancel
        largest = np.nanargmax(np.nan_to_num(np.abs(relative), nan=-1.0), axis=-1)
        difference = np.take_along_axis(relative, largest[..., None], axis=-1)[..., 0]
        figure, axes = plt.subplots(1, 3, figsize=(12, 3.6), layout="constrained")
        for axis, image, title in ((axes[0], photograph, "photograph"), (axes[1], predicted, "the maps relit")):
            axis.imshow(_shown(image * exposure), interpolation="nearest")
            axis.set_title(title)
        limit = float(np.nanpercentile(np.abs(difference), 99)) if np.isfinite(difference).any() else 0.01
        shown = axes[2].imshow(difference, cmap="RdBu_r", vmin=-limit, vmax=limit, interpolation="nearest")
        figure.colorbar(shown, ax=axes[2], shrink=0.8)
        median = float(np.nanmedian(np.abs(difference))) if np.isfinite(difference).any() else float("nan")
        axes[2].set_title(f"relit / photograph − 1, largest channel (median |·| {median:.2%})")
        for axis in axes:
            axis.set_axis_off()
        light = ", ".join(f"{value:g}" for value in shot.light_mm)
        caption = (
            f"<code>{html.escape(shot.file.name)}</code>: light at ({light}) mm; photograph and relit image at one"
            f" exposure, and their relative difference (red: the maps brighter; median |·| {median:.2%})."
        )
        parts.append(embedded_figure(figure, caption))
        plt.close(figure)
    return parts


def _shown(image: np.ndarray) -> np.ndarray:
    """Radiance (already exposed) as an sRGB image: one channel as grey."""
    image = np.nan_to_num(image)
    image = np.repeat(image, 3, axis=-1) if image.shape[-1] == 1 else image[..., :3]
    return srgb_encoded(image)
