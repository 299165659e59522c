"""JAX in float64: every module that uses JAX imports this first (``from . import _jax``).

brdffit computes in float64 unless asked otherwise (SPEC section 1), and JAX
only makes float64 arrays with ``jax_enable_x64`` on. It must be on before the
first array exists, whichever brdffit module is imported first, hence one
import line in each rather than one switch in ``__init__`` (which stays free
of imports so that ``import brdffit`` costs nothing).
"""

import jax

jax.config.update("jax_enable_x64", True)
