"""Slices through a BRDF: data and fitted models against the viewer's zenith angle in the plane of incidence (and
the plane perpendicular to it), one panel per incidence, on a log scale.

These are the figures of Ngan et al. 2005 ("Experimental analysis of BRDF models", EGSR), which compare measured
and fitted values along the plane of incidence. :func:`polar` (``polar.py``) draws the same slices as BRDF
Explorer's polar plots; both take their incidences, in-plane samples and model curves from this module.

Angles: the plane of incidence holds the normal and the light; a viewer direction in it has the signed zenith
``θo > 0 on the mirror side`` (azimuth ``φi + 180°``: the specular peak lies at ``θo = +θi``, retro-reflection at
``θo = −θi``). The perpendicular plane holds the normal and the azimuths ``φi ± 90°``, ``θo > 0`` at ``φi + 90°``.
Each sample's plane is taken about its own light azimuth, so data measured at several light azimuths share a panel
(exact for isotropic materials); model curves use the panel's light azimuth (:func:`incidence_panels`).
"""

import numbers
import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..checks import whole_number
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError, not_allowed
from ..fitting.comparison.compare import Comparison
from ..fitting.single.result import FitResult
from ..physics.geometry import direction_to_spherical, spherical_to_direction
from .figures import (
    FIT_STYLES,
    as_list,
    channel_colour,
    characters_in,
    check_figure_path,
    checked_samples,
    evenly_spread,
    label,
    save_figure,
    wrapped,
)

#: A sample lies in a plane when its viewer direction is within this angle (degrees) of the plane.
PLANE_TOLERANCE = 0.5
#: Light zeniths are told apart after rounding to this step (degrees): the data's distinct incidences.
INCIDENCE_STEP = 0.5
#: Data with at most this many distinct incidences are a goniometer's: each panel is one of them. With more
#: (random or dense data), panels sit at whole degrees across the data's range.
MAX_DISTINCT_INCIDENCES = 12
#: For an incidence given or binned (not one of the data's own), samples whose θi lies within this (degrees).
INCIDENCE_TOLERANCE = 0.5
#: Spacing (degrees) of the model curves along a plane; the mirror and retro directions are always included.
CURVE_STEP = 0.25
#: The curves stop this short of the horizon (degrees), where most models fall to 0.
HORIZON_MARGIN = 0.5
#: The value axis spans at most this ratio: the floor is at least the top value / DYNAMIC_RANGE.
DYNAMIC_RANGE = 1e6
#: The planes a slice lies in, as the value axis names them ...
PLANES = {
    "incidence": "plane of incidence",
    "perpendicular": "perpendicular plane",
}
#: ... and how each names its signed θo.
AXIS_LABELS = {
    "incidence": "signed θo (°), > 0 on the mirror side",
    "perpendicular": "signed θo (°), > 0 at φi + 90°",
}
#: The longest line of a fit's name in a legend (8-point, beside the panels); a longer spec wraps after its
#: ``:`` and ``,``.
LEGEND_CHARACTERS = 26
#: Channels named in a legend; more (spectral bands) are summarised.
LEGEND_CHANNELS = 8


@dataclass(frozen=True)
class Incidence:
    """One panel's light: zenith ``theta_i`` and azimuth ``phi_i`` in degrees (the model curves' light), and which
    samples were measured at it (``members``, a boolean mask over the samples)."""

    theta_i: float
    phi_i: float
    members: np.ndarray


@dataclass(frozen=True)
class Slice:
    """One plane at one incidence: the in-plane samples (signed θo in degrees, values (n, C) in 1/sr) and each
    fit's model curve (values (M, C) in 1/sr at the signed θo ``curve_theta_o``)."""

    incidence: Incidence
    plane: str
    data_theta_o: np.ndarray
    data_values: np.ndarray
    curve_theta_o: np.ndarray
    curves: list[np.ndarray]


def slices(
    results: FitResult | Sequence[FitResult],
    samples: Samples,
    *,
    incidences=None,
    max_panels: int = 4,
    perpendicular: bool = True,
    path: str | os.PathLike | None = None,
) -> Figure:
    """Measured values and each fit's model against the signed viewer zenith θo (degrees), one panel per incidence.

    The first row is the plane of incidence (``θo > 0`` on the mirror side); a second row the perpendicular plane
    (``θo > 0`` at azimuth ``φi + 90°``), when ``perpendicular`` and some samples lie in it. Values are BRDF in
    1/sr on a log axis shared by every panel: points are the samples within :data:`PLANE_TOLERANCE` degrees of the
    plane at that incidence, lines each result's ``predict`` along it (colour: channel; line style: fit, named in
    the legend by :func:`~brdffit.views.figures.label`). Values at or below the axis floor (zeros included) are drawn
    on the floor as ▽. Pale vertical bands mark the mirror (``+θi``) and retro (``−θi``) directions. A panel with no
    samples in its plane (random data) says so and still shows the curves. As in Ngan et al. 2005's comparisons.

    ``results``: one :class:`FitResult` or several (with the samples' channels). ``incidences``: light zeniths in
    degrees to show (samples within :data:`INCIDENCE_TOLERANCE`); by default the data's distinct incidences, at
    most ``max_panels`` of them, evenly chosen (see :func:`incidence_panels`). ``path``: also save the figure there
    (``.png``, ``.pdf``, ``.svg``). Returns the figure (matplotlib's :class:`~matplotlib.figure.Figure`, no pyplot).
    """
    results, samples, path = checked_arguments(results, samples, path)
    perpendicular = _checked_flag("perpendicular", perpendicular)
    panels = incidence_panels(samples, incidences, max_panels)
    rows = [plane_slices(results, samples, panels, "incidence")]
    if perpendicular:
        across = plane_slices(results, samples, panels, "perpendicular")
        if any(cut.data_theta_o.size for cut in across):
            rows.append(across)
    floor, top = value_range([cut for row in rows for cut in row])

    columns = len(panels)
    figure = Figure(figsize=(0.6 + 3.3 * columns + 2.2, 0.5 + 3.0 * len(rows)), layout="constrained")
    axes = figure.subplots(len(rows), columns, sharex=True, sharey=True, squeeze=False)
    below_floor = False
    for row, cuts in enumerate(rows):
        for column, cut in enumerate(cuts):
            axis = axes[row, column]
            below_floor |= _draw_slice(axis, cut, results, samples.channels, floor)
            axis.set_yscale("log")
            axis.set_xlim(-90, 90)
            axis.set_xticks(np.arange(-90, 91, 30))
            axis.grid(True, which="major", color="0.9", linewidth=0.6)
            axis.set_title(incidence_title(cut.incidence), fontsize=10)
            if column == 0:
                axis.set_ylabel(f"{PLANES[cut.plane]}\nBRDF (1/sr)")
            axis.set_xlabel(AXIS_LABELS[cut.plane], fontsize=9)
    axes[0, 0].set_ylim(floor, top)
    figure.legend(
        handles=legend_handles(results, samples.channels, below_floor=below_floor, directions=True),
        loc="outside right upper",
        fontsize=8,
        frameon=False,
    )
    figure.suptitle(
        wrapped(f"{samples.source}: slices through the BRDF", characters_in(figure.get_figwidth(), 11)), fontsize=11
    )
    if path is not None:
        save_figure(figure, path)
    return figure


# ------------------------------------------------------------------ arguments
def checked_arguments(results, samples, path) -> tuple[list[FitResult], Samples, Path | None]:
    """``results`` as a list of :class:`FitResult` with the samples' channels, the samples, and the figure path
    (None, or a path whose suffix matplotlib writes in a folder that exists); one-line errors naming the argument."""
    fits = isinstance(results, FitResult | Comparison | Sequence) and not isinstance(results, str)
    listed = as_list(results) if fits else None
    if not listed or not all(isinstance(result, FitResult) for result in listed):
        raise BrdfInputError(
            Argument("results"), f" must be a FitResult or a non-empty list of them, got {_described(results)}"
        )
    samples = checked_samples(samples, listed)
    for result in listed:
        if tuple(result.channels) != tuple(samples.channels):
            raise BrdfInputError(
                Argument("results"),
                f": {label(result)} has channels {', '.join(result.channels)} but the samples have"
                f" {', '.join(samples.channels)}",
            )
    return listed, samples, None if path is None else check_figure_path(path)


def _checked_flag(name: str, value) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise not_allowed(name, value, "give True or False")
    return bool(value)


def _checked_incidences(value) -> np.ndarray:
    single = isinstance(value, numbers.Real) and not isinstance(value, bool)
    try:
        angles = np.array([value] if single else list(value), dtype=float)
    except (TypeError, ValueError):
        angles = None
    if angles is None or angles.size == 0 or not np.all((angles >= 0) & (angles < 90)):
        raise not_allowed("incidences", value, "give light zenith angles in degrees, each in [0, 90)")
    return angles


def _described(value) -> str:
    return f"an empty {type(value).__name__}" if isinstance(value, Sequence) and not value else type(value).__name__


# ------------------------------------------------------------------ incidences
def incidence_panels(samples: Samples, incidences=None, max_panels: int = 4) -> list[Incidence]:
    """The incidences to show, in increasing θi.

    ``incidences`` (degrees) given: those, each with the samples within :data:`INCIDENCE_TOLERANCE` of it.
    Otherwise the data's distinct light zeniths (after rounding to :data:`INCIDENCE_STEP`): all of them if at most
    ``max_panels``; ``max_panels`` evenly spread ones if at most :data:`MAX_DISTINCT_INCIDENCES` (each at the mean
    θi of its samples); for random or dense data, whole degrees at the middles of ``max_panels`` equal bins of the
    data's θi range (samples within :data:`INCIDENCE_TOLERANCE`: a narrow slice of such data, often empty).
    The light azimuth of a panel's model curves is that of most of its samples (rounded to :data:`INCIDENCE_STEP`)
    when they agree, else 0 (the tangent).
    """
    max_panels = whole_number("max_panels", max_panels, 1, MAX_DISTINCT_INCIDENCES)
    theta_i = samples.theta_i
    if incidences is not None:
        centres = _checked_incidences(incidences)
        chosen = [(centre, np.abs(theta_i - centre) <= INCIDENCE_TOLERANCE) for centre in np.unique(centres)]
    else:
        rounded = np.round(theta_i / INCIDENCE_STEP) * INCIDENCE_STEP
        distinct = np.unique(rounded)
        if len(distinct) <= MAX_DISTINCT_INCIDENCES:
            picked = distinct[evenly_spread(len(distinct), max_panels)]
            chosen = []
            for value in picked:
                members = rounded == value
                chosen.append((float(np.mean(theta_i[members])), members))
        else:
            edges = np.linspace(theta_i.min(), theta_i.max(), max_panels + 1)
            centres = np.unique(np.round((edges[:-1] + edges[1:]) / 2))
            chosen = [(centre, np.abs(theta_i - centre) <= INCIDENCE_TOLERANCE) for centre in centres]
    _, light_azimuth = direction_to_spherical(samples.wi)
    return [
        Incidence(float(centre), _panel_azimuth(np.degrees(light_azimuth[members]), centre), members)
        for centre, members in chosen
    ]


def _panel_azimuth(azimuths: np.ndarray, theta_i: float) -> float:
    """The light azimuth (degrees) most of a panel's samples share, or 0 when they do not (or the light is at the
    normal, where azimuth means nothing)."""
    if azimuths.size == 0 or theta_i < INCIDENCE_STEP:
        return 0.0
    rounded = np.round(azimuths / INCIDENCE_STEP) * INCIDENCE_STEP
    value, count = Counter(np.where(rounded == -180.0, 180.0, rounded).tolist()).most_common(1)[0]
    return float(value) if 2 * count >= azimuths.size else 0.0


def incidence_title(incidence: Incidence) -> str:
    azimuth = f", φi = {incidence.phi_i:.3g}°" if incidence.phi_i != 0 else ""
    return f"θi = {incidence.theta_i:.3g}°{azimuth}"


# ------------------------------------------------------------------ planes
def in_plane(samples: Samples, plane: str) -> tuple[np.ndarray, np.ndarray]:
    """Which samples lie in ``plane`` ("incidence" or "perpendicular", about each sample's own light azimuth) within
    :data:`PLANE_TOLERANCE` degrees, and every sample's signed θo in degrees (its zenith ``samples.theta_o``, > 0 on
    the mirror side, or at ``φi + 90°`` for the perpendicular plane).

    The distance of ``wo`` from the plane is ``asin(sin θo · |sin Δφ|)`` (incidence) or ``asin(sin θo · |cos Δφ|)``
    (perpendicular), with ``Δφ = φo − φi``.
    """
    _, phi_i = direction_to_spherical(samples.wi)
    theta_o, phi_o = direction_to_spherical(samples.wo)
    delta = phi_o - phi_i
    # along: the azimuth's component towards the plane's positive side; across: towards its normal.
    along, across = (-np.cos(delta), np.sin(delta)) if plane == "incidence" else (np.sin(delta), np.cos(delta))
    inside = np.sin(theta_o) * np.abs(across) <= np.sin(np.radians(PLANE_TOLERANCE))
    return inside, np.where(along >= 0, 1.0, -1.0) * samples.theta_o


def plane_directions(theta_i: float, phi_i: float, signed_theta_o: np.ndarray, plane: str):
    """Light and viewer directions (M, 3) for the light at (``theta_i``, ``phi_i``) and viewers at the signed zeniths
    ``signed_theta_o`` of ``plane`` (all degrees; the sign convention of :func:`in_plane`)."""
    positive, negative = (180.0, 0.0) if plane == "incidence" else (90.0, -90.0)
    phi_o = np.radians(phi_i + np.where(signed_theta_o > 0, positive, negative))
    wo = np.asarray(spherical_to_direction(np.radians(np.abs(signed_theta_o)), phi_o))
    wi = np.asarray(spherical_to_direction(np.radians(theta_i), np.radians(phi_i)))
    return np.broadcast_to(wi, wo.shape), wo


def curve_angles(theta_i: float, plane: str) -> np.ndarray:
    """Signed θo (degrees) where the model curves are evaluated: every :data:`CURVE_STEP` degrees up to
    :data:`HORIZON_MARGIN` from the horizon, plus the mirror and retro directions (sharp peaks are not missed)."""
    limit = 90.0 - HORIZON_MARGIN
    grid = np.arange(-limit, limit + CURVE_STEP / 2, CURVE_STEP)
    special = [theta_i, -theta_i] if plane == "incidence" else []
    return np.unique(np.concatenate([grid, special]))


def plane_slices(results: list[FitResult], samples: Samples, panels: list[Incidence], plane: str) -> list[Slice]:
    """Each panel's :class:`Slice` of ``plane``: its in-plane samples and every result's model curve; each result is
    evaluated once over all panels (one compiled evaluation)."""
    inside, signed = in_plane(samples, plane)
    angles = [curve_angles(panel.theta_i, plane) for panel in panels]
    directions = [plane_directions(p.theta_i, p.phi_i, a, plane) for p, a in zip(panels, angles, strict=True)]
    wi = np.concatenate([pair[0] for pair in directions])
    wo = np.concatenate([pair[1] for pair in directions])
    splits = np.cumsum([a.size for a in angles])[:-1]
    predicted = [np.split(result.predict(wi, wo), splits) for result in results]
    cuts = []
    for index, (panel, theta_o) in enumerate(zip(panels, angles, strict=True)):
        chosen = panel.members & inside
        order = np.argsort(signed[chosen], kind="stable")
        cuts.append(
            Slice(
                panel,
                plane,
                signed[chosen][order],
                samples.values[chosen][order],
                theta_o,
                [curves[index] for curves in predicted],
            )
        )
    return cuts


def value_range(cuts: list[Slice]) -> tuple[float, float]:
    """The value axis (floor, top) in 1/sr: from half the smallest positive value shown to twice the largest, the
    floor no lower than ``top / DYNAMIC_RANGE`` (a model's values near the horizon can fall to 1e-30)."""
    shown = [cut.data_values.ravel() for cut in cuts] + [curve.ravel() for cut in cuts for curve in cut.curves]
    values = np.concatenate(shown)
    positive = values[np.isfinite(values) & (values > 0)]
    if positive.size == 0:
        return 1e-3, 1.0
    top = 2.0 * positive.max()
    return max(0.5 * positive.min(), top / DYNAMIC_RANGE), top


# ------------------------------------------------------------------ drawing
def _draw_slice(axis, cut: Slice, results: list[FitResult], channels: Sequence[str], floor: float) -> bool:
    """Draw one slice on cartesian axes; True when some data lie at or below the floor (drawn there as ▽)."""
    if cut.plane == "incidence":
        for direction in sorted({cut.incidence.theta_i, -cut.incidence.theta_i}):
            # A thin pale band, unlike any fit's line style.
            axis.axvline(direction, color="0.85", linestyle="-", linewidth=3, zorder=0, gid="direction")
    below = False
    for index in range(len(results)):
        for channel in range(len(channels)):
            axis.plot(
                cut.curve_theta_o,
                cut.curves[index][:, channel],
                color=channel_colour(channels, channel),
                linestyle=FIT_STYLES[index % len(FIT_STYLES)],
                linewidth=1.3,
                gid=f"fit:{index}:{channels[channel]}",
            )
    count = cut.data_theta_o.size
    for channel in range(len(channels) if count else 0):
        values = cut.data_values[:, channel]
        low = values <= floor
        axis.plot(
            cut.data_theta_o[~low],
            values[~low],
            linestyle="",
            marker="o",
            markersize=_marker_size(count),
            markerfacecolor="none",  # open: a curve that fits stays visible through its points
            markeredgewidth=0.8,
            alpha=0.8,
            zorder=3,
            color=channel_colour(channels, channel),
            gid=f"data:{channels[channel]}",
        )
        if low.any():
            below = True
            axis.plot(
                cut.data_theta_o[low],
                np.full(low.sum(), floor),
                linestyle="",
                marker="v",
                markersize=4,
                markerfacecolor="none",
                color=channel_colour(channels, channel),
                gid=f"floor:{channels[channel]}",
                clip_on=False,
            )
    note = (
        f"{count} sample{'s' if count > 1 else ''}"
        if count
        else f"no samples within {PLANE_TOLERANCE:g}° of this plane"
    )
    axis.text(0.02, 0.98, note, transform=axis.transAxes, ha="left", va="top", fontsize=7, color="0.35")
    return below


def _marker_size(count: int) -> float:
    """Marker size (points) that keeps a few hundred points readable and a few apart visible."""
    return float(np.clip(30.0 / np.sqrt(max(count, 1)), 2.0, 4.5))


def legend_handles(results: list[FitResult], channels: Sequence[str], *, below_floor: bool, directions: bool):
    """The legend: one line style per fit (named by its model spec), the data marker, the channels' colours."""
    names = [label(result) for result in results]
    named = [f"{name} ({k + 1})" if names.count(name) > 1 else name for k, name in enumerate(names)]
    named = [wrapped(name, LEGEND_CHARACTERS) for name in named]
    handles = [
        Line2D([], [], color="0.25", linestyle=FIT_STYLES[k % len(FIT_STYLES)], label=name)
        for k, name in enumerate(named)
    ]
    handles.append(
        Line2D([], [], color="0.25", linestyle="", marker="o", markerfacecolor="none", markersize=4, label="data")
    )
    if below_floor:
        handles.append(
            Line2D([], [], color="0.25", linestyle="", marker="v", markerfacecolor="none", label="data ≤ axis floor")
        )
    if directions:
        handles.append(Line2D([], [], color="0.85", linestyle="-", linewidth=3, label="mirror (+θi), retro (−θi)"))
    if len(channels) > 1:
        shown = min(len(channels), LEGEND_CHANNELS)
        handles += [
            Line2D([], [], color=channel_colour(channels, k), linewidth=4, label=channels[k]) for k in range(shown)
        ]
        if len(channels) > shown:
            handles.append(Line2D([], [], color="none", label=f"… {len(channels)} channels"))
    return handles
