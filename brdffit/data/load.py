"""Readers and writers of the measurement formats beyond the CSV samples file (SPEC section 4).

=========  ==========================  =====================================================
format     files                       module
=========  ==========================  =====================================================
csv        ``.csv`` (SPEC section 4)   ``brdffit/samples.py``
merl       ``.binary``                 ``merl.py`` (Matusik et al. 2003), read and tabulate
alta       ``.dat`` (``#PARAM_IN``)    ``alta.py`` (ALTA, Belcour et al.)
astm       ``.astm``, ``.txt``         ``astm.py`` (ASTM E1392, Cornell's measurements)
=========  ==========================  =====================================================

The format comes from ``--format`` or, by default, from the file: its
extension, then its first line (``#`` headers are ALTA's, ``NUM_POINTS`` or
``VARS`` lines ASTM's). Spectral value columns (named by wavelength in nm) can
be converted to XYZ or linear sRGB on loading (``spectral.py``).
"""

from pathlib import Path

from ..errors import BrdfInputError

FORMATS = ("csv", "merl", "alta", "astm")
EXTENSIONS = {".csv": "csv", ".binary": "merl", ".dat": "alta", ".astm": "astm"}
#: The format each writable extension gets from ``brdffit convert``.
WRITABLE = {".csv": "csv", ".dat": "alta", ".astm": "astm", ".txt": "astm", ".binary": "merl"}


def detect_format(path: Path, format: str | None = None) -> str:
    """``format`` when given (checked), else the format of ``path`` from its extension and first line."""
    if format is not None:
        if format not in FORMATS:
            raise BrdfInputError(f"--format {format!r} is not allowed; choose one of: {', '.join(FORMATS)}")
        return format
    by_extension = EXTENSIONS.get(path.suffix.lower())
    if by_extension in ("csv", "merl", "astm"):
        return by_extension
    head = _first_lines(path)
    if by_extension == "alta" or any(line.startswith("#") for line in head[:1]):
        if any(line.upper().startswith(("#DIM", "#PARAM_IN")) for line in head):
            return "alta"
    if any(line.upper().startswith(("NUM_POINTS", "VARS")) for line in head):
        return "astm"
    if by_extension == "alta":
        return "alta"  # the ALTA reader says what is missing
    return "csv"


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
