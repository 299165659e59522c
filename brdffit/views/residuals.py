"""Maps of a fit's residuals, in the units of its loss, to see where a model misses the data.

A goniometer's data (few light directions) get one polar map per light direction over the viewer's hemisphere
(``θo`` as the radius, ``φo − φi`` as the angle); dense or random data one binned map over Rusinkiewicz's (1998)
half and difference angles ``(θh, θd)``. Colours diverge about 0 with symmetric limits: red where the model lies
above the data, blue below.
"""

import os
from typing import TYPE_CHECKING, NamedTuple, cast

import numpy as np
from matplotlib.figure import Figure

from ..data.samples import Samples
from ..data.summary import half_difference_angles
from ..errors import Argument, BrdfInputError
from ..fitting.objective.losses import LOSSES
from ..fitting.single.result import FitResult
from ..physics.geometry import direction_to_spherical
from .figures import characters_in, check_figure_path, checked_samples, evenly_spread, label, save_figure, wrapped

if TYPE_CHECKING:
    from matplotlib.projections.polar import PolarAxes

#: Data with at most this many distinct light directions are a goniometer's: one map per light direction.
MAX_LIGHTS = 12
#: At most this many maps; more light directions are evenly chosen among them (in increasing θi).
MAX_MAPS = 6
#: Maps per row.
MAP_COLUMNS = 3
#: The colour limits are ± this percentile of the |residuals| shown, so a few outliers do not wash out the rest.
LIMIT_PERCENTILE = 99
#: ... and at least this, in the loss's units: residuals below it are rounding (an exact fit shows white).
LIMIT_FLOOR = 1e-12
#: Bins per axis of the (θh, θd) map, the finest that leave on average this many samples per bin.
HALF_DIFFERENCE_BINS = (90, 60, 45, 30, 18, 9)
SAMPLES_PER_BIN = 10
COLOURMAP = "RdBu_r"


def residuals(
    result: FitResult, samples: Samples, *, limit: float | None = None, path: str | os.PathLike | None = None
) -> Figure:
    """Where the fit ``result`` misses ``samples``: its residuals (``result.residuals``, the loss's units, ``T(f) −
    T(y)`` scaled by weight and sigma; > 0 where the model lies above the data), averaged over the channels.

    Goniometer data (at most :data:`MAX_LIGHTS` distinct light directions, ``Samples.light_directions``): one polar
    map per light direction (at most :data:`MAX_MAPS`, evenly chosen), each sample a dot at radius θo (degrees) and
    angle ``φo − φi`` (0 towards the light, on the left; 180° the mirror side, on the right), the light's direction
    marked ×, the mirror direction +. Other data: the mean residual in bins of the half and difference angles
    ``(θh, θd)`` (Rusinkiewicz 1998, degrees), bins without samples left grey. The colour scale is diverging,
    centred at 0, with limits ± the :data:`LIMIT_PERCENTILE`-th percentile of the |residuals| shown (of the bin
    means, for the binned map), and never below :data:`LIMIT_FLOOR` (an exact fit shows white, not its rounding);
    ``limit`` sets it instead, so that the maps of several fits share one scale (:func:`colour_limit`). ``path``:
    also save the figure there (``.png``, ``.pdf``, ``.svg``). Returns the matplotlib
    :class:`~matplotlib.figure.Figure`.
    """
    if not isinstance(result, FitResult):
        raise BrdfInputError(Argument("result"), f" must be one FitResult, got {type(result).__name__}")
    samples = checked_samples(samples, [result])
    if tuple(result.channels) != tuple(samples.channels):
        raise BrdfInputError(
            Argument("result"),
            f": {label(result)} has channels {', '.join(result.channels)} but the samples have"
            f" {', '.join(samples.channels)}",
        )
    path = None if path is None else check_figure_path(path)
    if limit is not None and not (isinstance(limit, float | int) and np.isfinite(limit) and limit > 0):
        raise BrdfInputError(Argument.given("limit", limit), " is not allowed; give a positive number (or None)")
    shown = _shown(result, samples)
    limit = symmetric_limit(shown.values) if limit is None else float(limit)
    bar_label = colour_bar_label(result, samples)
    if shown.lights is not None:
        figure = _light_maps(samples, shown, limit, bar_label)
    else:
        figure = _half_difference_map(samples, shown, limit, bar_label)
    title = f"{label(result)} on {samples.source}: where the fit misses"
    figure.suptitle(wrapped(title, characters_in(figure.get_figwidth(), 11)), fontsize=11)
    if path is not None:
        save_figure(figure, path)
    return figure


def colour_bar_label(result: FitResult, samples: Samples) -> str:
    """What the colours are: the loss's residual, how it is scaled, over which channels, and its sign."""
    scaled = (" × √weight" if samples.weight is not None else "") + (" ÷ σ" if samples.sigma is not None else "")
    channels = samples.channels[0] if samples.n_channels == 1 else f"mean of {samples.n_channels} channels"
    return f"{result.loss}-loss residual{scaled} ({channels})\n{LOSSES[result.loss].summary}\n> 0: model above the data"


def symmetric_limit(values: np.ndarray) -> float:
    """± this limit holds the :data:`LIMIT_PERCENTILE`-th percentile of |values| (finite ones), at least
    :data:`LIMIT_FLOOR`."""
    magnitudes = np.abs(values[np.isfinite(values)])
    limit = float(np.percentile(magnitudes, LIMIT_PERCENTILE)) if magnitudes.size else 0.0
    return max(limit, LIMIT_FLOOR)


def colour_limit(result: FitResult, samples: Samples) -> float:
    """The colour limit :func:`residuals` would choose for ``result`` on ``samples``; the largest over several fits
    puts their maps on one scale."""
    return symmetric_limit(_shown(result, samples).values)


class _Shown(NamedTuple):
    """What a residual map shows: the channel-mean residual of each sample (N,), and either the light directions
    mapped (``lights``: the chosen indices, ``light_index`` of each sample) or the (θh, θd) bins (``edges`` (n+1,),
    ``means`` (n, n), NaN where empty). ``values``: the numbers the colour limit is taken from."""

    mean_residual: np.ndarray
    values: np.ndarray
    lights: np.ndarray | None = None
    light_index: np.ndarray | None = None
    n_lights: int = 0
    edges: np.ndarray | None = None
    means: np.ndarray | None = None


def _shown(result: FitResult, samples: Samples) -> _Shown:
    mean_residual = np.mean(result.residuals(samples), axis=1)
    lights, light_index = samples.light_directions()
    if len(lights) <= MAX_LIGHTS:
        theta_i = samples.theta_i
        # Lights in increasing θi (the mean over the samples that share one), then evenly chosen.
        order = np.argsort([np.mean(theta_i[light_index == k]) for k in range(len(lights))], kind="stable")
        shown = order[evenly_spread(len(lights), MAX_MAPS)]
        selected = mean_residual[np.isin(light_index, shown)]
        return _Shown(mean_residual, selected, shown, light_index, len(lights))
    edges, means = _binned(samples, mean_residual)
    return _Shown(mean_residual, means, edges=edges, means=means)


def _binned(samples: Samples, mean_residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean residual in (θh, θd) bins: the finest of :data:`HALF_DIFFERENCE_BINS` that averages at least
    :data:`SAMPLES_PER_BIN` samples per bin and leaves no empty bin between two full ones along either axis (MERL's
    θh grid is quadratic: at 1° its bins above 25° alternate full and empty, an artefact of the grid, not a hole
    in the data). Returns the edges (n + 1,) in degrees and the means (n, n), rows θd, columns θh."""
    theta_h, theta_d = half_difference_angles(samples)
    for bins in HALF_DIFFERENCE_BINS:
        edges = np.linspace(0.0, 90.0, bins + 1)
        column = np.clip(np.searchsorted(edges, theta_h, side="right") - 1, 0, bins - 1)
        row = np.clip(np.searchsorted(edges, theta_d, side="right") - 1, 0, bins - 1)
        cell = row * bins + column
        counts = np.bincount(cell, minlength=bins * bins).reshape(bins, bins)
        enough = samples.n_samples >= SAMPLES_PER_BIN * bins * bins
        if bins == HALF_DIFFERENCE_BINS[-1] or (enough and not _has_gaps(counts > 0)):
            break
    sums = np.bincount(cell, weights=mean_residual, minlength=bins * bins).reshape(bins, bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        return edges, np.where(counts > 0, sums / counts, np.nan)


def _has_gaps(full: np.ndarray) -> bool:
    """Whether some empty cell lies between two full ones, along a row or a column."""
    between_columns = ~full[:, 1:-1] & full[:, :-2] & full[:, 2:]
    between_rows = ~full[1:-1, :] & full[:-2, :] & full[2:, :]
    return bool(between_columns.any() or between_rows.any())


def _light_maps(samples: Samples, shown_maps: _Shown, limit: float, bar_label: str) -> Figure:
    theta_i = samples.theta_i
    mean_residual, light_index, n_lights = shown_maps.mean_residual, shown_maps.light_index, shown_maps.n_lights
    shown = shown_maps.lights
    assert shown is not None and light_index is not None  # lights mapped (_shown)
    columns = min(MAP_COLUMNS, len(shown))
    rows = -(-len(shown) // columns)
    figure = Figure(figsize=(0.4 + 3.3 * columns + 1.6, 0.7 + 3.4 * rows), layout="constrained")
    _, phi_i = direction_to_spherical(samples.wi)
    _, phi_o = direction_to_spherical(samples.wo)
    theta_o = samples.theta_o
    mappable = None
    axes = []
    for index, light in enumerate(shown):
        members = light_index == light
        axis = cast("PolarAxes", figure.add_subplot(rows, columns, index + 1, projection="polar"))
        axes.append(axis)
        axis.set_theta_zero_location("W")  # towards the light on the left, the mirror side on the right
        axis.set_theta_direction(-1)
        delta = np.mod(phi_o[members] - phi_i[members], 2 * np.pi)
        order_drawn = np.argsort(np.abs(mean_residual[members]))  # the largest residuals on top
        mappable = axis.scatter(
            delta[order_drawn],
            theta_o[members][order_drawn],
            c=mean_residual[members][order_drawn],
            s=_dot_area(int(members.sum())),
            cmap=COLOURMAP,
            vmin=-limit,
            vmax=limit,
            linewidths=0,
        )
        light_theta = float(np.mean(theta_i[members]))
        axis.plot([np.pi], [light_theta], marker="+", color="k", markersize=9, linestyle="", gid="mirror")
        axis.plot([0.0], [light_theta], marker="x", color="k", markersize=6, linestyle="", gid="light")
        axis.set_rlim(0, 90)
        axis.set_rticks([30, 60])
        axis.set_rlabel_position(67.5)  # between the azimuth labels
        axis.set_yticklabels(["30°", "60°"], fontsize=7)
        axis.tick_params(axis="x", labelsize=7)
        light_phi = float(np.degrees(phi_i[members][0]))
        azimuth = f", φi = {light_phi:.3g}°" if abs(light_phi) > 0.25 and light_theta > 0.25 else ""
        axis.set_title(f"θi = {light_theta:.3g}°{azimuth} ({int(members.sum())} samples)", fontsize=9)
    assert mappable is not None  # one light or more
    bar = figure.colorbar(mappable, ax=axes, shrink=0.8, extend="both")
    bar.set_label(bar_label, fontsize=8)
    shown_note = f"{len(shown)} of {n_lights} light directions; " if len(shown) < n_lights else ""
    figure.text(
        0.01,
        0.005,
        f"{shown_note}angle: φo − φi (0° towards the light), radius: θo (0–90°); × the light, + the mirror direction",
        fontsize=8,
        color="0.3",
    )
    return figure


def _half_difference_map(samples: Samples, shown: _Shown, limit: float, bar_label: str) -> Figure:
    edges, means = shown.edges, shown.means
    assert edges is not None and means is not None  # binned (_shown)
    bins = len(edges) - 1
    figure = Figure(figsize=(6.4, 5.0), layout="constrained")
    axis = figure.add_subplot()
    axis.set_facecolor("0.85")
    mesh = axis.pcolormesh(edges, edges, np.ma.masked_invalid(means), cmap=COLOURMAP, vmin=-limit, vmax=limit)
    axis.set_xlabel("θh (°), half vector from the normal")
    axis.set_ylabel("θd (°), light from the half vector")
    axis.set_xlim(0, 90)
    axis.set_ylim(0, 90)
    axis.set_xticks(np.arange(0, 91, 15))
    axis.set_yticks(np.arange(0, 91, 15))
    axis.set_aspect("equal")
    axis.set_title(
        f"mean residual in {90 / bins:.3g}° × {90 / bins:.3g}° bins ({samples.n_samples} samples; grey: none)",
        fontsize=9,
    )
    bar = figure.colorbar(mesh, ax=axis, extend="both")
    bar.set_label(bar_label, fontsize=8)
    return figure


def _dot_area(count: int) -> float:
    """Dot area (points²): dots that touch for a dense grid of a thousand, larger when few."""
    return float(np.clip(15000.0 / max(count, 1), 3.0, 80.0))
