"""Compiled programs kept on disk across processes, so that a later run neither traces nor lowers them.

JAX's persistent compilation cache (``cache.py``) keeps XLA's executables, but JAX finds one by a key that it
computes by tracing the Python function and lowering it to StableHLO: for the shipped example's fit that was
0.7 s of a 2 s command, in every run. Here a function compiled by ``jit.jit`` is stored once per *signature*
as a serialized ``jax.export.Exported`` (its StableHLO and its argument and result trees). A later process
computes the signature from the call alone, without tracing: the function's identity (its name, and the cache
keys of what a closure closes over), the cache keys of its static arguments (``keys.py``), and the tree, shapes and
dtypes of its array arguments. It deserializes the program (a few ms) and compiles it, which the compilation cache
answers.

A stored program belongs to this brdffit version and source (every ``.py`` file of the package is hashed), this JAX
and jaxlib, this backend and device kind: a change of any of them gives new signatures, and stale files are never
read. Programs are stored only while the compilation cache is on, in its folder's ``programs/``. A call that cannot
be stored (a static argument without a cache key, an argument that is not an array, keyword arguments, a program
``jax.export`` refuses) is compiled by ``jax.jit`` as before.
"""

import hashlib
import importlib
import json
import threading
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path

import numpy as np

from .._files import atomic_path
from .._jax import jax
from .keys import key_of

#: A stored program's file: one line of JSON (the named tuples its trees hold) and the serialized program.
SUFFIX = ".jaxprogram"

_lock = threading.Lock()  # held while a program is loaded or exported, and while it is published in ``_loaded``
_MISSING = object()  # not in ``_loaded`` (None there means: cannot be stored)
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
    identity: list, jitted, args: Sequence, static_argnums: Sequence[int], compile_options: dict | None
) -> Callable | None:
    """A compiled call of the stored program for ``jitted(*args)`` (of the dynamic arguments only), or None.

    ``identity`` names the function (its module and qualified name, and the cache keys of what it closes over:
    ``jit.jit``), ``jitted`` is its ``jax.jit``, used to export it the first time. None when programs are not being
    stored or the call cannot be.
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
        program = _loaded.get(signature, _MISSING)
        if program is _MISSING:
            exported = _load_or_export(folder / f"{signature}{SUFFIX}", jitted, args, static_argnums)
            program = None if exported is None else jax.jit(exported.call, compiler_options=compile_options)
            _loaded[signature] = program
        return program


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


def _load_or_export(path: Path, jitted, args: Sequence, static_argnums: Sequence[int]):
    """The ``Exported`` stored at ``path``, or the program exported now and stored there; None if it cannot be."""
    try:
        return _read(path)
    except Exception:  # missing, cut short by a crash, written by another version: export it again
        pass
    count_trace()
    try:
        exported = jax.export.export(jitted)(*(_shape_of(arg, i, static_argnums) for i, arg in enumerate(args)))
        types = sorted(_named_tuples(exported.in_tree) | _named_tuples(exported.out_tree), key=_type_name)
        for kind in types:
            _register(kind)
        payload = exported.serialize()
    except Exception:  # jax.export refuses it (a callback, a custom call it does not know): compile it as usual
        return None
    header = json.dumps({"named_tuples": [_type_name(kind) for kind in types]}).encode()
    _write_atomically(path, header + b"\n" + bytes(payload))
    return exported


def _read(path: Path):
    header, _, payload = path.read_bytes().partition(b"\n")
    for name in json.loads(header)["named_tuples"]:
        module, _, qualified = name.partition(":")
        kind = importlib.import_module(module)
        for part in qualified.split("."):
            kind = getattr(kind, part)
        _register(kind)
    return jax.export.deserialize(bytearray(payload))


def _shape_of(arg, index: int, static_argnums: Sequence[int]):
    """A static argument as it is; the arrays of a dynamic one as ``jax.ShapeDtypeStruct``."""
    if index in static_argnums:
        return arg
    return jax.tree.map(
        lambda leaf: jax.ShapeDtypeStruct(leaf.shape, leaf.dtype, weak_type=bool(getattr(leaf, "weak_type", False))),
        arg,
    )


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


def _write_atomically(path: Path, data: bytes) -> None:
    """``data`` into ``path`` atomically (``_files.atomic_path``): a reader never sees half a program. A cache that
    cannot be written (read-only, full) stores nothing; the program is still used in this process."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as temporary:
            temporary.write_bytes(data)
    except OSError:
        pass
