"""ASTM E1392 scatter data files, the text format of Cornell's gonioreflectometer measurements.

ASTM E1392-96, "Standard Practice for Angle Resolved Optical Scatter Measurements on Specular or
Diffuse Surfaces"; Cornell University Program of Computer Graphics, reflectance data
(graphics.cornell.edu/online/measurements/reflectance). A file is a header of keyword lines, then
one measurement per line::

    SOURCE        Cornell University Program of Computer Graphics
    SAMPLE_NAME   "krylon blue"
    NUM_POINTS    1439
    VARS          theta_i,phi_i,theta_s,phi_s,R,G,B
    0.17453,0,0.52360,3.14159,0.0712,0.0843,0.1529
    ...

* ``NUM_POINTS n``: the number of data lines (required, must match).
* ``VARS name,...``: the columns (required): ``theta_i, phi_i`` (the light), ``theta_s, phi_s``
  (the scattered direction, i.e. the viewer), in any order, and the value columns: BRDF in 1/sr,
  one channel each. Channels are named after the columns: ``R, G, B`` and ``X, Y, Z`` lower-cased,
  wavelengths (``400`` or ``400nm``) as their number (``"400"``), any other name as written.
* Keywords are case-insensitive; other keyword lines (``SOURCE``, ``SAMPLE_NAME``, ``FORMAT``,
  ...), blank lines and ``#`` lines are ignored. The data start at the first line that begins
  with a number; cells are separated by commas or white space.

Angles: ``θ`` is the zenith angle, ``φ`` the azimuth, both directions pointing away from the surface
(``wi = d(θi, φi)``, ``wo = d(θs, φs)``, ``d = (sin θ cos φ, sin θ sin φ, cos θ)``). The unit is
not stated in the files. Cornell's files are read in radians by both public readers found (libbsdf's
``AstmReader``, which wraps negative angles by 2π, and the ASTM parser of the RIT ray tracer
``edu.rit.krisher``, which takes ``sin`` of them directly), while degrees are the usual unit in
scatter work; so the unit is inferred: **radians when every angle in the file is within ±2π,
otherwise degrees**. A file in degrees whose every angle is within ±6.28° (only near-normal
measurements) would be misread; :func:`write_astm` writes radians, which are always read back as
such. ``θ`` must lie in [0, 90°) (directions above the horizon) and ``φ`` within ±360°.

Bad input raises :class:`~brdffit.errors.BrdfInputError` with one line naming the file (and the
line in the file where there is one).
"""

import math
import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from .._files import write_text_atomic
from .._jax import first_bad
from ..errors import BrdfInputError
from ..physics.geometry import direction_to_spherical
from .cells import TableChecks, named
from .samples import Provenance, Samples
from .text import format_rows, is_number, parse_numbers, read_text

#: The geometry columns every ``VARS`` line names.
ANGLE_NAMES = ("theta_i", "phi_i", "theta_s", "phi_s")
_KEYWORD = re.compile(r"([^\s,=:]+)[\s,=:]*(.*)")
_WAVELENGTH = re.compile(r"([0-9]+(?:\.[0-9]+)?)\s*nm", re.IGNORECASE)
_TWO_PI = 2 * math.pi


def read_astm(path: str | os.PathLike) -> Samples:
    """Read an ASTM E1392 text file into :class:`Samples` holding BRDF values in 1/sr.

    Angles are read in radians when all are within ±2π, else in degrees (module docstring).
    """
    path = Path(path)
    source = str(path)
    text = read_text(path, "an ASTM E1392 file")
    keywords, data = _split(text, source)
    if not data:
        raise BrdfInputError(f"{source}: no data rows (no line starting with a number after the header)")
    for keyword, example in (("NUM_POINTS", "NUM_POINTS 1439"), ("VARS", "VARS theta_i,phi_i,theta_s,phi_s,R,G,B")):
        if keyword not in keywords:
            raise BrdfInputError(f"{source}: no {keyword} line before the data (e.g. '{example}')")
    count_line, count_text = keywords["NUM_POINTS"]
    if not re.fullmatch(r"\+?[0-9]{1,12}", count_text):
        raise BrdfInputError(f"{source}: line {count_line}: NUM_POINTS {count_text!r} is not a whole number")
    names, angle_columns, value_columns, channels = _columns(*keywords["VARS"], source)

    lines = np.array([number for number, _ in data])
    rows = [_cells(line) for _, line in data]
    counts = np.fromiter(map(len, rows), dtype=np.int64, count=len(rows))
    uneven = first_bad(counts != len(names))
    if uneven is not None:
        row = uneven[0]
        raise BrdfInputError(
            f"{source}: line {lines[row]}: {counts[row]} cells, but VARS (line {keywords['VARS'][0]}) names"
            f" {len(names)} columns"
        )
    if int(count_text) != len(rows):
        raise BrdfInputError(
            f"{source}: NUM_POINTS (line {count_line}) says {int(count_text)} points, but the file has"
            f" {len(rows)} data rows{' (truncated?)' if int(count_text) > len(rows) else ''}"
        )
    checks = TableChecks(lambda row: f"{source}: line {lines[row]}")
    table = parse_numbers(rows, checks, named(names))

    angles = table[:, angle_columns]
    values = table[:, value_columns]
    beyond = np.any(np.abs(angles) > _TWO_PI + 1e-9, axis=1)  # rows that can only be degrees
    radians = not bool(np.any(beyond))
    if not radians and np.count_nonzero(beyond) <= MIXED_SHARE * len(rows):
        first = int(np.argmax(beyond))
        raise BrdfInputError(
            f"{source}: line {lines[first]}: an angle beyond ±2π (degrees) in a file whose other rows"
            f" ({len(rows) - np.count_nonzero(beyond)} of {len(rows)}) all lie within ±2π (radians): the units are"
            " mixed; write every angle in one unit (radians, Cornell's)"
        )
    why = "every angle in the file is within ±2π" if radians else "some angle in the file is beyond ±2π"
    unit = "radians" if radians else "degrees"
    wi, wo = checks.angles_to_directions(
        angles[:, [0, 2]],
        angles[:, [1, 3]],
        unit,
        ("theta_i", "theta_s"),
        ("phi_i", "phi_s"),
        because=f"; angles are read as {unit} because {why}",
    )
    checks.non_negative(
        values, named(channels, "channel"), lambda v: f"{v:g} is negative (negative reflectance is not allowed)"
    )
    samples = Samples.from_arrays(wi, wo, values, channels=channels, source=source)
    return replace(samples, provenance=Provenance("astm", rows=len(rows)))


#: A file read as degrees (some angle beyond ±2π) where at most this share of the rows has such an angle is refused as
#: mixed: a file in degrees has an azimuth or a scatter angle beyond 6.28° on almost every row.
MIXED_SHARE = 0.1


def _split(text: str, source: str) -> tuple[dict[str, tuple[int, str]], list[tuple[int, str]]]:
    """The ``NUM_POINTS`` and ``VARS`` keyword lines as ``{KEYWORD: (line, value)}``, and the data lines."""
    keywords: dict[str, tuple[int, str]] = {}
    data: list[tuple[int, str]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        if data or is_number(_cells(stripped)[0]):
            data.append((number, stripped))
            continue
        match = _KEYWORD.fullmatch(stripped)
        keyword = match.group(1).upper() if match else ""
        if match and keyword in ("NUM_POINTS", "VARS"):
            if keyword in keywords:
                raise BrdfInputError(
                    f"{source}: line {number}: {keyword} appears twice (first on line {keywords[keyword][0]})"
                )
            keywords[keyword] = (number, match.group(2).strip())
    return keywords, data


def _cells(line: str) -> list[str]:
    """A line's cells: comma-separated (one trailing comma allowed) when it has a comma, else white-space separated."""
    if "," not in line:
        return line.split()
    stripped = line.strip()
    if stripped.endswith(","):
        stripped = stripped[:-1]
    return [cell.strip() for cell in stripped.split(",")]


def channel_name(name: str) -> str:
    """The channel a ``VARS`` value column gives: ``R`` → ``r``, ``X`` → ``x``, ``400nm`` → ``400``."""
    lower = name.lower()
    if lower in ("r", "g", "b", "x", "y", "z"):
        return lower
    wavelength = _WAVELENGTH.fullmatch(name)
    return wavelength.group(1) if wavelength else name


def _columns(line: int, text: str, source: str) -> tuple[list[str], list[int], list[int], tuple[str, ...]]:
    """Column names, the indices of ``theta_i, phi_i, theta_s, phi_s``, the value columns and their channels."""
    where = f"{source}: line {line}"
    names = _cells(text)
    if any(not name for name in names):
        raise BrdfInputError(f"{where}: VARS {text!r} has an empty column name")
    lower = [name.lower() for name in names]
    for index, name in enumerate(lower):
        if name in lower[:index]:
            raise BrdfInputError(f"{where}: VARS names column {names[index]!r} twice")
    missing = [name for name in ANGLE_NAMES if name not in lower]
    if missing:
        raise BrdfInputError(
            f"{where}: VARS lacks {', '.join(missing)}; it must name {', '.join(ANGLE_NAMES)} and the value columns"
        )
    angle_columns = [lower.index(name) for name in ANGLE_NAMES]
    value_columns = [index for index in range(len(names)) if index not in angle_columns]
    if not value_columns:
        raise BrdfInputError(f"{where}: VARS names no value column after {', '.join(ANGLE_NAMES)}")
    channels = tuple(channel_name(names[index]) for index in value_columns)
    if len(set(channels)) != len(channels):
        raise BrdfInputError(f"{where}: VARS names the same channel twice ({', '.join(channels)})")
    return names, angle_columns, value_columns, channels


# ---------------------------------------------------------------------- writing
def write_astm(samples: Samples, path: str | os.PathLike) -> None:
    """Write ``samples`` as an ASTM E1392 text file, atomically.

    Header ``SOURCE``, ``SAMPLE_NAME``, ``NUM_POINTS`` and ``VARS theta_i,phi_i,theta_s,phi_s,...``
    (channels ``r, g, b`` and ``x, y, z`` as ``R, G, B`` and ``X, Y, Z``, wavelength channels such
    as ``400`` as ``400nm``, as libbsdf expects, other names as they are), then comma-separated
    rows: angles in **radians** (Cornell's unit; :func:`read_astm` reads them back as radians) and
    BRDF values in 1/sr, with 17 significant digits, so the round trip is exact to ~1e-16.
    Sigma and weights are not written. A channel name that is empty, holds a comma or white space,
    or is an angle name cannot be written.
    """
    written = []
    for name in samples.channels:
        if not name or "," in name or any(ch.isspace() for ch in name) or name.lower() in ANGLE_NAMES:
            raise BrdfInputError(
                f"{path}: channel name {name!r} cannot be an ASTM VARS column (no commas, white space or angle names)"
            )
        lower = name.lower()
        if lower in ("r", "g", "b", "x", "y", "z"):
            written.append(lower.upper())
        elif re.fullmatch(r"[0-9]+(?:\.[0-9]+)?", name):
            written.append(f"{name}nm")
        else:
            written.append(name)
    back = [channel_name(name) for name in written]
    if len(set(back)) != len(back):
        raise BrdfInputError(f"{path}: channels {', '.join(samples.channels)} would read back as the same column")
    theta_i, phi_i = direction_to_spherical(np.asarray(samples.wi, dtype=np.float64))
    theta_s, phi_s = direction_to_spherical(np.asarray(samples.wo, dtype=np.float64))
    table = np.column_stack([theta_i, phi_i, theta_s, phi_s, np.asarray(samples.values, dtype=np.float64)])
    name = " ".join(str(samples.source).replace('"', "'").split())
    header = (
        "SOURCE brdffit\n"
        f'SAMPLE_NAME "{name}"\n'
        f"NUM_POINTS {samples.n_samples}\n"
        f"VARS {','.join((*ANGLE_NAMES, *written))}\n"
    )
    write_text_atomic(path, header + format_rows(table, ","))
