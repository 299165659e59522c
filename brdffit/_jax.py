"""JAX as brdffit uses it: float64, and one ``jit`` with the compiler options that suit these programs.

brdffit computes in float64 unless asked otherwise (SPEC section 1), and JAX
only makes float64 arrays with ``jax_enable_x64`` on. It must be on before the
first array exists, whichever brdffit module is imported first, hence one
import line in each rather than one switch in ``__init__`` (which stays free
of imports so that ``import brdffit`` costs nothing).
"""

import functools

import jax

jax.config.update("jax_enable_x64", True)

#: XLA options for the CPU backend, measured on the MERL-size Cook-Torrance solver (2-core Xeon, jax 0.10.2):
#: XLA's newer CPU "fusion emitters" (the default) compile it in 1.3–1.4 s, the classic loop emitters in 0.5–0.6 s,
#: and the classic code runs faster. Turning YNNPACK's fusions (of the pass's reductions and dots) off adds ~0.2 s
#: of compile time and saves ~25% of every pass (5 passes: 0.70 s → 0.55 s). XNNPACK rewrites only add compile time.
CPU_COMPILER_OPTIONS = {
    "xla_cpu_use_fusion_emitters": False,
    "xla_cpu_use_xnnpack": False,
    "xla_cpu_experimental_ynn_fusion_type": "",
}


@functools.cache
def compiler_options() -> dict | None:
    """:data:`CPU_COMPILER_OPTIONS` when JAX's default backend is the CPU, else None (XLA's defaults)."""
    return CPU_COMPILER_OPTIONS if jax.default_backend() == "cpu" else None


def jit(fun=None, **jit_arguments):
    """``jax.jit`` with :func:`compiler_options`, chosen at the first call so that importing does no work.

    Usable as ``@jit``, ``@jit(static_argnums=0)`` or ``jit(f, static_argnums=0)``. JAX takes compiler
    options only for a program compiled on its own, so inside a traced function (``jit`` or ``vmap`` of a
    caller) the plain ``jax.jit`` is used and the outer program's options apply.
    """
    if fun is None:
        return functools.partial(jit, **jit_arguments)
    plain = jax.jit(fun, **jit_arguments)

    @functools.cache
    def top_level():
        return jax.jit(fun, compiler_options=compiler_options(), **jit_arguments)

    @functools.wraps(fun)
    def call(*args, **kwargs):
        if any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree.leaves((args, kwargs))):
            return plain(*args, **kwargs)
        return top_level()(*args, **kwargs)

    def precompile(*args, **kwargs) -> None:
        """Trace and compile for the shapes of ``args`` (arrays or ``jax.ShapeDtypeStruct``), without running.

        A later call with arrays of those shapes reuses JAX's caches; so this
        can run in another thread while the caller does other work.
        """
        top_level().lower(*args, **kwargs).compile()

    call.precompile = precompile
    return call
