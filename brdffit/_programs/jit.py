"""One ``jit`` for brdffit's compiled functions: float64, the CPU compiler options that suit them, stored programs.

Every function brdffit compiles goes through :func:`jit`: it traces and runs in float64 (``_jax.precision``),
compiles with :data:`CPU_COMPILER_OPTIONS` on a CPU, runs the program stored for its signature while the compilation
cache is on (``stored.py``), and lets only one thread compile each signature (``first_calls.py``).
:func:`built_once` caches the builders of compiled functions (a solver for a model and a loss) across threads.
"""

import functools
import threading
import weakref
from collections.abc import Callable
from typing import Any, Protocol, cast

from .._jax import float64, jax
from . import stored
from .first_calls import FirstCalls
from .keys import key_of

#: XLA options for the CPU backend, measured on the MERL-size Cook-Torrance solver (2-core Xeon, jax 0.10.2):
#: XLA's newer CPU "fusion emitters" (the default) compile it in 1.3–1.4 s, the classic loop emitters in 0.5–0.6 s,
#: and the classic code runs faster. Turning YNNPACK's fusions (of the pass's reductions and dots) off adds ~0.2 s
#: of compile time and saves ~25% of every pass (5 passes: 0.70 s → 0.55 s). XNNPACK rewrites only add compile time.
CPU_COMPILER_OPTIONS = {
    "xla_cpu_use_fusion_emitters": False,
    "xla_cpu_use_xnnpack": False,
    "xla_cpu_experimental_ynn_fusion_type": "",
}
#: :data:`CPU_COMPILER_OPTIONS` with XLA's fusion emitters on, for the programs of a model that says it is compiled
#: better so (``Lobe.fusion_emitters``). The classic emitters compile the forward-mode basis of a whole-lobe material
#: with per-channel colours (glTF's, Mitsuba's ``roughplastic``) into code 2.1–3.7 times slower: a Levenberg-Marquardt
#: step of glTF's model on 155,520 pairs took 142 ms so and 39 ms with the emitters (``roughplastic`` 102 and 48 ms).
#: The others keep the classic ones: Ward 4.6 and 4.8 ms, Cook-Torrance 4.7 and 5.3, an anisotropic conductor 60 and
#: 64, principled's whole Jacobian 138 and 373. Compiling takes 0.5–1.2 s longer a program.
EMITTER_COMPILER_OPTIONS = CPU_COMPILER_OPTIONS | {"xla_cpu_use_fusion_emitters": True}
#: Added for a program compiled unoptimised (``jit(..., optimised=False)``): LLVM's passes skipped, for a small
#: program whose run is short (a single fit's caveat screens, ``caveats._screens_program``): XLA compiles the albedo
#: screen's ~300 operations in 0.05 s instead of 0.15–0.19 s.
UNOPTIMISED = {"xla_backend_optimization_level": 0}


class Compiled(Protocol):
    """What :func:`jit` returns: the function, and its ``precompile``, ``precompile_with`` and ``is_compiled``."""

    precompile: Callable[..., None]
    precompile_with: Callable[..., None]
    is_compiled: Callable[..., bool]

    def __call__(self, *args: Any, **kwargs: Any) -> Any: ...


def built_once(builder: Callable) -> Callable:
    """``functools.cache`` for a function that builds a compiled function (a solver for a model and loss), safe
    across threads: threads that ask for the same one at once (``fit_batch``'s batches) get one, where two would
    be two compiled functions, each tracing its programs."""
    cached = functools.cache(builder)
    lock = threading.Lock()

    @functools.wraps(builder)
    def once(*args, **kwargs):
        with lock:
            return cached(*args, **kwargs)

    return once


@functools.cache
def compiler_options(fusion_emitters: bool = False, optimised: bool = True) -> dict | None:
    """:data:`CPU_COMPILER_OPTIONS` (:data:`EMITTER_COMPILER_OPTIONS` with ``fusion_emitters``, and
    :data:`UNOPTIMISED` unless ``optimised``) that the running XLA knows (:func:`known_options`) when JAX's default
    backend is the CPU, else None (XLA's defaults)."""
    if jax.default_backend() != "cpu":
        return None
    options = EMITTER_COMPILER_OPTIONS if fusion_emitters else CPU_COMPILER_OPTIONS
    return known_options(options if optimised else options | UNOPTIMISED)


def known_options(options: dict) -> dict:
    """``options`` less those the running XLA does not know: they are private flags, which XLA adds, renames and
    removes between releases (jax 0.8's refuses ``xla_cpu_experimental_ynn_fusion_type``: "No such compile option").
    Found by compiling a one-operation program with them (~20 ms, once per process for each set of options), each on
    its own where all together are refused; an option that is not known only costs its speed-up."""

    def accepted(chosen: dict) -> bool:
        try:
            jax.jit(lambda x: x + 1.0).lower(1.0).compile(compiler_options=chosen)
        except Exception as error:  # jax.errors.JaxRuntimeError (XlaRuntimeError in older jaxlibs)
            if "compile option" not in str(error):
                raise
            return False
        return True

    if accepted(options):
        return dict(options)
    return {name: value for name, value in options.items() if accepted({name: value})}


def jit(fun=None, *, name: str | None = None, closes_over: tuple = (), optimised: bool = True, **jit_arguments):
    """``jax.jit`` in :func:`float64` with :func:`compiler_options`, chosen at the first call (importing does no work):
    with XLA's fusion emitters where a model among the static arguments and the values it closes over says so (its
    ``fusion_emitters``: :data:`EMITTER_COMPILER_OPTIONS`); ``optimised=False``: with :data:`UNOPTIMISED` too, for a
    small program that runs briefly.

    Usable as ``@jit``, ``@jit(static_argnums=0)`` or ``jit(f, static_argnums=0)``. JAX takes compiler
    options only for a program compiled on its own, so inside a traced function (``jit`` or ``vmap`` of a
    caller) the plain ``jax.jit`` is used and the outer program's options apply.

    While the compilation cache is on, a call at the top level runs the program stored for its signature
    (``stored.py``): a later process then neither traces nor lowers it. A module-level function is stored
    under its module and name, a ``functools.partial`` of one under that name and the cache keys of its bound
    arguments (``keys.py``); a closure only under the ``name`` its caller gives together with every value it
    closes over (``closes_over``, each named by its cache key).
    """
    if fun is None:
        return functools.partial(jit, name=name, closes_over=closes_over, optimised=optimised, **jit_arguments)
    if name is None and isinstance(fun, functools.partial) and _module_level(fun.func):
        name = f"{fun.func.__module__}.{fun.func.__qualname__}"
        closes_over = (*fun.args, *sorted(fun.keywords.items()))
    elif name is None and _module_level(fun):
        name = f"{fun.__module__}.{fun.__qualname__}"
    identity = None if name is None else [name, key_of(tuple(closes_over))]
    if identity is not None and identity[1] is None:  # something it closes over has no key: never stored
        identity = None
    static_argnums = jit_arguments.get("static_argnums", ())
    static_argnums = (static_argnums,) if isinstance(static_argnums, int) else tuple(static_argnums)

    @functools.cache
    def plain():
        return jax.jit(fun, **jit_arguments)

    @functools.cache
    def top_level(emitters: bool):
        return jax.jit(fun, compiler_options=compiler_options(emitters, optimised), **jit_arguments)

    def emitters_for(args) -> bool:
        """Whether the call's program compiles with XLA's fusion emitters (the docstring); a value bound by keyword
        is a ``(name, value)`` pair of ``closes_over``."""
        statics = (*closes_over, *stored.static_arguments(args, static_argnums))
        values = [item for value in statics for item in (value if isinstance(value, tuple) else (value,))]
        return any(getattr(value, "fusion_emitters", False) is True for value in values)

    def stored_for(args, kwargs, on_lowered=None):
        """The stored program for a top-level call, or None (``stored.stored_program``, which calls ``on_lowered()``
        between exporting the program, or reading its export, and compiling it)."""
        if identity is None or kwargs:
            return None
        emitters = emitters_for(args)
        jitted, options = (lambda: top_level(emitters)), (lambda: compiler_options(emitters, optimised))
        return stored.stored_program(stored_identity(emitters), jitted, args, static_argnums, options, on_lowered)

    def stored_identity(emitters: bool) -> list:
        """What names a call's stored program: the function's identity and the options it compiles with."""
        assert identity is not None  # a stored program is only ever found for a function with an identity
        return [*identity, {"fusion_emitters": emitters} | ({} if optimised else {"optimised": False})]

    def with_stored(args, kwargs, key, use, otherwise, runs: bool = True, on_lowered=None):
        """``use(program)`` with the stored program for the call, or ``otherwise()`` when there is none. A stored
        program that fails the first time it is compiled or run in this process (a file this cache signed, but that
        this JAX cannot read) is discarded with one warning (``stored.discard``) and exported again. ``runs``: whether
        ``use`` runs the program (else it only compiles it, which proves nothing of an executable loaded ready).
        ``on_lowered``: called once a program is exported or its export read, before it is compiled (``stored_for``)."""
        program = stored_for(args, kwargs, on_lowered)
        if program is None:
            return otherwise()
        if program in proven:
            return use(program)
        try:
            result = use(program)
        except Exception as error:
            stored.discard(stored_identity(emitters_for(args)), args, static_argnums, error)
            program = stored_for(args, kwargs)
            if program is None:
                return otherwise()
            result = use(program)
        if runs or not isinstance(program, jax.stages.Compiled):
            proven.add(program)
        return result

    first_calls = FirstCalls()
    compiled: set = set()  # the call keys whose programs have run or been compiled in this process
    # the stored programs that have run or compiled in this process: no failure to expect (held weakly: forgetting
    # the loaded programs, ``stored.forget_loaded``, frees their executables)
    proven: weakref.WeakSet = weakref.WeakSet()

    @functools.wraps(fun)
    def call(*args, **kwargs):
        with float64():
            if any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree.leaves((args, kwargs))):
                return plain()(*args, **kwargs)
            key = _call_key(args, kwargs, static_argnums)
            result = with_stored(
                args,
                kwargs,
                key,
                lambda program: program(*stored.dynamic_arguments(args, static_argnums)),
                lambda: first_calls.run(key, lambda: top_level(emitters_for(args))(*args, **kwargs)),
            )
            compiled.add(key)
            return result

    def precompile(*args, **kwargs) -> None:
        """Trace and compile for the shapes of ``args`` (arrays or ``jax.ShapeDtypeStruct``), without running.

        A later call with arrays of those shapes reuses JAX's caches; so this
        can run in another thread while the caller does other work.
        """
        precompile_with(None, *args, **kwargs)

    def precompile_with(on_lowered: Callable[[], None] | None, *args, **kwargs) -> None:
        """:func:`precompile`, calling ``on_lowered()`` on this thread once the program is traced and lowered (or its
        stored export read), just before XLA compiles it; not at all where it is compiled in this process already.
        Work that holds the GIL (another program's tracing) started there runs beside the compilation, which
        releases it, instead of beside the tracing, which it would slow as much as it takes (``single/stacked.py``).
        """
        with float64():
            key = _call_key(args, kwargs, static_argnums)
            if key in compiled:
                return
            with_stored(
                args,
                kwargs,
                key,
                lambda program: _compile(program, stored.dynamic_arguments(args, static_argnums)),
                lambda: first_calls.run(
                    key, lambda: _compile_lowered(top_level(emitters_for(args)).lower(*args, **kwargs), on_lowered)
                ),
                runs=False,
                on_lowered=on_lowered,
            )
            compiled.add(key)

    def is_compiled(*args, **kwargs) -> bool:
        """Whether a call with ``args`` of these shapes (arrays or ``jax.ShapeDtypeStruct``) has run or been
        precompiled in this process: then it compiles nothing."""
        return _call_key(args, kwargs, static_argnums) in compiled

    compiled_call = cast(Compiled, call)
    compiled_call.precompile = precompile
    compiled_call.precompile_with = precompile_with
    compiled_call.is_compiled = is_compiled
    return compiled_call


def _module_level(function) -> bool:
    """Whether ``function`` is defined at the top of a module (not a lambda, a closure or a partial)."""
    return "<" not in getattr(function, "__qualname__", "<")


def _call_key(args: tuple, kwargs: dict, static_argnums: tuple[int, ...]) -> tuple:
    """What a call's compiled program depends on: its static arguments, its tree, each array's shape and dtype (an
    array and a ``jax.ShapeDtypeStruct`` of its shape give the same key)."""
    leaves, tree = jax.tree.flatten((stored.dynamic_arguments(args, static_argnums), kwargs))
    statics = stored.static_arguments(args, static_argnums)
    return statics, tree, tuple(stored.array_description(leaf) for leaf in leaves)


def _compile_lowered(program, on_lowered: Callable[[], None] | None) -> None:
    """Compile a lowered ``program`` (``jax.stages.Lowered``), calling ``on_lowered()`` first (``precompile_with``)."""
    if on_lowered is not None:
        on_lowered()
    program.compile()


def _compile(program, dynamic_args) -> None:
    """Compile a stored program for ``dynamic_args`` unless it is compiled already (an executable, loaded or made)."""
    if not isinstance(program, jax.stages.Compiled):
        program.lower(*dynamic_args).compile()
