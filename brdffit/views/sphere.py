"""The lit-sphere figure: each fit rendered on a sphere, beside the measured material where the data are dense.

As in Ngan, Durand and Matusik, "Experimental analysis of BRDF models" (EGSR 2005): a sphere under a point light
(and under a few lights, ``environment``) shows what a fit looks like, highlight, colour and falloff towards the
silhouette, in one glance; next to the sphere rendered from the measured values (nearest sample,
:func:`~brdffit.views.render.render_measured`) it shows where the fit departs from the material. The renderer is
``render.py``; this module lays the images out.
"""

import os
import textwrap
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from ..checks import choice, whole_number
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from .figures import as_list, characters_in, check_figure_path, checked_samples, label, save_figure, wrapped
from .render import (
    LIGHTS,
    MAX_DISTANCE_DEGREES,
    MeasuredSphere,
    display_rgb,
    exposure_for,
    render_measured,
    render_sphere,
    sphere_normals,
    to_srgb,
)

#: The ``lights`` a figure takes: one of the presets of :data:`~brdffit.views.render.LIGHTS`, or both as two rows.
LIGHTINGS = (*LIGHTS, "both")
#: The measured sphere is shown when at least this share of the lit disc has a sample near enough: "dense" data
#: (a MERL table covers all of it; a 10k-sample gonioreflectometer set a small part).
DENSE_FRACTION = 0.9
#: Inches per sphere panel.
PANEL_INCHES = 2.6
#: The two greys of the stripes that mark lit pixels without measured data (sRGB-encoded display values).
NO_DATA_GREYS = (0.55, 0.7)
#: The stripes' period, in pixels along each image axis.
STRIPE_PIXELS = 8
#: What the rows are called.
_ROW_LABELS = {"point": "point light", "environment": "environment (4 lights)"}


def sphere(
    results: FitResult | Sequence[FitResult],
    samples: Samples | None = None,
    *,
    size: int = 256,
    lights: str = "point",
    path: str | os.PathLike | None = None,
) -> Figure:
    """Lit spheres of one fit or several, side by side, and of the measured values when ``samples`` are dense.

    One row per lighting (``lights``: ``point``, ``environment`` or ``both``; presets of
    :data:`~brdffit.views.render.LIGHTS`), one ``size × size`` panel per fit, titled with its model spec
    (:func:`~brdffit.views.figures.label`), then a ``measured`` panel when ``samples`` are given and cover at least
    :data:`DENSE_FRACTION` of the lit disc (otherwise the figure's title says how much they cover). All panels of
    a row share one exposure (:func:`~brdffit.views.render.exposure_for` over the fitted spheres), so they
    compare; lit pixels without a measured value are striped grey. ``path``: also save it (PNG, PDF, SVG by
    suffix; :func:`~brdffit.views.figures.save_figure`). Returns the :class:`matplotlib.figure.Figure`.
    """
    results = as_list(results)
    if not results or not all(isinstance(result, FitResult) for result in results):
        raise BrdfInputError(Argument("results"), " must be a FitResult or a non-empty sequence of them")
    samples = None if samples is None else checked_samples(samples, results)
    choice("lights", lights, LIGHTINGS)
    size = whole_number("size", size, minimum=16, maximum=2048)
    path = None if path is None else check_figure_path(path)  # before the work
    lightings = tuple(LIGHTS) if lights == "both" else (lights,)
    inside, _ = sphere_normals(size)

    rows, notes, sparse = [], [], {}
    for lighting in lightings:
        fitted = []
        for result in results:
            radiance = render_sphere(
                result.model,
                result.params,
                size=size,
                lights=lighting,
                channels=result.channels,
                **result.model_options,
            )
            rgb, note = display_rgb(radiance, result.channels)
            fitted.append((label(result), rgb))
            if note:
                notes.append(f"{label(result)}: {note}")
        measured = None
        if samples is not None:
            found = render_measured(samples, size=size, lights=lighting)
            rgb, note = display_rgb(found.radiance, samples.channels)
            if found.data_fraction < DENSE_FRACTION:
                sparse[lighting] = found.data_fraction
            else:
                measured = (found, rgb)
                if note:
                    notes.append(f"measured: {note}")
        rows.append((lighting, fitted, measured))
    if sparse:
        covered = ", ".join(f"{fraction:.0%} ({lighting})" for lighting, fraction in sparse.items())
        notes.append(
            f"measured sphere not shown: a sample lies within {MAX_DISTANCE_DEGREES:g}° for {covered} of the lit"
            f" disc, under the {DENSE_FRACTION:.0%} it needs"
        )

    n_columns = max(len(fitted) + (measured is not None) for _, fitted, measured in rows)
    figure = Figure(figsize=(PANEL_INCHES * n_columns + 0.4, PANEL_INCHES * len(rows) + 0.5), layout="constrained")
    axes = figure.subplots(len(rows), n_columns, squeeze=False)
    for row, (lighting, fitted, measured) in enumerate(rows):
        exposure = exposure_for([rgb for _, rgb in fitted])
        panels = [(title, disc_image(rgb, exposure, inside)) for title, rgb in fitted]
        if measured is not None:
            found, rgb = measured
            panels.append((f"measured ({found.data_fraction:.0%} of lit disc)", measured_image(found, rgb, exposure)))
        for column, axis in enumerate(axes[row]):
            axis.set_axis_off()
            if column < len(panels):
                title, image = panels[column]
                axis.imshow(image, interpolation="nearest")
                axis.set_title(wrapped(title, characters_in(PANEL_INCHES, 9)), fontsize=9)
        axes[row][0].text(
            -0.04, 0.5, _ROW_LABELS[lighting], transform=axes[row][0].transAxes, rotation=90, ha="right", va="center"
        )
    if notes:
        width = characters_in(PANEL_INCHES * n_columns, 8)
        figure.suptitle(textwrap.fill("; ".join(dict.fromkeys(notes)), width), fontsize=8)
    if path is not None:
        save_figure(figure, path)
    return figure


def disc_image(linear_rgb: np.ndarray, exposure: float, inside: np.ndarray) -> np.ndarray:
    """RGBA (size, size, 4): the tone-mapped sphere, transparent outside the disc."""
    return np.concatenate([to_srgb(linear_rgb, exposure), inside[..., None].astype(float)], axis=-1)


def measured_image(measured: MeasuredSphere, linear_rgb: np.ndarray, exposure: float) -> np.ndarray:
    """:func:`disc_image` of the measured sphere, with lit pixels that have no data striped in two greys."""
    inside, _ = sphere_normals(linear_rgb.shape[0])
    image = disc_image(linear_rgb, exposure, inside)
    rows, columns = np.indices(inside.shape)
    stripes = np.where((rows + columns) // (STRIPE_PIXELS // 2) % 2 == 0, *NO_DATA_GREYS)
    no_data = measured.lit & ~measured.has_data
    image[no_data, :3] = stripes[no_data, None]
    return image
