"""Spectral measurements: value columns named by wavelength, turned into CIE XYZ, linear sRGB or kept as bands.

A samples file whose value columns are named by wavelength in nm (``400, 410, …, 700``; also ``400nm`` or
``400.5``) holds a spectral BRDF f(λ) in 1/sr per band. :func:`spectral_to` turns it into

* ``xyz``: CIE 1931 (or 1964, 2015) tristimulus values of the BRDF (CIE 15:2004, section 7), channels
  ``x, y, z``, normalised so that a spectrally flat BRDF ``f`` has ``Y = f``: a perfect reflecting diffuser
  (reflectance 1, BRDF 1/π in every band) has ``Y = 1/π`` and its albedo ``π·Y`` is 1;
* ``rgb``: linear sRGB (IEC 61966-2-1:1999; no transfer function) of that XYZ, channels ``r, g, b``;
* ``keep``: every band its own channel (the identity).

The conversion is linear, so it is one precomputed weight matrix ``W`` (bands × 3) and ``values @ W`` converts
every sample at once (:func:`conversion_matrix`). The colour-matching functions and illuminants are
colour-science's (``colour.MSDS_CMFS``, ``colour.SDS_ILLUMINANTS``: CIE 15:2004 tables), and ``W`` reproduces
colour-science's ``sd_to_XYZ(sd, cmfs, illuminant, method="Integration") / 100`` of a reflectance spectrum
(its classical integration, Wyszecki & Stiles 1982, on the colour-matching functions' 1 nm grid):

1. the spectrum is interpolated to the 1 nm grid of the colour-matching functions (360–830 nm for the CIE 1931
   observer) the way colour-science aligns a spectral distribution: Sprague (1880) for evenly spaced bands (six
   or more), a cubic spline for unevenly spaced ones (four or more), linear interpolation for fewer bands; outside
   the measured bands the spectrum is held at the first and last band's value (colour-science's constant
   extrapolation, which ASTM E308 also assumes);
2. ``XYZ_c = Σ_λ S(λ) c̄(λ) ρ(λ) / Σ_λ S(λ) ȳ(λ)`` over that grid (Δλ cancels), with the illuminant ``S`` aligned to
   the same grid by colour-science (Sprague within its table, constant beyond).

Each row of ``W`` is the result for a spectrum that is 1 in one band and 0 in the others, so ``W`` agrees with
colour-science's ``Integration`` to rounding (about 1e-15) wherever colour-science can compute it (whole-nm band
centres), and also works for bands colour-science's alignment cannot handle (fractional centres such as 400.5 nm,
or fewer than six evenly spaced bands). colour-science's default method, ASTM E308-15 (tristimulus weighting
factors), differs from it by less than 0.1 % for smooth spectra sampled every 10 nm; ASTM E308 only accepts 1, 5,
10 and 20 nm spacing.

Bands outside the colour-matching functions' range (below 360 or above 830 nm) get no colour-matching weight of
their own (their row of ``W`` is zero unless they shape the interpolated spectrum just inside the range, as they
do in colour-science); at least one band must lie within the range.

colour-science (``colour``) takes about 1.5 s to import, so it is imported on first use, never with this module.
"""

import re
import warnings
from collections.abc import Iterable, Sequence
from contextlib import contextmanager
from dataclasses import replace
from functools import lru_cache

import numpy as np

from .._jax import first_bad
from ..checks import choice
from ..errors import Argument, BrdfInputError, not_allowed
from .samples import Samples

#: What :func:`spectral_to` turns spectral samples into.
SPECTRAL_TARGETS = ("xyz", "rgb", "keep")
DEFAULT_ILLUMINANT = "D65"
DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"
#: Channel names outside this range (nm) are not taken as wavelengths.
WAVELENGTH_RANGE_NM = (200.0, 2500.0)
#: The output channels of each conversion.
TARGET_CHANNELS = {"xyz": ("x", "y", "z"), "rgb": ("r", "g", "b")}

_WAVELENGTH_NAME = re.compile(r"\s*(\d+(?:\.\d*)?|\.\d+)\s*(?:nm)?\s*", re.IGNORECASE)
#: How many valid choices an unknown-name message lists.
_SHOWN_CHOICES = 10
#: colour-science's interpolators need this many points: Sprague six, the cubic spline four.
_SPRAGUE_POINTS = 6
_SPLINE_POINTS = 4


# ------------------------------------------------------------------ channel names
def wavelengths(channels: Sequence[str]) -> np.ndarray | None:
    """The wavelengths in nm (float64) if every channel name is one, else None.

    A name is a wavelength if it is a plain positive decimal number, optionally followed by ``nm``
    (``"400"``, ``"400.5"``, ``"400nm"``, ``"400 nm"``), within :data:`WAVELENGTH_RANGE_NM`. The wavelengths must
    be strictly increasing, and there must be at least two.
    """
    names = tuple(channels)
    if len(names) < 2:
        return None
    found = []
    for name in names:
        match = _WAVELENGTH_NAME.fullmatch(str(name))
        if match is None:
            return None
        found.append(float(match.group(1)))
    result = np.array(found, dtype=np.float64)
    low, high = WAVELENGTH_RANGE_NM
    if np.any(result < low) or np.any(result > high) or np.any(np.diff(result) <= 0):
        return None
    return result


# ------------------------------------------------------------------ the weight matrix
def conversion_matrix(
    wavelengths: Sequence[float] | np.ndarray,
    target: str,
    illuminant: str = DEFAULT_ILLUMINANT,
    observer: str = DEFAULT_OBSERVER,
) -> tuple[np.ndarray, tuple[str, ...]]:
    """The weights ``W`` (bands × outputs, float64) and output channel names for converting spectral values.

    ``values @ W`` turns values (N, bands), one column per wavelength (nm, strictly increasing), into ``target``:

    * ``"xyz"``: CIE XYZ (``x, y, z``) under ``illuminant`` (a key of ``colour.SDS_ILLUMINANTS``: ``D65``, ``A``,
      ``D50``, …; CIE 15:2004) for ``observer`` (a key of colour-science's standard-observer colour-matching
      functions: ``CIE 1931 2 Degree Standard Observer``, ``CIE 1964 10 Degree Standard Observer``, …), normalised
      so that a flat spectrum ``f`` has ``Y = f``; it equals colour-science's
      ``sd_to_XYZ(sd, cmfs, illuminant, method="Integration") / 100`` (see the module docstring). XYZ keeps the
      units of the values (1/sr for a BRDF).
    * ``"rgb"``: linear sRGB (``r, g, b``; IEC 61966-2-1), ``W_xyz @ M.T`` with colour-science's
      ``RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB``, no chromatic adaptation: white under D65 is (1, 1, 1), white
      under another illuminant is that illuminant's colour. Saturated spectra give negative components.
    * ``"keep"``: the identity, one channel per band (named like ``400`` or ``400.5``); ``illuminant`` and
      ``observer`` are not used.

    Unknown targets, illuminants or observers, and bands that miss the colour-matching functions' range entirely,
    raise :class:`~brdffit.errors.BrdfInputError`.
    """
    _check_target(target)
    bands = _check_wavelengths(wavelengths)
    if target == "keep":
        return np.eye(bands.size), tuple(format(w, "g") for w in bands)
    return _weights(bands, target, illuminant, observer, ""), TARGET_CHANNELS[target]


def spectral_to(
    samples: Samples,
    target: str,
    illuminant: str = DEFAULT_ILLUMINANT,
    observer: str = DEFAULT_OBSERVER,
) -> Samples:
    """``samples`` whose channels are wavelengths (nm) converted to ``target`` (see :func:`conversion_matrix`).

    Values become ``values @ W``. A sigma becomes ``sqrt(sigma² @ W²)``: the uncertainty of a linear combination of
    bands whose errors are independent (uncorrelated between bands; correlated errors, such as a common
    calibration scale, would add covariance terms this ignores). Weights and directions are unchanged.

    ``"keep"`` returns ``samples`` as they are (spectral or not). Other targets need wavelength channels, and
    refuse results with a negative value (the fitter allows no negative reflectance): linear sRGB of a saturated
    spectrum, outside the sRGB gamut, is negative, and the message suggests ``--spectral-to xyz`` or ``keep``.
    """
    _check_target(target)
    if target == "keep":
        return samples
    bands = wavelengths(samples.channels)
    if bands is None:
        raise BrdfInputError(
            f"{samples.source}: ",
            Argument("spectral_to", target),
            f" needs value columns named by wavelength in nm; got {', '.join(samples.channels)}",
        )
    weights = _weights(bands, target, illuminant, observer, f"{samples.source}: ")
    names = TARGET_CHANNELS[target]
    values = np.asarray(samples.values, dtype=np.float64) @ weights
    negative = first_bad(values < 0)
    if negative is not None:
        row, column = negative
        if target == "rgb":
            what = (
                f"linear sRGB {names[column]} = {values[row, column]:.4g} < 0 (the spectrum is outside the sRGB gamut)"
            )
            instead: list[str | Argument] = [
                "use ",
                Argument("spectral_to", "xyz"),
                " or ",
                Argument("spectral_to", "keep"),
            ]
        else:
            what = (
                f"CIE {names[column].upper()} = {values[row, column]:.4g} < 0 (the interpolated spectrum dips below 0)"
            )
            instead = ["use ", Argument("spectral_to", "keep")]
        raise BrdfInputError(
            f"{samples.source}: sample {row + 1}: {what}, and negative reflectance is not allowed; ", *instead
        )
    sigma = None
    if samples.sigma is not None:
        sigma = np.sqrt(np.asarray(samples.sigma, dtype=np.float64) ** 2 @ weights**2)
    return replace(samples, values=values, channels=names, sigma=sigma)


# ------------------------------------------------------------------ checks
def _check_target(target: str) -> None:
    choice("spectral_to", target, SPECTRAL_TARGETS, verb="is not known")


def _check_wavelengths(values) -> np.ndarray:
    try:
        bands = np.asarray(values, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise BrdfInputError(f"wavelengths {values!r} are not numbers (nm)") from None
    if bands.size < 2 or not np.all(np.isfinite(bands)) or np.any(bands <= 0) or np.any(np.diff(bands) <= 0):
        raise BrdfInputError(
            f"wavelengths {', '.join(format(w, 'g') for w in bands) or '(none)'} are not allowed;"
            " give two or more positive, strictly increasing wavelengths in nm"
        )
    return bands


def _choices(names: Iterable[str]) -> str:
    listed = list(names)
    shown = ", ".join(listed[:_SHOWN_CHOICES])
    return shown if len(listed) <= _SHOWN_CHOICES else f"{shown}, … ({len(listed)} in all)"


# ------------------------------------------------------------------ colour-science
def _colour():
    """colour-science, imported on first use (about 1.5 s)."""
    try:
        import colour
    except ImportError:  # pragma: no cover - colour-science is installed where the tests run
        raise BrdfInputError(
            Argument("spectral_to"), " xyz and rgb need colour-science; install it (pip install colour-science)"
        ) from None
    return colour


@contextmanager
def _quiet_alignment():
    """Silence colour-science's ``ColourRuntimeWarning`` inside the block; other warnings pass through.

    colour-science warns (``ColourRuntimeWarning``) whenever it aligns an illuminant or a spectrum to another
    spectral shape ("Aligning … shape", "… is not uniform, using minimum interval"): here that alignment is the
    intended interpolation, so the warning says nothing.
    """
    from colour.utilities import ColourRuntimeWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ColourRuntimeWarning)
        yield


def _observer(colour, observer: str):
    from colour.colorimetry import MSDS_CMFS_STANDARD_OBSERVER

    if not isinstance(observer, str) or observer not in MSDS_CMFS_STANDARD_OBSERVER:
        choices = _choices(MSDS_CMFS_STANDARD_OBSERVER.keys())
        raise not_allowed("observer", observer, f"choose one of: {choices}", verb="is not known")
    return MSDS_CMFS_STANDARD_OBSERVER[observer]


def _illuminant(colour, illuminant: str):
    if not isinstance(illuminant, str) or illuminant not in colour.SDS_ILLUMINANTS:
        choices = _choices(colour.SDS_ILLUMINANTS.keys())
        raise not_allowed("illuminant", illuminant, f"choose one of: {choices}", verb="is not known")
    return colour.SDS_ILLUMINANTS[illuminant]


def _weights(bands: np.ndarray, target: str, illuminant: str, observer: str, where: str) -> np.ndarray:
    """``W`` for ``xyz`` or ``rgb`` (a fresh copy); ``where`` prefixes the band-range message (a source)."""
    colour = _colour()
    cmfs = _observer(colour, observer)
    _illuminant(colour, illuminant)
    low, high = float(cmfs.wavelengths[0]), float(cmfs.wavelengths[-1])
    if not np.any((bands >= low) & (bands <= high)):
        raise BrdfInputError(
            f"{where}bands {bands[0]:g}–{bands[-1]:g} nm miss the {observer} colour-matching functions"
            f" ({low:g}–{high:g} nm); use ",
            Argument("spectral_to", "keep"),
        )
    weights = _xyz_weights(tuple(bands.tolist()), illuminant, observer)
    if target == "rgb":
        weights = weights @ np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB, dtype=np.float64).T
    return np.array(weights, dtype=np.float64)


@lru_cache(maxsize=32)
def _xyz_weights(bands: tuple[float, ...], illuminant: str, observer: str) -> np.ndarray:
    """``W`` (bands × 3) for CIE XYZ, read-only; names already checked by :func:`_weights`."""
    colour = _colour()
    cmfs = _observer(colour, observer)
    grid = np.asarray(cmfs.wavelengths, dtype=np.float64)
    with _quiet_alignment():
        source = _illuminant(colour, illuminant).copy().align(cmfs.shape)
        power = np.asarray(source.values, dtype=np.float64)
        spectrum = _interpolation_matrix(colour, np.asarray(bands), grid)
    weighted = power[:, None] * np.asarray(cmfs.values, dtype=np.float64)
    weights = spectrum.T @ weighted / np.sum(weighted[:, 1])
    weights.setflags(write=False)
    return weights


def _interpolation_matrix(colour, bands: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """``M`` (grid × bands): the spectrum on ``grid`` is ``M @ band values``, interpolated as colour-science aligns.

    colour-science's ``SpectralDistribution.align`` interpolates with Sprague for uniform spacing and a cubic
    spline otherwise, then extrapolates a constant; both interpolators are linear in the values, so interpolating
    the unit spectra (the identity's columns) gives ``M``. Sprague needs six bands and the spline four; with fewer,
    linear interpolation.
    """
    count = bands.size
    uniform = colour.utilities.is_uniform(bands)
    if uniform and count >= _SPRAGUE_POINTS:
        interpolator = colour.SpragueInterpolator
    elif not uniform and count >= _SPLINE_POINTS:
        interpolator = colour.CubicSplineInterpolator
    else:
        interpolator = colour.LinearInterpolator
    basis = colour.MultiSpectralDistributions(
        np.eye(count), bands, labels=[f"band {k}" for k in range(count)], interpolator=interpolator
    )
    matrix = np.zeros((grid.size, count))
    inside = (grid >= bands[0]) & (grid <= bands[-1])
    if np.any(inside):
        matrix[inside] = np.asarray(basis[grid[inside]], dtype=np.float64).reshape(-1, count)
    matrix[grid < bands[0], 0] = 1.0
    matrix[grid > bands[-1], -1] = 1.0
    return matrix
