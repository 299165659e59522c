"""Polar plots of a BRDF in the plane of incidence, as BRDF Explorer (Walt Disney Animation Studios, 2012) draws
them: a half disc with the normal up, the viewer's signed zenith θo as the angle (−90° at the left horizon, 90° at
the right, ``θo > 0`` on the mirror side), and the value as the radius on a log scale.

The incidences, in-plane samples and model curves are those of the cartesian slices (``slices.py``).
"""

import os
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import NullFormatter

from ..data.samples import Samples
from ..fitting.single.result import FitResult
from .figures import FIT_STYLES, channel_colour, characters_in, save_figure, wrapped
from .slices import (
    PLANE_TOLERANCE,
    Slice,
    checked_arguments,
    incidence_panels,
    incidence_title,
    legend_handles,
    plane_slices,
    value_range,
)

#: The radius spans at most this ratio (a log radius from the floor at the centre to the top at the rim): enough
#: for a diffuse floor beside a sharp peak, few enough decades that neither shrinks to a dot.
POLAR_RANGE = 1e4
#: ... and at least this ratio, so that a flat panel still has a decade tick or two.
MIN_POLAR_RANGE = 100.0
#: The width (inches) of each half disc.
WEDGE_INCHES = 3.3
#: The colour of the ray that shows where the light comes from.
LIGHT_COLOUR = "#e6a100"


def polar(
    results: FitResult | Sequence[FitResult],
    samples: Samples,
    *,
    incidences=None,
    max_panels: int = 4,
    path: str | os.PathLike | None = None,
) -> Figure:
    """Polar plots of the plane of incidence, one half disc per incidence, as in BRDF Explorer (Disney, 2012).

    The angle is the viewer's signed zenith θo (normal up; ``θo > 0`` on the mirror side, to the right); the radius
    the BRDF in 1/sr on a log scale from a floor at the centre to the top at the rim, each panel its own (a grazing
    peak would otherwise shrink the others to dots; the radial ticks give the values). The floor is half the
    smallest value shown, kept within :data:`MIN_POLAR_RANGE` to :data:`POLAR_RANGE` below the top. Curves below it
    run along the centre; data below it are left out (and counted in the panel). The light is a ray from the rim
    towards the centre at ``−θi``. Points are the samples within :data:`~brdffit.views.slices.PLANE_TOLERANCE`
    degrees of the plane, lines each result's ``predict`` (colour: channel; line style: fit, named in the legend).

    ``results``, ``incidences``, ``max_panels``, ``path`` as in :func:`~brdffit.views.slices.slices`. Returns the
    matplotlib :class:`~matplotlib.figure.Figure`.
    """
    results, samples, path = checked_arguments(results, samples, path)
    panels = incidence_panels(samples, incidences, max_panels)
    cuts = plane_slices(results, samples, panels, "incidence")

    # Laid out by hand: a half disc fills only the middle half of its square axes, which a layout engine would
    # leave as empty space above and below it. Sizes in inches.
    wedge, gap, left, bottom, top_margin, legend_width = WEDGE_INCHES, 0.7, 0.5, 0.45, 1.05, 2.4
    width = left + len(cuts) * wedge + (len(cuts) - 1) * gap + legend_width
    light = Line2D([], [], color=LIGHT_COLOUR, linewidth=1.2, marker=">", markersize=4, label="light (at −θi)")
    handles = [*legend_handles(results, samples.channels, below_floor=False, directions=False), light]
    # The legend hangs from 0.4 in below the top; each of its 8-point lines takes ~0.2 in with the spacing.
    legend_height = 0.5 + 0.2 * sum(handle.get_label().count("\n") + 1 for handle in handles)
    height = max(bottom + wedge / 2 + top_margin, legend_height)
    figure = Figure(figsize=(width, height))
    for index, cut in enumerate(cuts):
        x0 = left + index * (wedge + gap)
        # The square axes box reaches a quarter of its side below and above the half disc it draws.
        box = (x0 / width, (bottom - wedge / 4) / height, wedge / width, wedge / height)
        axis = figure.add_axes(box, projection="polar")
        floor, top = value_range([_within_the_data(cut)])
        top *= 0.6  # value_range leaves a factor 2 above the largest value; a rim just above it is enough here
        _draw_polar(
            axis, cut, results, samples.channels, min(max(floor, top / POLAR_RANGE), top / MIN_POLAR_RANGE), top
        )
    figure.legend(
        handles=handles,
        loc="upper left",
        bbox_to_anchor=((width - legend_width + 0.2) / width, 1 - 0.4 / height),
        fontsize=8,
        frameon=False,
    )
    figure.suptitle(
        wrapped(
            f"{samples.source}: plane of incidence; angle θo (> 0 on the mirror side), radius BRDF (1/sr, log scale)",
            characters_in(width, 10),
        ),
        fontsize=10,
        y=1 - 0.08 / height,
        va="top",
    )
    if path is not None:
        save_figure(figure, path)
    return figure


def _within_the_data(cut: Slice) -> Slice:
    """``cut`` with its curves kept to the data's span of θo (2° beyond each end), for the radius range: a model's
    values past the last sample (a grazing peak no sample saw) must not squash the data into the centre. A cut with
    no data keeps its curves."""
    if cut.data_theta_o.size == 0:
        return cut
    low, high = cut.data_theta_o.min() - 2.0, cut.data_theta_o.max() + 2.0
    seen = (cut.curve_theta_o >= low) & (cut.curve_theta_o <= high)
    return replace(cut, curve_theta_o=cut.curve_theta_o[seen], curves=[curve[seen] for curve in cut.curves])


def _draw_polar(axis, cut: Slice, results: list[FitResult], channels: Sequence[str], floor: float, top: float):
    """One half disc: normal up, θo clockwise from it (so > 0 to the right), log radius from ``floor`` to ``top``."""
    axis.set_theta_zero_location("N")
    axis.set_theta_direction(-1)
    axis.set_thetamin(-90)
    axis.set_thetamax(90)
    axis.set_rscale("log")
    axis.set_rlim(floor, top)
    axis.set_thetagrids(np.arange(-90, 91, 30), [f"{angle}°" for angle in range(-90, 91, 30)], fontsize=8)
    axis.yaxis.set_minor_formatter(NullFormatter())  # decades only: the minor labels would overlap
    axis.tick_params(axis="y", labelsize=7)
    for index in range(len(results)):
        for channel in range(len(channels)):
            # Clipped to the floor: a value below it is drawn at the centre, never on the opposite side.
            axis.plot(
                np.radians(cut.curve_theta_o),
                np.maximum(cut.curves[index][:, channel], floor),
                color=channel_colour(channels, channel),
                linestyle=FIT_STYLES[index % len(FIT_STYLES)],
                linewidth=1.3,
                gid=f"fit:{index}:{channels[channel]}",
            )
    count = cut.data_theta_o.size
    left_out = 0
    for channel in range(len(channels) if count else 0):
        values = cut.data_values[:, channel]
        shown = values > floor
        left_out += int(np.sum(~shown))
        axis.plot(
            np.radians(cut.data_theta_o[shown]),
            values[shown],
            linestyle="",
            marker="o",
            markersize=3,
            markerfacecolor="none",
            markeredgewidth=0.7,
            alpha=0.8,
            color=channel_colour(channels, channel),
            gid=f"data:{channels[channel]}",
            zorder=3,
        )
    light = np.radians(-cut.incidence.theta_i)
    axis.annotate(
        "",
        xy=(light, floor),
        xytext=(light, top),
        arrowprops={"arrowstyle": "->", "color": LIGHT_COLOUR, "linewidth": 1.2, "alpha": 0.8},
        annotation_clip=False,
        zorder=1,  # under the curves and data: a retro-reflective lobe lies along the ray
    )
    if count == 0:
        note = f"no samples within {PLANE_TOLERANCE:g}° of this plane"
    else:
        note = f"{count} sample{'s' if count > 1 else ''}" + (
            f", {left_out} values below {floor:.2g} left out" if left_out else ""
        )
    # In the axes box's fraction: the half disc's top is at 0.75, its θ labels take about 0.25 inch above it.
    axis.set_title(f"{incidence_title(cut.incidence)}\n{note}", fontsize=9, y=0.75 + 0.3 / WEDGE_INCHES)
