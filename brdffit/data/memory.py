"""Freed memory handed back to the system, where the C library keeps it.

glibc's ``malloc`` serves each thread from an arena of its own and keeps what is freed there for later
allocations: a thread that built and dropped large temporary structures (the reciprocity check's k-d trees, ~60 MB
at MERL size) leaves the process that much larger while the main thread goes on to its own peak. ``malloc_trim(0)``
returns the free pages (Dask's workers do the same: distributed's "memory trimming"). Elsewhere than glibc, nothing.
"""

import ctypes
import functools


def return_freed_memory() -> None:
    """Hand the free pages of every ``malloc`` arena back to the system (glibc ``malloc_trim(0)``; ~10 ms)."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


@functools.cache
def _malloc_trim():
    """glibc's ``malloc_trim``, or None where the C library has none (musl, macOS, Windows): looked up among the
    symbols the process has loaded already, which hold the C library's."""
    try:
        return getattr(ctypes.CDLL(None), "malloc_trim", None)
    except (OSError, TypeError):  # no handle to the process's own symbols (Windows)
        return None
