"""Which array library a function computes with (numpy on the host, ``jax.numpy`` inside JAX programs), and the
one scan for the first bad entry of an array.

Readers, writers and other host code call the same geometry as the models do; with numpy input it
stays numpy (``jax.numpy`` would compile and dispatch a program per operation, ~0.1 s to read a
10k-row CSV), and modules that only compute on the host never import JAX.
"""

import numbers

import numpy as np

#: The host's array and number types, checked first: an abstract class's ``isinstance`` (``numbers.Number``) costs
#: five times a tuple of concrete ones, and host code asks this of every small array it computes with.
_HOST_TYPES = (np.ndarray, np.generic, float, int, complex)


def namespace(*arrays):
    """numpy when every argument is a numpy array or scalar or a Python number, else ``jax.numpy``."""
    for array in arrays:
        if not isinstance(array, _HOST_TYPES) and not isinstance(array, numbers.Number):
            import jax.numpy as jnp

            return jnp
    return np


def first_bad(bad: np.ndarray) -> tuple[int, int] | None:
    """``(row, column)`` of the first True of a mask (N,) or (N, k), row by row; None when all is well."""
    if not np.any(bad):
        return None
    bad = np.asarray(bad).reshape(len(bad), -1)
    row, column = np.unravel_index(np.argmax(bad), bad.shape)
    return int(row), int(column)
