"""JAX's persistent compilation cache: compile a solver once per machine, not once per process.

A ``brdffit fit`` spends most of its time compiling the solver for its model
and data size; with the cache a later run loads the compiled program instead.
The command line enables it; Python users call :func:`enable_compilation_cache`.

The folder holds programs that run as the user's own code, so it is trusted only when it is the user's: a folder
(or its ``programs/``) that another user owns, or that its group or anyone may write, is refused with one warning,
and the fits compile as if the cache were off. brdffit makes its folders with mode 0700.
"""

import os
import stat
import sys
from pathlib import Path

from ..errors import InputWarning, warn

#: The environment variable that moves the cache; set it to an empty string to turn the cache off.
CACHE_VARIABLE = "BRDFFIT_CACHE_DIR"

_enabled: Path | None = None  # the folder enable_compilation_cache turned on, if any


def default_cache_dir() -> Path | None:
    """``$BRDFFIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/brdffit/jax``, else ``~/.cache/brdffit/jax``; None if off."""
    configured = os.environ.get(CACHE_VARIABLE)
    if configured is not None:
        return Path(configured) if configured else None
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "brdffit" / "jax"


def enable_compilation_cache(path: str | os.PathLike | None = None) -> Path | None:
    """Keep compiled programs in ``path`` (default :func:`default_cache_dir`) across processes.

    Every program is cached, however quickly it compiled (JAX's default keeps
    only those over a second), and brdffit's own programs are also kept before
    compiling (``programs/``, ``stored.py``), so that a later process does not
    trace them again. Returns the folder, or None when the cache is off or the
    folder cannot be created (a read-only home): fits then compile as usual.
    """
    global _enabled
    folder = Path(path) if path is not None else default_cache_dir()
    if folder is None:
        return None
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError:
        return None
    distrust = untrusted(folder) or untrusted(folder / "programs")
    if distrust is not None:
        warn(InputWarning(f"the compilation cache {distrust}: not used (its programs would run as yours)"))
        return None
    _enabled = folder
    if "jax" not in sys.modules:
        # JAX reads these when it is imported: a command that never computes never pays for importing it.
        os.environ["JAX_COMPILATION_CACHE_DIR"] = str(folder)
        os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0"
        return folder
    import jax

    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return folder


def untrusted(folder: Path) -> str | None:
    """Why ``folder`` cannot be trusted to hold programs (``"FOLDER is owned by user 1001"``), or None: it is ours and
    no one else may write it (or it does not exist yet). Links are followed."""
    try:
        status = os.stat(folder)
    except FileNotFoundError:
        return None
    except OSError as error:
        return f"{folder} cannot be read ({error.strerror or error})"
    if hasattr(os, "getuid") and status.st_uid != os.getuid():
        return f"{folder} is owned by user {status.st_uid}, not by this one ({os.getuid()})"
    if status.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"{folder} may be written by others (mode {stat.S_IMODE(status.st_mode):o}; chmod go-w to trust it)"
    return None


def programs_folder() -> Path | None:
    """Where brdffit's exported programs are kept: ``programs/`` in the enabled cache, None while it is off."""
    return None if _enabled is None else _enabled / "programs"
