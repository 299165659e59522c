"""The measurement formats brdffit reads and writes, and :func:`load_samples`: the one place that knows them all.

=========  ==============================  =====================================================
format     files                           module
=========  ==============================  =====================================================
csv        ``.csv`` (brdffit's own)        ``csv.py``
merl       ``.binary``                     ``merl.py`` (Matusik et al. 2003)
alta       ``.dat`` (``#PARAM_IN``)        ``alta.py`` (ALTA, Belcour et al.)
astm       ``.astm``, ``.txt``             ``astm.py`` (ASTM E1392, Cornell's measurements)
=========  ==============================  =====================================================

:data:`FORMATS` holds each format's reader, its writer (MERL tables are written from a fitted model,
``brdffit/export``) and its file suffixes. The format comes from ``format`` or, by default, from the
file: its suffix, then its first lines (``#`` headers are ALTA's, ``NUM_POINTS`` or ``VARS`` lines
ASTM's). After reading, the values are turned into BRDF values (``quantities.py``) and spectral
channels, if asked, into XYZ or linear sRGB (``spectral.py``).
"""

import inspect
import os
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..checks import choice
from ..errors import Argument, BrdfInputError, InputWarning, warn
from . import spectral
from .alta import read_alta, write_alta
from .astm import read_astm, write_astm
from .csv import ANGLE_UNITS, read_csv, read_data_frame, write_csv
from .merl import read_merl
from .quantities import canonical, to_brdf
from .samples import Samples
from .spectral import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, SPECTRAL_TARGETS

if TYPE_CHECKING:
    import pandas


@dataclass(frozen=True)
class Format:
    """A measurement format: ``read(path, **options)``, ``write(samples, path)`` (None: not written from
    samples) and its file suffixes, the first of which names it when reading."""

    description: str
    suffixes: tuple[str, ...]
    read: Callable[..., Samples]
    write: Callable[[Samples, str | os.PathLike], None] | None


#: The formats by name.
FORMATS = {
    "csv": Format("brdffit's samples table", (".csv",), read_csv, write_csv),
    "merl": Format("MERL BRDF table (Matusik et al. 2003)", (".binary",), read_merl, None),
    "alta": Format("ALTA text data", (".dat",), read_alta, write_alta),
    "astm": Format("ASTM E1392 scatter data (Cornell)", (".astm", ".txt"), read_astm, write_astm),
}


def detect_format(path: Path, format: str | None = None) -> str:
    """``format`` when given (checked), else the format of ``path`` from its suffix and first lines."""
    if format is not None:
        return choice("format", format, FORMATS)
    if path.suffix.lower() == ".json":  # read as a CSV, a result file said it had "no geometry columns"
        raise BrdfInputError(
            f"{path}: a JSON file, not samples: samples are read from CSV, MERL, ALTA and ASTM files; a fit's result"
            " file is read by export, plot and render, and as a fit's start"
        )
    by_suffix = next((name for name, kind in FORMATS.items() if path.suffix.lower() == kind.suffixes[0]), None)
    if by_suffix in ("csv", "merl", "astm"):
        return by_suffix
    head = _first_lines(path)
    if by_suffix == "alta" or any(line.startswith("#") for line in head[:1]):
        if any(line.upper().startswith(("#DIM", "#PARAM_IN")) for line in head):
            return "alta"
    if any(line.upper().startswith(("NUM_POINTS", "VARS")) for line in head):
        return "astm"
    if by_suffix == "alta":
        return "alta"  # the ALTA reader says what is missing
    return "csv"


def format_of_output(path: Path) -> str | None:
    """The format a file written to ``path`` gets from its suffix (None for a suffix no format uses)."""
    return next((name for name, kind in FORMATS.items() if path.suffix.lower() in kind.suffixes), None)


def load_samples(
    path: "str | os.PathLike | pandas.DataFrame",
    *,
    format: str | None = None,
    angles: str = "degrees",
    quantity: str | None = None,
    spectral_to: str = "keep",
    illuminant: str = DEFAULT_ILLUMINANT,
    observer: str = DEFAULT_OBSERVER,
    subsample: int | None = None,
    subsample_method: str = "random",
    seed: int = 0,
    bin_centres: bool = False,
) -> Samples:
    """Read a measurement file (or a pandas ``DataFrame`` with a samples CSV's columns, ``docs/formats.md``) into
    :class:`Samples` holding BRDF values in 1/sr.

    ``format``: one of :data:`FORMATS` (default: from the file's suffix and first lines).
    ``angles``: ``"degrees"`` (default) or ``"radians"`` for a CSV file's angle columns.
    ``quantity``: what the values are, one of ``brdf``, ``reflectance-factor``, ``cosine-weighted-in``
    (also ``cosine-weighted``) or ``cosine-weighted-out`` (``quantities.py``); default: what the file's
    header says (ALTA's ``#PARAM_OUT``), else ``brdf``. A quantity given where the header says another wins,
    with an :class:`~brdffit.errors.InputWarning`; never are values divided twice. ``spectral_to``: for
    value columns named by wavelength in nm, ``xyz`` or ``rgb`` (linear sRGB) under ``illuminant`` and
    ``observer`` (colour-science names), or ``keep`` every band as a channel (default). ``subsample``
    (MERL): keep that many samples, ``subsample_method`` ``random`` or ``stratified`` over θh, seeded by
    ``seed``. ``bin_centres`` (MERL): each bin's sample at the bin's centre, not its lower edge (where MERL's
    ``BRDFRead.cpp`` looks it up; ``physics/merl_table.py``).
    """
    choice("angles", angles, ANGLE_UNITS)
    given = None if quantity is None else canonical(quantity)
    frame = _is_data_frame(path)
    if frame and format not in (None, "csv"):
        raise BrdfInputError(Argument("format", repr(format)), " does not apply to a DataFrame (read as a CSV's table)")
    where = "the DataFrame" if frame else Path(path)
    kind = "csv" if frame else detect_format(Path(path), format)
    if kind != "csv" and angles != "degrees":
        raise BrdfInputError(
            Argument("angles"), f" applies to CSV files; {where} is {kind} (its angle units are fixed)"
        )
    for name, given_here in (("subsample", subsample is not None), ("bin_centres", bool(bin_centres))):
        if kind != "merl" and given_here:
            raise BrdfInputError(Argument(name), f" applies to MERL files; {where} is {kind}")
    if frame:  # a CSV's table, without a file or its header: no file to read again, so no reading to record
        return _as_quantity(read_data_frame(path, angles), given, None, spectral_to, illuminant, observer)
    reading = _reading(format, angles, spectral_to, illuminant, observer, bin_centres)
    path = where
    reader_options: dict[str, dict[str, Any]] = {
        "csv": {"angles": angles},
        "merl": {
            "subsample": subsample,
            "subsample_method": subsample_method,
            "seed": seed,
            "bin_centres": bool(bin_centres),
        },
    }
    samples = FORMATS[kind].read(path, **reader_options.get(kind, {}))
    assert samples.provenance is not None  # every reader records how it read the file
    header = samples.provenance.header_quantity
    if given is not None and header is not None and given != header:
        warn(
            InputWarning(
                f"{path}: the values are read as ", Argument("quantity", given), f", not as the header says ({header})"
            )
        )
    return _read(_as_quantity(samples, given, header, spectral_to, illuminant, observer), reading)


def _reading(format, angles, spectral_to, illuminant, observer, bin_centres) -> tuple[tuple[str, Any], ...]:
    """The options of :func:`load_samples` that make what a file gives and differ from their defaults, as ``(name,
    value)`` pairs (``Provenance.reading``): the format given, radians, a spectral conversion (with its illuminant
    and observer), MERL's bin centres. Not ``quantity`` (a result records it apart) nor a subsample (a fit of part
    of a file is compared with all of it)."""
    kept: dict[str, Any] = {} if format is None else {"format": format}
    if angles != "degrees":
        kept["angles"] = angles
    if spectral_to != "keep":
        kept |= {"spectral_to": spectral_to, "illuminant": illuminant, "observer": observer}
    if bin_centres:
        kept["bin_centres"] = True
    return tuple(kept.items())


#: The options :func:`_reading` records and what each may be: a result file, which holds them (``fit.reading``), is
#: input, so :func:`checked_reading` checks them when it is read.
READING_OPTIONS: dict[str, Any] = {
    "format": tuple(FORMATS),
    "angles": ANGLE_UNITS,
    "spectral_to": SPECTRAL_TARGETS,
    "illuminant": str,
    "observer": str,
    "bin_centres": bool,
}


def checked_reading(reading: dict[str, Any]) -> dict[str, Any]:
    """``reading`` (a result's ``fit.reading``) if each of its entries is an option of :data:`READING_OPTIONS` with
    a value it may take, else ``TypeError`` naming the first that is not."""
    for name, value in reading.items():
        allowed = READING_OPTIONS.get(name)
        if isinstance(allowed, tuple):
            fits = isinstance(value, str) and value in allowed
        else:
            fits = allowed is not None and isinstance(value, allowed)
        if not fits:
            raise TypeError(
                f"fit.reading: {name} = {value!r}; it holds {', '.join(READING_OPTIONS)} (format, angles and"
                " spectral_to as load_samples takes them, bin_centres true or false)"
            )
    return reading


def agreed_reading(readings: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """The options of :data:`READING_OPTIONS` to read a samples file with again as results read theirs (each
    ``fit.reading``): those whose value every reading gives alike and that differ from :func:`load_samples`'s default
    (an option a reading does not record is at its default). An option the readings disagree on is left at its
    default."""
    readings = list(readings)
    defaults = load_samples_defaults()
    agreed = {}
    for name in READING_OPTIONS:
        values = [reading.get(name, defaults[name]) for reading in readings]
        if values and all(value == values[0] for value in values) and values[0] != defaults[name]:
            agreed[name] = values[0]
    return agreed


@contextmanager
def errors_name_the_reading(path, reading: dict[str, Any], whose: str) -> Iterator[None]:
    """Within it, a :class:`BrdfInputError` (reading ``path`` with ``reading``, options taken from results'
    ``fit.reading``) says where they came from: ``{path}: read as {whose} fit.reading: a=b, …): {the error}``, with
    ``whose`` such as ``the fit read its samples (the result's``. Without ``reading`` the error is left as it is."""
    try:
        yield
    except BrdfInputError as error:
        if not reading:
            raise
        said = ", ".join(f"{name}={value}" for name, value in reading.items())
        raise BrdfInputError(f"{path}: read as {whose} fit.reading: {said}): ", *error.parts) from None


def load_samples_defaults() -> dict[str, Any]:
    """:func:`load_samples`'s keyword arguments and their defaults."""
    return {name: parameter.default for name, parameter in inspect.signature(load_samples).parameters.items()}


def _read(samples: Samples, reading: tuple[tuple[str, Any], ...]) -> Samples:
    """``samples`` with how they were read (:func:`_reading`) in their provenance."""
    assert samples.provenance is not None  # every reader records how it read the file
    return replace(samples, provenance=replace(samples.provenance, reading=reading))


def _as_quantity(
    samples: Samples, given: str | None, header: str | None, spectral_to: str, illuminant: str, observer: str
) -> Samples:
    """Samples as read, their values made BRDFs from the quantity ``given`` (else the ``header``'s, else ``brdf``) and
    their channels converted as ``spectral_to`` asks (:func:`load_samples`)."""
    quantity = given or header or "brdf"
    assert samples.provenance is not None  # read from a file or a DataFrame
    samples = replace(
        to_brdf(samples, quantity),
        provenance=replace(samples.provenance, quantity=quantity, quantity_given=given is not None),
    )
    return spectral.spectral_to(samples, spectral_to, illuminant=illuminant, observer=observer)


def _is_data_frame(value) -> bool:
    """Whether ``value`` is a pandas ``DataFrame`` (by its type's module and name: pandas is not imported)."""
    kind = type(value)
    return kind.__name__ == "DataFrame" and kind.__module__.split(".")[0] == "pandas"


def as_samples(samples: "Samples | str | os.PathLike", **read_options) -> Samples:
    """Samples as they are, or the samples a file (or a pandas ``DataFrame``) holds (read by :func:`load_samples` with
    ``read_options``)."""
    if isinstance(samples, str | os.PathLike) or _is_data_frame(samples):
        return load_samples(samples, **read_options)
    return samples


def check_read_options(read_options: dict) -> None:
    """One line naming an option :func:`load_samples` does not take, before any file is read."""
    allowed = [name for name in inspect.signature(load_samples).parameters if name != "path"]
    unknown = sorted(set(read_options) - set(allowed))
    if unknown:
        raise BrdfInputError(
            Argument("read_options"), f" has {', '.join(map(repr, unknown))}; allowed: {', '.join(allowed)}"
        )


def save_samples(samples: Samples, path: str | os.PathLike) -> None:
    """Write ``samples`` atomically in the format ``path``'s suffix names (``.dat`` ALTA, ``.astm`` and ``.txt``
    ASTM), else as a samples CSV; :func:`load_samples` reads it back. A MERL table is written from a model
    (``brdffit/export``), not from samples."""
    kind = format_of_output(Path(path)) or "csv"
    write = FORMATS[kind].write
    if write is None:
        raise BrdfInputError(
            f"{path}: a {kind} file is written from a fitted model (brdffit convert RESULT.json {Path(path).name}),"
            " not from samples"
        )
    write(samples, path)


def _first_lines(path: Path, count: int = 64) -> list[str]:
    """The first ``count`` non-blank lines of a text file, stripped ([] for a binary or unreadable one)."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(16384)
    except OSError:
        return []  # the reader reports it
    if b"\0" in head:
        return []
    text = head.decode("utf-8", errors="replace")
    return [line.strip() for line in text.splitlines() if line.strip()][:count]
