"""Compiled programs: brdffit's one ``jit``, the first call of a signature, programs and executables stored across
processes, and the cache folder they live in.

``jit.py`` (:func:`jit`, :func:`built_once`, the CPU compiler options), ``first_calls.py`` (one thread compiles a
signature, the others wait), ``stored.py`` (programs kept on disk with ``jax.export``), ``executables.py`` (the
executables XLA compiled from them), ``signing.py`` (the cache's key; only files it signed are read), ``cache.py``
(JAX's persistent compilation cache and its folder; :func:`brdffit.enable_compilation_cache`).
"""

from .jit import built_once as built_once
from .jit import jit as jit
