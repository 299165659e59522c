"""The samples file: a CSV table of measurements, one per row (brdffit's own format; ``docs/formats.md``).

Comma- or whitespace-separated, ``#`` starts a comment (a whole line or the rest of one), one header row
naming

* the geometry: ``theta_i, phi_i, theta_o, phi_o`` (degrees unless ``angles="radians"``) or
  ``wi_x, wi_y, wi_z, wo_x, wo_y, wo_z``;
* the values: ``value``, or ``r, g, b``, or any other numeric columns, taken as named channels in file
  order (spectral bands named by wavelength);
* optionally ``sigma`` (or ``sigma_<channel>`` for each channel), the 1-σ uncertainty in the units of
  the values, and ``weight``.

Bad input raises :class:`~brdffit.errors.BrdfInputError` with one line naming the file, the row (and its
line in the file) and the column.
"""

import functools
import itertools
import math
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._files import write_text_atomic
from ..errors import Argument, BrdfInputError, InputWarning, warn
from ..physics.geometry import direction_to_spherical
from .cells import TableChecks, named
from .samples import Provenance, Samples
from .text import check_text, parse_numbers, text_lines

ANGLE_COLUMNS = ("theta_i", "phi_i", "theta_o", "phi_o")
VECTOR_COLUMNS = ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")
RGB_COLUMNS = ("r", "g", "b")
ANGLE_UNITS = ("degrees", "radians")
#: Column-name prefixes that belong to the geometry, never to a channel.
_GEOMETRY_PREFIXES = ("theta", "phi", "wi_", "wo_")


#: Data rows parsed at a time where the fast parser (``numpy.loadtxt``) refuses a file and the cells are read one
#: by one: the Python objects of one chunk (~1.4 KB a row) are all that file costs beyond its table.
CHUNK_ROWS = 65536
_WHAT = "a samples file"


def read_csv(path: str | os.PathLike, angles: str = "degrees") -> Samples:
    """Read a samples file into :class:`Samples`; ``angles`` is the unit of its angle columns.

    The file is streamed (``docs/formats.md``, memory): its table of float64 cells is parsed by ``numpy.loadtxt``,
    and only a file that parser refuses is read cell by cell (in :data:`CHUNK_ROWS`-row chunks) to name the row
    and column at fault."""
    path = Path(path)
    source = str(path)
    check_text(path, _WHAT)
    header_line, header = _header(path, source)
    delimiter = "," if "," in header else None
    names = [name.strip() for name in header.split(delimiter)]
    layout = _Layout.from_header(names, f"{source}: header (line {header_line})")
    line_of = functools.cache(functools.partial(_line_of_row, path, header_line))
    checks = TableChecks(lambda row: f"{source}: row {row + 1} (line {line_of(row)})")
    table = _fast_table(path, header_line, delimiter, len(names))
    if table is None:
        table = _table_by_cells(path, header_line, delimiter, names, checks)
    else:
        checks.finite(table, named(names))
    return _samples_of_table(table, layout, checks, source, angles)


def read_data_frame(frame, angles: str = "degrees") -> Samples:
    """A pandas ``DataFrame`` whose columns are a samples file's (``docs/formats.md``), read as that file would be:
    the same columns, checks and messages, which name the DataFrame's row by its index label. pandas itself is not
    imported: the frame is read through its ``columns``, ``index`` and ``to_numpy``."""
    source = "DataFrame"
    names = [str(name).strip() for name in frame.columns]
    layout = _Layout.from_header(names, f"{source}: columns")
    labels = list(frame.index)
    try:
        table = frame.to_numpy(dtype=np.float64)
    except (TypeError, ValueError):
        raise _not_a_number(frame, names, labels, source) from None
    checks = TableChecks(lambda row: f"{source}: row {labels[row]!r}")
    checks.finite(table, named(names))
    return _samples_of_table(table, layout, checks, source, angles)


def _not_a_number(frame, names: list[str], labels: list, source: str) -> BrdfInputError:
    """The error naming a DataFrame's first cell that is not a number, by row label and column."""
    for column, name in enumerate(names):
        for row, cell in enumerate(frame.iloc[:, column].to_numpy()):
            try:
                float(cell)
            except (TypeError, ValueError):
                return BrdfInputError(f"{source}: row {labels[row]!r}, column {name!r}: {cell!r} is not a number")
    return BrdfInputError(f"{source}: its cells are not all numbers")


def _samples_of_table(table: np.ndarray, layout: "_Layout", checks: TableChecks, source: str, angles: str) -> Samples:
    """The samples of a parsed table of float64 cells (rows × the header's columns) laid out as ``layout`` says."""
    if not len(table):
        raise BrdfInputError(f"{source}: empty table (a header row but no data rows)")
    rows = len(table)

    if layout.angles:
        angles_table = table[:, layout.geometry]
        theta = angles_table[:, [0, 2]]
        wi, wo = checks.angles_to_directions(
            theta, angles_table[:, [1, 3]], angles, ("theta_i", "theta_o"), ("phi_i", "phi_o")
        )
        if angles == "degrees" and 0 < np.max(theta) <= math.pi / 2:
            warn(
                InputWarning(
                    f"{source}: every zenith angle is within [0, π/2] = [0, 1.571] degrees: radians read as degrees?"
                    " If so, give ",
                    Argument("angles", "radians"),
                )
            )
    else:
        geometry = table[:, layout.geometry]
        wi = checks.unit_directions(geometry[:, :3], "wi")
        wo = checks.unit_directions(geometry[:, 3:], "wo")
    values = table[:, layout.values]
    sigma = None if layout.sigma is None else np.broadcast_to(table[:, layout.sigma], values.shape)
    weight = None if layout.weight is None else table[:, layout.weight]
    sigma, weight = checks.values_sigma_weight(values, layout.channels, sigma, weight, source, layout.sigma_names)
    return Samples(wi, wo, values, layout.channels, sigma, weight, source, Provenance("csv", rows=rows))


def _is_content(line: str) -> bool:
    """Whether a line holds a header or data (not blank, not a whole-line ``#`` comment)."""
    stripped = line.lstrip()
    return bool(stripped) and not stripped.startswith("#")


def _header(path: Path, source: str) -> tuple[int, str]:
    """The first content line: its number and text."""
    for number, line in text_lines(path, _WHAT):
        if _is_content(line):
            return number, line
    raise BrdfInputError(f"{source}: empty table (no header row and no data)")


def _data_lines(path: Path, header_line: int) -> Iterator[tuple[int, str]]:
    """``(number, line)`` of each data row: the content lines after the header."""
    return ((number, line) for number, line in text_lines(path, _WHAT) if number > header_line and _is_content(line))


def _line_of_row(path: Path, header_line: int, row: int) -> int:
    """The line in the file of data row ``row`` (from 0): found again by reading the file, for a message."""
    return next(itertools.islice(_data_lines(path, header_line), row, None))[0]


def _fast_table(path: Path, header_line: int, delimiter: str | None, width: int) -> np.ndarray | None:
    """The data rows as an (N, width) float64 table read by ``numpy.loadtxt`` (its C parser: ~8 bytes a cell beyond
    the table), or None where it refuses the file or reads another width: the cells are then read one by one.

    What ``loadtxt`` refuses (``1_000``, digits other than ASCII, a line of blanks, a row of other width) is judged
    cell by cell, as before: the same numbers, the same errors."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": said as an empty table
            table = np.loadtxt(
                path,
                dtype=np.float64,
                delimiter=delimiter,
                comments="#",
                skiprows=header_line,
                ndmin=2,
                encoding="utf-8-sig",
            )
    except (ValueError, OverflowError):
        return None
    if table.size and table.shape[1] != width:
        return None
    return table.reshape(-1, width)


def _table_by_cells(
    path: Path, header_line: int, delimiter: str | None, names: list[str], checks: TableChecks
) -> np.ndarray:
    """The data rows as an (N, columns) float64 table read cell by cell, :data:`CHUNK_ROWS` rows at a time; the
    first row whose cells the header does not name, or cell that is no finite number, is reported by ``checks``."""
    blocks, done = [], 0
    lines = _data_lines(path, header_line)
    while chunk := list(itertools.islice(lines, CHUNK_ROWS)):
        cells = [[cell.strip() for cell in line.split("#", 1)[0].split(delimiter)] for _, line in chunk]

        def locate(row: int, offset: int = done) -> str:  # this chunk's rows, numbered in the whole table
            return checks.locate(offset + row)

        shifted = TableChecks(locate)
        for row, row_cells in enumerate(cells):
            if len(row_cells) != len(names):
                raise BrdfInputError(
                    f"{shifted.locate(row)}: {len(row_cells)} cells, but the header names {len(names)} columns"
                )
        blocks.append(parse_numbers(cells, shifted, named(names)))
        done += len(chunk)
    return np.concatenate(blocks) if blocks else np.empty((0, len(names)))


def write_csv(samples: Samples, path: str | os.PathLike) -> None:
    """Write ``samples`` as a samples file, atomically: angles in degrees, BRDF values, sigma and weight if present.

    Numbers are written with 17 significant digits, so reading the file back
    gives the same float64 values (up to the angle ↔ vector conversion, ~1e-16).
    """
    columns = [np.degrees(angle) for w in (samples.wi, samples.wo) for angle in direction_to_spherical(w)]
    header = list(ANGLE_COLUMNS) + list(samples.channels)
    columns += list(samples.values.T)
    if samples.sigma is not None:
        header += ["sigma"] if samples.n_channels == 1 else [f"sigma_{c}" for c in samples.channels]
        columns += list(samples.sigma.T)
    if samples.weight is not None:
        header.append("weight")
        columns.append(samples.weight)
    table = np.column_stack(columns)
    body = "\n".join(",".join(f"{x:.17g}" for x in row) for row in table)
    write_text_atomic(path, ",".join(header) + "\n" + body + "\n")


@dataclass(frozen=True)
class _Layout:
    """Which header columns hold the geometry, values, sigma and weight."""

    angles: bool
    geometry: list[int]
    values: list[int]
    channels: tuple[str, ...]
    sigma: list[int] | None
    sigma_names: list[str] | None
    weight: int | None

    @classmethod
    def from_header(cls, names: list[str], where: str) -> "_Layout":
        """The layout of the columns ``names``; ``where`` begins each message (``oak.csv: header (line 1)``)."""
        lower = [name.lower() for name in names]
        for index, name in enumerate(lower):
            if not name:
                raise BrdfInputError(f"{where}: column {index + 1} has no name")
            if name in lower[:index]:
                raise BrdfInputError(f"{where}: column {names[index]!r} appears twice")
        position = {name: index for index, name in enumerate(lower)}
        has_angles = any(name in position for name in ANGLE_COLUMNS)
        has_vectors = any(name in position for name in VECTOR_COLUMNS)
        geometry_help = f"geometry is {', '.join(ANGLE_COLUMNS)} or {', '.join(VECTOR_COLUMNS)}"
        if has_angles and has_vectors:
            raise BrdfInputError(
                f"{where}: both angle and direction-vector columns; give one geometry ({geometry_help})"
            )
        if not (has_angles or has_vectors):
            raise BrdfInputError(f"{where}: no geometry columns; {geometry_help}")
        wanted = ANGLE_COLUMNS if has_angles else VECTOR_COLUMNS
        for name in wanted:
            if name not in position:
                raise BrdfInputError(f"{where}: missing column {name!r}; {geometry_help}")
        geometry = [position[name] for name in wanted]

        rest = [index for index in range(len(names)) if lower[index] not in wanted]
        weight = position.get("weight")
        sigma_columns = [i for i in rest if lower[i] == "sigma" or lower[i].startswith("sigma_")]
        value_columns = [i for i in rest if i != weight and i not in sigma_columns]
        for index in value_columns:
            if lower[index].startswith(_GEOMETRY_PREFIXES):
                raise BrdfInputError(f"{where}: unknown column {names[index]!r}; {geometry_help}")
        value_names = [lower[i] for i in value_columns]
        if "value" in value_names or any(name in RGB_COLUMNS for name in value_names):
            expected = ["value"] if "value" in value_names else list(RGB_COLUMNS)
            for index in value_columns:
                if lower[index] not in expected:
                    raise BrdfInputError(
                        f"{where}: unknown column {names[index]!r}; with {', '.join(expected)} no other value columns"
                        " are allowed (optional: sigma, sigma_<channel>, weight)"
                    )
            for name in expected:
                if name not in value_names:
                    raise BrdfInputError(f"{where}: missing column {name!r}; RGB values need r, g and b")
            value_columns = [position[name] for name in expected]
            channels = tuple(expected)
        else:
            channels = tuple(names[i] for i in value_columns)
        if not value_columns:
            raise BrdfInputError(f"{where}: no value columns; give value, or r, g, b, or named channels")

        sigma, sigma_names = None, None
        if sigma_columns:
            if len(sigma_columns) == 1 and lower[sigma_columns[0]] == "sigma":
                sigma, sigma_names = sigma_columns, [names[sigma_columns[0]]] * len(channels)
            else:
                by_channel = {lower[i][len("sigma_") :]: i for i in sigma_columns}
                for index in sigma_columns:
                    if lower[index] == "sigma":
                        raise BrdfInputError(
                            f"{where}: give either one 'sigma' column or one sigma_<channel> per channel, not both"
                        )
                    if lower[index][len("sigma_") :] not in [c.lower() for c in channels]:
                        raise BrdfInputError(
                            f"{where}: unknown column {names[index]!r}; sigma columns are sigma_<channel>"
                            f" for channels {', '.join(channels)}"
                        )
                missing = [c for c in channels if c.lower() not in by_channel]
                if missing:
                    raise BrdfInputError(
                        f"{where}: missing column 'sigma_{missing[0]}'; give a sigma for every channel or one 'sigma'"
                    )
                sigma = [by_channel[c.lower()] for c in channels]
                sigma_names = [names[i] for i in sigma]
        return cls(has_angles, geometry, value_columns, channels, sigma, sigma_names, weight)
