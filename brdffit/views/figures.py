"""What every figure shares: how a fit is named, the colour of each channel, and saving a figure safely.

Figures are built on :class:`matplotlib.figure.Figure` directly, never through ``pyplot``: no global state,
no window, nothing left open when a program draws hundreds of them.
"""

import os
from collections.abc import Sequence
from pathlib import Path

from .._files import atomic_path
from ..fitting.results import FitResult
from ..physics.models.specs import spec_of

#: Colours of the first channels (r, g, b look like themselves); further channels take matplotlib's cycle.
CHANNEL_COLOURS = {"r": "#d62728", "g": "#2ca02c", "b": "#1f77b4", "value": "#333333", "y": "#333333"}
#: Line styles that tell several fits apart on one axis (colour already tells the channels apart).
FIT_STYLES = ("-", "--", ":", "-.")


def label(result: FitResult) -> str:
    """A fit named as a model spec: ``ward``, ``lafortune:lobes=2``, ``cook-torrance:fresnel=conductor``."""
    return spec_of(result.model, result.model_options)


def as_list(results: FitResult | Sequence[FitResult]) -> list[FitResult]:
    """One result or several, as a list."""
    return [results] if isinstance(results, FitResult) else list(results)


def channel_colour(channels: Sequence[str], index: int) -> str:
    """The colour of channel ``index`` of ``channels``: red, green, blue for r, g, b, grey for one channel."""
    name = channels[index]
    if name in CHANNEL_COLOURS and not (name == "y" and len(channels) == 3):
        return CHANNEL_COLOURS[name]
    return f"C{index % 10}"


def save_figure(figure, path: str | os.PathLike, dpi: int = 120) -> Path:
    """Write ``figure`` to ``path`` (format from the suffix) atomically: a temporary file renamed into place."""
    path = Path(path)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=dpi, format=path.suffix.lstrip(".").lower() or "png")
    return path
