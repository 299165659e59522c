"""Atomic file writes (readers never see a half-written file) and one-line errors for files that cannot be read or
written.

A write that fails (a full disk, a folder that cannot be written) raises :class:`~brdffit.errors.BrdfWriteError`, one
line that names the file; the old file is kept and no temporary is left. An interrupted command writes nothing:
the command line's signal handlers call :func:`stop_writing`, and from then on every atomic write of the process
raises ``KeyboardInterrupt`` before its rename, even where the first ``KeyboardInterrupt`` was swallowed (JAX's
``_xla_gc_callback`` prints "Exception ignored" for one raised while it runs, and the work goes on).
"""

import errno
import json
import math
import os
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .errors import BrdfInputError, BrdfWriteError


def _read_umask() -> int:
    """The process's umask (read once, at import: reading it sets it for a moment, which other threads would see)."""
    umask = os.umask(0o077)
    os.umask(umask)
    return umask


#: The largest JSON file brdffit reads (a result, a comparison, parameters: kilobytes); a bigger one is refused unread.
MAX_JSON_BYTES = 64 * 2**20

#: Permissions a plain ``open(path, "w")`` gives: 0666 less the umask (mkstemp uses 0600).
DEFAULT_MODE = 0o666 & ~_read_umask()


_stopped = threading.Event()  # set by an interrupt: no atomic write of this process completes any more
_stopped_by: list[type[BaseException]] = [KeyboardInterrupt]  # what check_not_stopped raises: the signal's exception


def stop_writing(raising: type[BaseException] = KeyboardInterrupt) -> None:
    """From now on, every atomic write of this process raises ``raising`` (the interrupt's ``KeyboardInterrupt``, a
    SIGTERM's own exception) instead of renaming its file, and so does every :func:`check_not_stopped` of long work
    (an interrupted command writes nothing and stops, even if the interrupt itself was swallowed)."""
    _stopped_by[0] = raising
    _stopped.set()


def resume_writing() -> None:
    """Undo :func:`stop_writing` (a new command starts)."""
    _stopped.clear()


def check_not_stopped() -> None:
    """Raise the stop's exception (``KeyboardInterrupt`` unless :func:`stop_writing` said another) if writes were
    stopped: called before writing anything, a file or a stream, and between the steps of long work (MCMC)."""
    if _stopped.is_set():
        raise _stopped_by[0]


def cannot_write(path: str | os.PathLike, error: OSError) -> BrdfWriteError:
    """The one-line error for ``path`` that could not be written because of ``error``."""
    reason = error.strerror or str(error) or errno.errorcode.get(error.errno or 0, "an error")
    return BrdfWriteError(f"{path}: cannot be written ({reason}); nothing written there, an old file is kept")


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path in ``path``'s folder (same suffix) to write to; renamed onto ``path`` when the block
    ends without an error, removed when it raises. The temporary file exists, empty, when the block starts.

    An operating-system error (a full disk, a folder that cannot be written) becomes
    :class:`~brdffit.errors.BrdfWriteError`, naming ``path``; after :func:`stop_writing`, ``KeyboardInterrupt``
    (the temporary removed, ``path`` untouched)."""
    path = Path(path)
    check_not_stopped()
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}")
    except OSError as error:
        raise cannot_write(path, error) from None
    os.close(handle)
    try:
        yield Path(temporary)
        check_not_stopped()
        os.chmod(temporary, DEFAULT_MODE)
        os.replace(temporary, path)
    except BaseException as error:
        Path(temporary).unlink(missing_ok=True)
        if isinstance(error, OSError) and not isinstance(error, BrdfWriteError):
            raise cannot_write(path, error) from None
        raise


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder and a rename."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8", newline="")


@contextmanager
def reading(path: str | os.PathLike, what: str) -> Iterator[None]:
    """Turn the operating system's failures to read ``path`` into one-line errors; ``what`` names the file kind."""
    try:
        yield
    except FileNotFoundError:
        raise BrdfInputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise BrdfInputError(f"{path}: is a folder, not {what}") from None
    except OSError as error:
        raise BrdfInputError(f"{path}: cannot be read ({error.strerror or error})") from None


def read_json_file(path: str | os.PathLike, what: str) -> Any:
    """The JSON in the file ``path`` (:func:`read_json_text`, :func:`parse_json`), or a one-line error naming the
    file and ``what`` it should be (``a capture file``)."""
    with reading(path, what):
        text = read_json_text(path)
    try:
        return parse_json(text)
    except ValueError as error:
        raise BrdfInputError(f"{path}: not {what} ({error})") from None


def parse_json(text: str) -> Any:
    """``text`` as JSON, strictly, as every JSON brdffit is given is read: no ``NaN`` or ``Infinity`` (not JSON) and no
    number beyond float64's range (``1e400``), nesting no deeper than Python's recursion limit (~1,000); raises
    ``ValueError`` saying what is wrong (``json.JSONDecodeError`` for bad syntax)."""

    def constant(name: str):
        raise ValueError(f"{name} is not a JSON number")

    def finite(number: str) -> float:
        value = float(number)
        if not math.isfinite(value):
            raise ValueError(f"{number} is beyond float64's range")
        return value

    try:
        return json.loads(text, parse_constant=constant, parse_float=finite)
    except RecursionError:
        raise ValueError("nested too deeply") from None


def read_json_text(path: str | os.PathLike) -> str:
    """The text of the JSON file ``path``, refused (``ValueError``) above :data:`MAX_JSON_BYTES` without reading more;
    ``OSError`` and ``UnicodeDecodeError`` as ``open`` and ``read`` raise them."""
    with open(path, encoding="utf-8") as stream:
        text = stream.read(MAX_JSON_BYTES + 1)
    if len(text) > MAX_JSON_BYTES:
        raise ValueError(f"larger than {MAX_JSON_BYTES // 2**20} MiB, which no brdffit JSON file is")
    return text
