"""Compiled programs kept on disk across processes, so that a later run neither traces nor lowers them.

JAX's persistent compilation cache (``cache.py``) keeps XLA's executables, but JAX finds one by a key that it
computes by tracing the Python function and lowering it to StableHLO: for the shipped example's fit that was
0.7 s of a 2 s command, in every run. Here a function compiled by ``jit.jit`` is stored once per *signature*
as a serialized ``jax.export.Exported`` (its StableHLO and its argument and result trees). A later process
computes the signature from the call alone, without tracing: the function's identity (its name, and the cache
keys of what a closure closes over), the cache keys of its static arguments (``keys.py``), and the tree, shapes and
dtypes of its array arguments. It deserializes the program (a few ms) and loads the executable compiled from it
(``executables.py``), or compiles it, which the compilation cache answers.

A stored program belongs to this brdffit version and source (every ``.py`` file of the package is hashed), this JAX
and jaxlib, optimistix, equinox and lineax, this backend and device kind: a change of any of them gives new signatures,
and stale files are never read. Programs are stored only while the compilation cache is on, in its folder's
``programs/``. A call that cannot be stored (a static argument without a cache key, an argument that is not an array,
keyword arguments, a program ``jax.export`` refuses) is compiled by ``jax.jit`` as before.

The folder is untrusted input (issue 29, item 8): a program read from it runs as the user's own code. So each file
begins with an HMAC-SHA256 of its signature and its content under a key that only this cache knows (``key``, 32
random bytes, mode 0600, made by the first process that stores a program): a file this cache did not write (planted,
copied from another cache) or whose bytes changed (a flipped bit) fails the check, is never deserialized, and is
exported again and replaced, with one :class:`~brdffit.errors.InputWarning`. The named tuples a header lists are
looked up, never imported from elsewhere: a type of brdffit's own modules, or of a module already loaded. (That the
folder is the user's own, writable by no one else, ``cache.py`` checks before turning the cache on.) A signed program
that fails the first time it is compiled or run is discarded (:func:`discard`, from ``jit.py``) and exported again.
"""

import enum
import hashlib
import importlib
import json
import sys
import threading
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path
from typing import Any, Final

import numpy as np

from .._jax import jax
from ..errors import InputWarning, warn
from . import executables
from .executables import shapes_of
from .keys import key_of
from .signing import UntrustedProgram, secret, signed_file, verified_body, write_atomically

#: A stored program's file: its HMAC (hex) on one line, one line of JSON (the named tuples its trees hold), and the
#: serialized program.
SUFFIX = ".jaxprogram"

_lock = threading.Lock()  # held while a program is loaded or exported, and while it is published in ``_loaded``
_compiling: dict[str, threading.Lock] = {}  # signature → held while its program is made (other programs go on)


class _Missing(enum.Enum):
    """Not in ``_loaded`` (None there means: cannot be stored)."""

    MISSING = enum.auto()


_MISSING: Final = _Missing.MISSING
_loaded: dict[str, Callable | None] = {}  # signature → compiled call, None when it cannot be stored
_registered: set[type] = set()
_lock_count = threading.Lock()
_traced = 0  # programs traced in this process: stored programs exported, and first calls of ``jit.jit``


def traced() -> int:
    """How many programs brdffit has traced in this process so far (exported for storing, or compiled by
    ``jit.jit``): a caller that sees the count unchanged over a piece of work knows it compiled nothing new."""
    return _traced


def count_trace() -> None:
    global _traced
    with _lock_count:
        _traced += 1


def stored_program(
    identity: list,
    jitted: Callable[[], Callable],
    args: Sequence,
    static_argnums: Sequence[int],
    compile_options: Callable[[], dict | None],
    on_lowered: Callable[[], None] | None = None,
) -> Callable | None:
    """A compiled call of the stored program for ``jitted()(*args)`` (of the dynamic arguments only), or None.

    ``identity`` names the function (its module and qualified name, and the cache keys of what it closes over:
    ``jit.jit``); ``jitted()`` gives its ``jax.jit``, used to export it the first time, and ``compile_options()`` the
    options to compile it with: both asked for only when the program is exported or compiled (finding the options
    compiles a program, ``jit.known_options``). None when programs are not being stored or the call cannot be.
    ``on_lowered()`` is called once the program is exported or read, before it is compiled (``jit.precompile_with``).
    """
    from .cache import programs_folder

    folder = programs_folder()
    if folder is None:
        return None
    signature = _signature(identity, args, static_argnums)
    if signature is None:
        return None
    # Double-checked: a program already published is read without waiting (a dict lookup is atomic); only what
    # is final is ever published, under the lock, so a reader never sees a half-made entry (issue 29: the raw
    # ``Exported``, published before its compiled call replaced it, reached other threads as "not callable").
    program = _loaded.get(signature, _MISSING)
    if program is not _MISSING:
        return program
    with _lock:
        making = _compiling.setdefault(signature, threading.Lock())
    with making:
        program = _loaded.get(signature, _MISSING)
        if program is _MISSING:
            with _lock:
                exported, name = _load_or_export(folder, signature, jitted, args, static_argnums)
            if exported is not None:
                if on_lowered is not None:
                    on_lowered()
                dynamic = dynamic_arguments(args, static_argnums)
                program = executables.compiled_program(folder, name, secret(folder), exported, dynamic, compile_options)
            else:
                program = None
            with _lock:
                _loaded[signature] = program
        return program


def forget_loaded() -> None:
    """Forget the programs loaded in this process, so that their executables are freed (with ``jax.clear_caches``,
    which frees what ``jax.jit`` holds); a later call loads its program again."""
    with _lock:
        _loaded.clear()


def discard(identity: list, args: Sequence, static_argnums: Sequence[int], error: Exception) -> None:
    """Forget the stored program for ``identity`` called with ``args``, which failed to compile or run (``error``):
    its file is removed and the next call exports it again; said in one :class:`~brdffit.errors.InputWarning`."""
    from .cache import programs_folder

    signature = _signature(identity, args, static_argnums)
    folder = programs_folder()
    if signature is None or folder is None:
        return
    path = folder / f"{signature}{SUFFIX}"
    with _lock:
        _loaded.pop(signature, None)
        try:
            executables.discard(folder, _program_name(signature, path.read_bytes()))
        except OSError:
            pass
        path.unlink(missing_ok=True)
    reason = (str(error).strip().splitlines() or [type(error).__name__])[0]
    warn(InputWarning(f"the stored program {path} failed ({reason}); it is compiled again and replaced"))


def dynamic_arguments(args: Sequence, static_argnums: Sequence[int]) -> tuple:
    """``args`` without the static ones: what a stored program takes."""
    return tuple(arg for index, arg in enumerate(args) if index not in static_argnums)


def static_arguments(args: Sequence, static_argnums: Sequence[int]) -> tuple:
    """The static ones of ``args`` (models, losses, counts): part of a program's identity, not its inputs."""
    return tuple(arg for index, arg in enumerate(args) if index in static_argnums)


def array_description(leaf) -> tuple:
    """What a compiled program depends on of an array argument: its shape, dtype and weak type (an array and a
    ``jax.ShapeDtypeStruct`` of its shape are described alike)."""
    return (
        getattr(leaf, "shape", None),
        str(getattr(leaf, "dtype", type(leaf))),
        bool(getattr(leaf, "weak_type", False)),
    )


def _signature(identity: list, args: Sequence, static_argnums: Sequence[int]) -> str | None:
    """The hex digest that names the program of the function ``identity`` names, called with ``args``; None if the
    call cannot be stored (a static argument without a cache key, an argument that is not an array)."""
    statics = [key_of(arg) for arg in static_arguments(args, static_argnums)]
    if any(key is None for key in statics):
        return None
    leaves, tree = jax.tree.flatten(dynamic_arguments(args, static_argnums))
    described = []
    for leaf in leaves:
        if not isinstance(leaf, np.ndarray | jax.Array | jax.ShapeDtypeStruct) or isinstance(leaf, jax.core.Tracer):
            return None
        described.append(array_description(leaf))
    text = json.dumps([_environment(), identity, statics, str(tree), repr(described)])
    return hashlib.sha256(text.encode()).hexdigest()[:40]


@cache
def _environment() -> list[str]:
    """What a stored program depends on besides its signature: brdffit's version and source, JAX, the libraries whose
    code its programs hold (optimistix's loop, equinox, lineax), the backend."""
    from importlib.metadata import version

    import jaxlib

    from .._version import __version__

    package = Path(__file__).parent.parent  # the whole brdffit package
    source = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        source.update(str(path.relative_to(package)).encode())
        source.update(path.read_bytes())
    device = jax.devices()[0]
    libraries = [f"{name} {version(name)}" for name in ("optimistix", "equinox", "lineax")]
    return [
        __version__,
        source.hexdigest(),
        jax.__version__,
        jaxlib.__version__,
        *libraries,
        device.platform,
        device.device_kind,
    ]


def _load_or_export(
    folder: Path, signature: str, jitted, args: Sequence, static_argnums: Sequence[int]
) -> tuple[Any, str]:
    """The ``Exported`` stored for ``signature`` in ``folder``, or the program exported now and stored there (None if
    it cannot be), and its name (:func:`_program_name`). A file that fails the checks (:func:`_read`) is said in one
    warning and replaced."""
    path = folder / f"{signature}{SUFFIX}"
    key = secret(folder)
    try:
        content = path.read_bytes()
        return _read(content, signature, key), _program_name(signature, content)
    except FileNotFoundError:
        pass
    except Exception as error:  # planted, flipped bytes, cut short by a crash: never run; exported again
        warn(
            InputWarning(
                f"the stored program {path} is not used ({error}); it is compiled again and replaced"
                " (the compilation cache is untrusted input: only the programs it signed run)"
            )
        )
    count_trace()
    try:
        exported = jax.export.export(jitted())(*(_shape_of(arg, i, static_argnums) for i, arg in enumerate(args)))
        types = sorted(_named_tuples(exported.in_tree) | _named_tuples(exported.out_tree), key=_type_name)
        for kind in types:
            _register(kind)
        payload = exported.serialize()
    except Exception:  # jax.export refuses it (a callback, a custom call it does not know): compile it as usual
        return None, signature
    body = json.dumps({"named_tuples": [_type_name(kind) for kind in types]}).encode() + b"\n" + bytes(payload)
    content = b"" if key is None else signed_file(key, signature, body)
    if key is not None:  # no key (a cache that cannot be written): nothing is stored
        write_atomically(path, content)
    return exported, _program_name(signature, content)


def _program_name(signature: str, content: bytes) -> str:
    """A stored program's name for its executables (``executables.py``): its signature and its file's bytes, so
    that a program exported again, or changed, never runs an executable compiled from another."""
    return hashlib.sha256(signature.encode() + b"\n" + content).hexdigest()


def _read(content: bytes, signature: str, key: bytes | None):
    """The ``Exported`` in a program file's ``content``, once its HMAC proves that this cache wrote it for
    ``signature``; raises :class:`UntrustedProgram` otherwise."""
    header, _, payload = verified_body(content, signature, key).partition(b"\n")
    for name in json.loads(header)["named_tuples"]:
        _register(_named_tuple(name))
    return jax.export.deserialize(bytearray(payload))


def _named_tuple(name: str) -> type:
    """The named tuple ``module:qualified.name`` a stored program's trees hold. Only brdffit's own modules are imported
    for it; any other must be loaded already (a file never makes brdffit import anything else)."""
    module_name, _, qualified = name.partition(":")
    if module_name == "brdffit" or module_name.startswith("brdffit."):
        module = importlib.import_module(module_name)
    elif module_name in sys.modules:
        module = sys.modules[module_name]
    else:
        raise UntrustedProgram(f"it names {name!r}, of a module that is not loaded")
    kind: object = module
    for part in qualified.split("."):
        kind = getattr(kind, part, None)
    if not (isinstance(kind, type) and issubclass(kind, tuple) and hasattr(kind, "_fields")):
        raise UntrustedProgram(f"it names {name!r}, which is not a named tuple")
    return kind


def _shape_of(arg, index: int, static_argnums: Sequence[int]):
    """A static argument as it is; the arrays of a dynamic one as ``jax.ShapeDtypeStruct``."""
    return arg if index in static_argnums else shapes_of(arg)


def _named_tuples(tree) -> set[type]:
    """Every named-tuple node type of a tree structure (``jax.export`` serializes them once registered)."""
    found = set()
    data = tree.node_data()
    if data is not None and issubclass(data[0], tuple) and hasattr(data[0], "_fields"):
        found.add(data[0])
    for child in tree.children():
        found |= _named_tuples(child)
    return found


def _type_name(kind: type) -> str:
    return f"{kind.__module__}:{kind.__qualname__}"


def _register(kind: type) -> None:
    if kind not in _registered:
        jax.export.register_namedtuple_serialization(kind, serialized_name=_type_name(kind))
        _registered.add(kind)
