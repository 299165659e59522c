"""What every figure shares: how a fit is named, the colour of each channel, and saving a figure safely.

Figures are built on :class:`matplotlib.figure.Figure` directly, never through ``pyplot``: no global state,
no window, nothing left open when a program draws hundreds of them.
"""

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._files import atomic_path
from ..data.load import as_samples
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from ..physics.models.specs import spec_of

#: File types figures are written as (matplotlib chooses the format by suffix).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")

#: Colours of the first channels (r, g, b look like themselves); further channels take matplotlib's cycle.
CHANNEL_COLOURS = {"r": "#d62728", "g": "#2ca02c", "b": "#1f77b4", "value": "#333333", "y": "#333333"}
#: Line styles that tell several fits apart on one axis (colour already tells the channels apart): solid, dashed,
#: dotted, dash-dot, long dashes, dash-dot-dot, loose dots; more fits than these repeat them.
FIT_STYLES = ("-", "--", ":", "-.", (0, (8, 3)), (0, (5, 2, 1, 2, 1, 2)), (0, (1, 4)))


def label(result: FitResult) -> str:
    """A fit named as a model spec: ``ward``, ``lafortune:lobes=2``, ``cook-torrance:fresnel=conductor``."""
    return spec_of(result.model, result.model_options)


#: The fits a comparison contributes to a figure: its best and those within one standard error, at most this many.
FROM_A_COMPARISON = 4


def as_list(results) -> list[FitResult]:
    """One result, several, or a :class:`~brdffit.Comparison` (its best fits: ``Comparison.best_results``), as a
    list."""
    from ..fitting.comparison.compare import Comparison

    if isinstance(results, Comparison):
        return results.best_results(FROM_A_COMPARISON)
    return [results] if isinstance(results, FitResult) else list(results)


def channel_colour(channels: Sequence[str], index: int) -> str:
    """The colour of channel ``index`` of ``channels``: red, green, blue for r, g, b, grey for one channel."""
    name = channels[index]
    if name in CHANNEL_COLOURS and not (name == "y" and len(channels) == 3):
        return CHANNEL_COLOURS[name]
    return f"C{index % 10}"


def check_figure_path(path, argument: str = "path") -> Path:
    """``path`` if matplotlib can write its suffix and its folder exists; ``argument`` names it in errors."""
    path = Path(path)
    where = Argument(argument, str(path))
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise BrdfInputError(where, f": the file must end in {', '.join(FIGURE_SUFFIXES)}")
    if not path.parent.is_dir():
        raise BrdfInputError(where, f": folder {path.parent} does not exist")
    return path


def checked_samples(samples) -> Samples:
    """``samples`` if it is a :class:`Samples` (a path is read with :func:`brdffit.load_samples`'s defaults), else a
    one-line error naming the argument."""
    samples = as_samples(samples)
    if not isinstance(samples, Samples):
        kind = f"an empty {type(samples).__name__}" if isinstance(samples, Sequence) and not samples else None
        raise BrdfInputError(
            Argument("samples"), f" must be Samples (from brdffit.load_samples), got {kind or type(samples).__name__}"
        )
    return samples


def evenly_spread(count: int, wanted: int) -> np.ndarray:
    """Indices of ``wanted`` items (all if fewer) spread evenly over ``count``, the first and last included."""
    return np.unique(np.round(np.linspace(0, count - 1, min(wanted, count))).astype(int))


def save_figure(figure, path: str | os.PathLike, dpi: int = 120, **options) -> Path:
    """Write ``figure`` to ``path`` (format from the suffix) atomically: a temporary file renamed into place.
    ``options`` go to matplotlib's ``savefig`` (``bbox_inches="tight"``)."""
    path = Path(path)
    text_as_typed(figure)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=dpi, format=path.suffix.lstrip(".").lower() or "png", **options)
    return path


def text_as_typed(figure) -> None:
    """Every text brdffit put on ``figure`` (titles, labels, legends: channel names, file names, model specs) shown as
    typed: brdffit writes no math, and a ``$`` in a channel name would start matplotlib's math text, which fails on it
    or mangles it. Tick labels, which matplotlib writes as math on log axes, are left alone."""
    from matplotlib.axis import Axis, Tick
    from matplotlib.text import Text

    tick_texts = {id(tick_label) for tick in figure.findobj(Tick) for tick_label in (tick.label1, tick.label2)}
    tick_texts |= {id(axis.offsetText) for axis in figure.findobj(Axis)}
    for text in figure.findobj(Text):
        if id(text) not in tick_texts:
            text.set_parse_math(False)
