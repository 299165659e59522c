"""JAX, imported on first use: ``from .._jax import jax, jnp``.

Importing JAX costs 0.4–1 s. The models, their parameters and domains, and every reader and writer are plain
Python and numpy until something is computed, so the commands that only list, read or convert (``brdffit
models``, ``info``, ``convert``, ``--help``) need none of it. The physics modules name JAX through these stand-ins;
the first attribute looked up imports the real module, and from then on every lookup finds the real module's
names directly (they are copied into the stand-in).
"""

import importlib
import types


class LazyModule(types.ModuleType):
    """A module imported at its first attribute lookup, then the module itself in all but identity."""

    def __init__(self, name: str):
        super().__init__(name)
        self.__dict__["_lazy_name"] = name

    def __getattr__(self, attribute: str):
        module = importlib.import_module(self.__dict__["_lazy_name"])
        self.__dict__.update(module.__dict__)  # later lookups do not come here
        return getattr(module, attribute)


jax = LazyModule("jax")
jnp = LazyModule("jax.numpy")
jsp_special = LazyModule("jax.scipy.special")
