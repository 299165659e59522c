"""What the text formats share: reading a file as text, cells as numbers, rows written back exactly."""

import codecs
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from .._files import reading
from ..errors import BrdfInputError
from .cells import ColumnName, TableChecks


def read_text(path: Path, what: str, *, allow_empty: bool = False) -> str:
    """The UTF-8 text of ``path`` (a byte-order mark dropped); every failure is a one-line error.

    ``what`` names the file kind in messages (``an ALTA data file``). A file of only white space is an
    error unless ``allow_empty`` (the format then says what is missing).
    """
    with reading(path, what):
        data = path.read_bytes()
    try:
        text = data.decode("utf-8-sig")  # a byte-order mark (Excel) is not part of the content
    except UnicodeDecodeError:
        raise BrdfInputError(f"{path}: not a text file (not UTF-8); {what} is text") from None
    if "\0" in text:
        raise BrdfInputError(f"{path}: binary content (NUL bytes); {what} is text")
    if not allow_empty and not text.strip():
        raise BrdfInputError(f"{path}: empty file; {what} has a header and rows of numbers")
    return text


#: How much of a file :func:`check_text` and :func:`text_lines` hold at once, bytes.
CHUNK_BYTES = 1 << 20


def check_text(path: Path, what: str) -> None:
    """Raise what :func:`read_text` raises for a file that is not text (not UTF-8, NUL bytes), reading it in chunks
    of :data:`CHUNK_BYTES`: a file of any size is checked in constant memory."""
    decoder = codecs.getincrementaldecoder("utf-8-sig")()
    with reading(path, what), open(path, "rb") as file:
        while True:
            chunk = file.read(CHUNK_BYTES)
            try:
                text = decoder.decode(chunk, final=not chunk)
            except UnicodeDecodeError:
                raise BrdfInputError(f"{path}: not a text file (not UTF-8); {what} is text") from None
            if "\0" in text:
                raise BrdfInputError(f"{path}: binary content (NUL bytes); {what} is text")
            if not chunk:
                return


def text_lines(path: Path, what: str) -> Iterator[tuple[int, str]]:
    """``(number, line)`` for each line of a text file checked by :func:`check_text`, numbered from 1, one at a
    time (lines end at universal newlines, as an editor counts them)."""
    with reading(path, what), open(path, encoding="utf-8-sig", newline=None) as file:
        yield from enumerate((line.rstrip("\n") for line in file), start=1)


def is_number(cell: str) -> bool:
    """Whether ``cell`` is a plain decimal number (``nan`` and ``inf`` included; no ``_`` separators)."""
    if "_" in cell:
        return False
    try:
        float(cell)
    except ValueError:
        return False
    return True


def parse_numbers(rows: Sequence[Sequence[str]], checks: TableChecks, column: ColumnName) -> np.ndarray:
    """``rows`` of equally many cells as an (N, columns) float64 array, every value finite.

    The first cell that is not a number, or not finite, is reported by ``checks`` (which names its row)
    and ``column`` (which names its column).
    """
    width = len(rows[0])
    flat = [cell for row in rows for cell in row]
    if not any("_" in cell for cell in flat):  # numpy, like float(), would read 1_000
        try:
            table = np.array(flat, dtype=np.float64).reshape(len(rows), width)
        except ValueError:
            pass
        else:
            checks.finite(table, column)
            return table
    bad = np.array([[not is_number(cell) for cell in row] for row in rows])
    cells = np.array(rows, dtype=object)
    checks.fail_first(bad, cells, column, lambda cell: f"{'an empty cell' if not cell else repr(cell)} is not a number")
    raise AssertionError("numpy and float() disagree on what a number is")  # pragma: no cover


def format_rows(table: np.ndarray, separator: str) -> str:
    """Rows of numbers with 17 significant digits (exact float64 round trip), one per line."""
    return "".join(separator.join(f"{x:.17g}" for x in row) + "\n" for row in table)
