"""How far an export lies from the measurement itself, at the measurement's own directions, evaluated as the renderer
evaluates it.

An approximation's grid error (``approximate.py``) says how far the renderer's model lies from the *fit*, over a
grid of the fit's choosing. What a user is hurt by is how far the renderer, given the exported file, lies from the
*data*: a fit's own error, an approximation's, and anything the renderer does differently (Mitsuba's Beckmann
``G1``, a refit into its range, a table's bins) all add up there. So, given the data, each export is evaluated at
the data's direction pairs by its consumer, or by the nearest thing to it brdffit has:

* Mitsuba 3: Mitsuba itself (``scalar_rgb``), loading the exported BSDF, where it is installed; else brdffit's
  model of the exported BSDF;
* glTF: the glTF metallic-roughness BRDF of the Khronos specification's appendix (``gltf_material.py``);
* MERL: the written table, read back and interpolated as brdffit reads MERL data (``datadriven/tabulation.py``).

Compared over every (pair, channel) whose data value is at least :data:`DARK` (where none is, every positive one):
the median and 90th percentile of ``|export − data| / data``, the median of ``export / data`` (1 when the export is as
bright as the data: 0.4 means it renders 0.4 times as bright); and over all of them, the rms of ``export − data`` as
a fraction of the data's rms. The fit's own median error and rms, on the same values, stand beside them: what the
export adds is the difference.
"""

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..data.load import errors_name_the_reading, load_samples
from ..data.samples import Samples
from ..errors import BrdfInputError
from ..fitting.objective.losses import RELATIVE_FLOOR
from ..fitting.single.result import FitResult

#: Data with more direction pairs than this are compared on a random subset of this many (seed
#: :data:`SUBSET_SEED`): the medians move by less than 0.3% of themselves (their standard error at 200,000 values is
#: ``1.25 σ/sqrt(n)``), and Mitsuba evaluates pair by pair (3 µs each).
MAX_PAIRS = 200_000
SUBSET_SEED = 0
#: Data values below this (1/sr) are left out of the relative errors: the relative loss's floor
#: (``fitting/objective/losses.RELATIVE_FLOOR``), below which a relative error says nothing a renderer shows. A
#: narrow Beckmann lobe's tails fall to 10⁻²⁰ and below (Mitsuba's copper at alpha 0.15: 56% of the values under
#: 10⁻⁶), where a fit's diffuse albedo of 10⁻⁴, well within the noise of the lobe, is many times the data: a median
#: error of 82% for a fit 0.9% off where the data are above the floor.
DARK = RELATIVE_FLOOR


@dataclass(frozen=True)
class DataError:
    """How far an export lies from the data at the data's directions (module docstring): ``median_error`` and
    ``p90_error`` of ``|export − data|/data``, ``brightness`` (the median ``export/data``), over ``n_values`` (pair,
    channel) values of ``n_pairs`` pairs of the data ``source`` (those at least :data:`DARK`), and ``relative_rmse``
    (rms of ``export − data`` over the data's rms, over all of them; ``n_dark`` values below :data:`DARK` left out of
    the rest); ``evaluated_by`` names what evaluated the export; ``fit_median_error`` and ``fit_relative_rmse``: the
    same of the fit itself."""

    source: str
    n_pairs: int
    n_values: int
    median_error: float
    p90_error: float
    brightness: float
    relative_rmse: float
    evaluated_by: str
    fit_median_error: float
    fit_relative_rmse: float
    n_dark: int = 0

    def to_dict(self) -> dict:
        return {
            "source": self.source,
            "n_pairs": self.n_pairs,
            "n_values": self.n_values,
            "median_error": self.median_error,
            "p90_error": self.p90_error,
            "brightness": self.brightness,
            "relative_rmse": self.relative_rmse,
            "evaluated_by": self.evaluated_by,
            "fit_median_error": self.fit_median_error,
            "fit_relative_rmse": self.fit_relative_rmse,
            "n_dark": self.n_dark,
        }

    def line(self) -> str:
        """One line a person reads: ``at the data's 10,368 directions (oak.csv), evaluated by Mitsuba 3.9.1: median
        error 1.20% (90th percentile 3.40%), export/data 1.002 (median), rmse 3.1% of the data's rms; the fit itself:
        median error 0.95%, rmse 2.9%``."""
        return (
            f"at the data's {self.n_pairs:,} directions ({Path(self.source).name}), evaluated by {self.evaluated_by}:"
            f" median error {self.median_error:.2%} (90th percentile {self.p90_error:.2%}{self._dark_text()}),"
            f" export/data {self.brightness:.3f} (median), rmse {self.relative_rmse:.1%} of the data's rms;"
            f" the fit itself: median error {self.fit_median_error:.2%}, rmse {self.fit_relative_rmse:.1%}"
        )

    def _dark_text(self) -> str:
        if not self.n_dark:
            return ""
        return f"; {self.n_dark:,} of {self.n_dark + self.n_values:,} values below {DARK:g} 1/sr left out"


def data_for(result: FitResult, samples: "Samples | str | os.PathLike", subset: bool = True) -> Samples:
    """The data an export of ``result`` is compared with: ``samples`` (a :class:`~brdffit.Samples`, or a file read
    as the fit read it: its ``quantity`` and its ``reading``, the angles' unit, a spectral conversion…), limited to the
    fit's ``max_theta``, with the result's channels (a one-line error otherwise); with ``subset``, at most
    :data:`MAX_PAIRS` pairs (a seeded random subset)."""
    if not isinstance(samples, Samples):
        with errors_name_the_reading(samples, result.reading, "the fit read its samples (the result's"):
            samples = load_samples(samples, quantity=result.quantity, **result.reading)
    samples = samples.within(result.max_theta)
    if tuple(samples.channels) != tuple(result.channels):
        raise BrdfInputError(
            f"{samples.source}: channels {', '.join(samples.channels)} are not the result's"
            f" ({', '.join(result.channels)}); give the data the fit was made from"
        )
    if not np.any(samples.values > 0):
        raise BrdfInputError(f"{samples.source}: no positive value to compare an export with")
    if subset and len(samples.values) > MAX_PAIRS:
        keep = np.sort(np.random.default_rng(SUBSET_SEED).choice(len(samples.values), MAX_PAIRS, replace=False))
        samples = samples.select(keep)
    return samples


def data_error(
    result: FitResult, samples: Samples, brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], evaluated_by: str
) -> DataError:
    """How far ``brdf(wi, wo) -> (N, C)`` (the export of ``result`` as ``evaluated_by`` evaluates it) lies from
    ``samples`` (:func:`data_for`'s), beside how far ``result`` itself does."""
    data = np.asarray(samples.values, dtype=float)
    positive = data >= DARK
    if not np.any(positive):
        positive = data > 0  # data_for's data have some
    rms = float(np.sqrt(np.mean(data**2)))

    def compared(values):
        values = np.asarray(values, dtype=float)[:, : data.shape[1]]
        ratio = values[positive] / data[positive]
        return ratio, float(np.sqrt(np.mean((values - data) ** 2))) / rms

    ratio, relative_rmse = compared(brdf(samples.wi, samples.wo))
    fit_ratio, fit_relative_rmse = compared(result.predict(samples.wi, samples.wo))
    error = np.abs(ratio - 1.0)
    return DataError(
        source=str(samples.source),
        n_pairs=len(data),
        n_values=int(positive.sum()),
        n_dark=int(positive.size - positive.sum()),
        median_error=float(np.median(error)),
        p90_error=float(np.percentile(error, 90)),
        brightness=float(np.median(ratio)),
        relative_rmse=relative_rmse,
        evaluated_by=evaluated_by,
        fit_median_error=float(np.median(np.abs(fit_ratio - 1.0))),
        fit_relative_rmse=fit_relative_rmse,
    )
