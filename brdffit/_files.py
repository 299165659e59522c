"""Atomic file writes (readers never see a half-written file) and one-line errors for files that cannot be read."""

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .errors import BrdfInputError


def _read_umask() -> int:
    """The process's umask (read once, at import: reading it sets it for a moment, which other threads would see)."""
    umask = os.umask(0o077)
    os.umask(umask)
    return umask


#: Permissions a plain ``open(path, "w")`` gives: 0666 less the umask (mkstemp uses 0600).
DEFAULT_MODE = 0o666 & ~_read_umask()


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path in ``path``'s folder (same suffix) to write to; renamed onto ``path`` when the block
    ends without an error, removed when it raises. The temporary file exists, empty, when the block starts."""
    path = Path(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}")
    os.close(handle)
    try:
        yield Path(temporary)
        os.chmod(temporary, DEFAULT_MODE)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
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
