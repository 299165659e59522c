"""JAX as brdffit uses it: imported on first use, float64 inside brdffit only, numpy on the host.

``lazy.py`` (the stand-ins ``jax``, ``jnp``: commands that compute nothing never import JAX), ``precision.py`` (the
float64 context), ``arrays.py`` (numpy on the host, ``jax.numpy`` inside programs). Compiled functions and their
programs are ``brdffit/_programs``.
"""

from .arrays import first_bad as first_bad
from .arrays import namespace as namespace
from .lazy import jax as jax
from .lazy import jnp as jnp
from .lazy import jsp_special as jsp_special
from .precision import float64 as float64
