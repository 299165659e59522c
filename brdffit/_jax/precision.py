"""float64 inside brdffit only: a context, never the process-wide switch.

brdffit computes in float64 unless asked otherwise, and JAX only makes float64 arrays with
``jax_enable_x64`` on. Switching that on for the whole process would change a user's own JAX code (their
``jnp.ones(3)`` would become float64), so brdffit turns it on only around its own work: every public
function that computes with JAX runs inside :func:`float64`, and every function compiled with
``brdffit._programs.jit`` traces and runs inside it too (so a caller of a compiled function gets float64 without
asking). JAX keeps the setting per thread; a thread that brdffit starts enters it itself.
"""

import functools
from collections.abc import Callable

from .lazy import jax


def float64(function: Callable | None = None):
    """``jax_enable_x64`` on for the duration of a block (``with float64():``) or of every call of ``function``.

    The setting is JAX's own context (``jax.enable_x64``), local to the thread; outside it the caller's
    setting is untouched.
    """
    if function is None:
        return jax.enable_x64(True)

    @functools.wraps(function)
    def in_float64(*args, **kwargs):
        with jax.enable_x64(True):
            return function(*args, **kwargs)

    return in_float64
