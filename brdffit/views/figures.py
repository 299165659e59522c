"""What every figure shares: how a fit is named, the colour of each channel, and saving a figure safely.

Figures are built on :class:`matplotlib.figure.Figure` directly, never through ``pyplot``: no global state,
no window, nothing left open when a program draws hundreds of them.
"""

import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._files import atomic_path
from ..data.load import agreed_reading, as_samples
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError, InputWarning, warn
from ..fitting.single.result import FitResult
from ..physics.models.specs import spec_of

if TYPE_CHECKING:
    from matplotlib.typing import LineStyleType

#: File types figures are written as (matplotlib chooses the format by suffix).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")

#: Colours of the first channels (r, g, b look like themselves); further channels take matplotlib's cycle.
CHANNEL_COLOURS = {"r": "#d62728", "g": "#2ca02c", "b": "#1f77b4", "value": "#333333", "y": "#333333"}
#: Line styles that tell several fits apart on one axis (colour already tells the channels apart): solid, dashed,
#: dotted, dash-dot, long dashes, dash-dot-dot, loose dots; more fits than these repeat them.
FIT_STYLES: "tuple[LineStyleType, ...]" = ("-", "--", ":", "-.", (0, (8, 3)), (0, (5, 2, 1, 2, 1, 2)), (0, (1, 4)))


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


#: How many characters of 8-point text fit in an inch of figure (DejaVu Sans, matplotlib's default, averages ~0.53 em
#: a character); text of another size fits in proportion (:func:`characters_in`).
CHARACTERS_PER_INCH_AT_8_POINTS = 17
#: Where a line of a label or title may break: after a spec's ``:`` and ``,``, a ``;`` or a space.
_BREAK_AFTER = re.compile(r"[^,:; ]*[,:; ]|[^,:; ]+")


def characters_in(inches: float, points: float = 8) -> int:
    """How many characters of ``points``-point text fit in ``inches`` (at least 8)."""
    return max(8, int(inches * CHARACTERS_PER_INCH_AT_8_POINTS * 8 / points))


def wrapped(text: str, width: int) -> str:
    """``text`` (a model spec, a title) over lines of at most ``width`` characters, each line broken after a spec's
    ``:`` or ``,`` (``cook-torrance:`` / ``distribution=ggx,`` / …), a ``;`` or a space; a part longer than a line
    is cut where the line ends. Long specs otherwise run into their neighbours' titles or off the figure."""
    lines = [""]
    for part in _BREAK_AFTER.findall(text):  # a line may end in its break character beyond the width
        if lines[-1] and len(lines[-1]) + len(part.rstrip(",:; ")) > width:
            lines.append("")
        lines[-1] += part
        while len(lines[-1].rstrip(",:; ")) > width:
            lines[-1], rest = lines[-1][:width], lines[-1][width:]
            lines.append(rest)
    return "\n".join(line.rstrip() for line in lines if line.strip())


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


def checked_samples(samples, results: Sequence[FitResult] = ()) -> Samples:
    """``samples`` if it is a :class:`Samples`, else a one-line error naming the argument. A path is read with
    :func:`brdffit.load_samples`'s defaults, but as ``results``' samples were read where they agree: their
    ``quantity`` (when they record one) and each option of ``fit.reading`` (radians, a spectral conversion, ...;
    :func:`~brdffit.data.load.agreed_reading`).
    Warns (:class:`~brdffit.InputWarning`) about a result fitted to values read as another quantity than these
    samples' (``brdf`` and ``cosine-weighted-out`` values of one file are different BRDFs): the figure would compare
    them without a word."""
    if isinstance(samples, str | os.PathLike):
        quantities = {result.quantity for result in results if result.quantity is not None}
        samples = as_samples(
            samples,
            **({"quantity": quantities.pop()} if len(quantities) == 1 else {}),
            **agreed_reading(result.reading for result in results),
        )
    if not isinstance(samples, Samples):
        kind = f"an empty {type(samples).__name__}" if isinstance(samples, Sequence) and not samples else None
        raise BrdfInputError(
            Argument("samples"), f" must be Samples (from brdffit.load_samples), got {kind or type(samples).__name__}"
        )
    read_as = samples.provenance.quantity if samples.provenance else None  # None: made from arrays, as a fit records
    for result in results:
        if None not in (result.quantity, read_as) and result.quantity != read_as:
            warn(
                InputWarning(
                    f"{label(result)} was fitted to samples read as {result.quantity}; {samples.source} is read as"
                    f" {read_as}: the figure compares BRDFs made from different quantities"
                )
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
