"""Freed memory handed back to the system, where the C library keeps it.

glibc's ``malloc`` serves each thread from an arena of its own and keeps what is freed there for later
allocations: a thread that built and dropped large temporary structures (the reciprocity check's k-d trees, ~90 MB
at MERL size) leaves the process that much larger while the main thread goes on to its own peak. ``malloc_trim(0)``
returns the free pages (Dask's workers do the same: distributed's "memory trimming"). Elsewhere than glibc, nothing.
"""

import ctypes
import ctypes.util
import functools


def return_freed_memory() -> None:
    """Hand the free pages of every ``malloc`` arena back to the system (glibc ``malloc_trim(0)``; ~10 ms)."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


@functools.cache
def _malloc_trim():
    """glibc's ``malloc_trim``, or None where the C library has none (musl, macOS, Windows)."""
    name = ctypes.util.find_library("c")
    try:
        return getattr(ctypes.CDLL(name), "malloc_trim", None) if name else None
    except OSError:
        return None
