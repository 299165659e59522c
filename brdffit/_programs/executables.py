"""Compiled executables kept beside the stored programs, so that a warm process neither lowers nor compiles them.

A stored program (``stored.py``) spares a later process the tracing, but calling it still lowered the ``Exported``
into a new module for the compilation cache to find its executable by: 0.3 s of the example's warm 1.25 s fit
(issue 32). Here the executable XLA compiled from a stored program is stored too
(``jax.experimental.serialize_executable``): a later process loads it in milliseconds and runs it.

An executable is native code for one CPU, so it is named by its program's signature, the program's own bytes (a
program exported again gets a new executable), and this machine (:func:`machine`: the CPU's features as Linux lists
them, ``XLA_FLAGS``, the backend's version); where the CPU's features cannot be read, no executable is stored. It is
stored only when every custom call it makes is one brdffit makes ready before running it (LAPACK's, whose function
table jaxlib fills on first use: an executable calling into a table not yet filled crashes the process), and only
when XLA has just compiled it: one that JAX's compilation cache gave back serializes without its machine code
(loaded, it fails with "Function … not found", and may abort the process), so an executable is stored only when JAX
says (``jax.monitoring``) that the compilation cache missed and did not hit while it was compiled. Like every
stored program it is signed with this cache's key (``signing.py``) and never loaded otherwise; one that fails to
load is said in one warning and compiled again, one that fails to run is discarded with its program (``jit.py``).
"""

import hashlib
import json
import os
import platform
import re
import threading
import types
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path

from .._jax import jax
from ..errors import InputWarning, warn
from . import signing

SUFFIX = ".jaxexe"
#: How a custom call appears in XLA's text of a compiled module.
_CUSTOM_CALL = re.compile(r'custom_call_target="([^"]+)"')


def compiled_program(
    folder: Path, name: str, key: bytes | None, exported, dynamic_args: Sequence, options: Callable[[], dict | None]
) -> Callable:
    """The compiled call of ``exported`` (a stored program named ``name``, its signature and bytes' digest) for
    arguments shaped as ``dynamic_args``: the executable stored for it in ``folder``, or compiled now with the compiler
    ``options()`` (or given back by the compilation cache) and, where XLA compiled it, stored there. Returns a
    ``jax.stages.Compiled``, or the ``jax.jit`` of the program where it does not compile here (it then fails when
    called, and ``jit.py`` discards it)."""
    in_tree = jax.tree.structure((tuple(dynamic_args), {}))
    machine_name = machine()
    path = None if machine_name is None else folder / f"{_digest(name, machine_name)}{SUFFIX}"
    if path is not None and key is not None:
        try:
            return _read(path, key, in_tree, exported.out_tree)
        except FileNotFoundError:
            pass
        except Exception as error:  # planted, flipped bytes, cut short, another jaxlib's: never run; compiled again
            signing.remove_quietly(path)
            warn(InputWarning(f"the stored executable {path} is not used ({error}); it is removed and compiled again"))
    jitted = jax.jit(_named_call(exported, name), compiler_options=options())
    _listen()
    hits, misses = _cache_events()
    try:
        compiled = jitted.lower(*shapes_of(dynamic_args)).compile()
    except Exception:
        return jitted
    hits_after, misses_after = _cache_events()
    compiled_now = hits_after == hits and misses_after > misses
    try:
        text = compiled.as_text()  # None where the backend cannot say: then its custom calls are not known
    except Exception:
        text = None
    calls = set(_CUSTOM_CALL.findall(text or ""))
    if path is not None and key is not None and compiled_now and text and calls <= _lapack_calls():
        from jax.experimental.serialize_executable import serialize

        try:
            payload = serialize(compiled)[0]
        except Exception:  # a backend that cannot serialize executables: this process runs it all the same
            return compiled
        body = json.dumps({"custom_calls": sorted(calls)}).encode() + b"\n" + payload
        signing.write_atomically(path, signing.signed_file(key, path.stem, body))
    return compiled


#: This thread's counts of JAX's compilation-cache hits and misses (``hits``, ``misses``: :func:`_listen`).
_events = threading.local()
_listening = threading.Lock()
_listener: list[Callable] = []


def _listen() -> None:
    """Count, per thread, the compilation cache's hits and misses that JAX reports (``jax.monitoring``), from now on."""
    with _listening:
        if _listener:
            return

        def count(event: str, **_) -> None:
            if event == "/jax/compilation_cache/cache_hits":
                _events.hits = getattr(_events, "hits", 0) + 1
            elif event == "/jax/compilation_cache/cache_misses":
                _events.misses = getattr(_events, "misses", 0) + 1

        jax.monitoring.register_event_listener(count)
        _listener.append(count)


def _named_call(exported, name: str):
    """``exported.call`` under the name ``brdffit_<name>``, which names the module JAX compiles. JAX's compilation
    cache keys a module by its text, name included: so a program exported again (a new brdffit, whose programs have
    new names) is compiled by XLA, not given back by the cache, and its executable can be stored."""

    def call(self, *args):
        return self.call(*args)

    call.__name__ = call.__qualname__ = f"brdffit_{name[:16]}"
    return types.MethodType(call, exported)


def _cache_events() -> tuple[int, int]:
    """How many compilation-cache hits and misses JAX has reported in this thread since :func:`_listen`."""
    return getattr(_events, "hits", 0), getattr(_events, "misses", 0)


def discard(folder: Path, name: str) -> None:
    """Remove the executable of the stored program ``name`` on this machine (it failed, or its program did)."""
    machine_name = machine()
    if machine_name is not None:
        signing.remove_quietly(folder / f"{_digest(name, machine_name)}{SUFFIX}")


def _read(path: Path, key: bytes, in_tree, out_tree):
    """The executable in ``path``, loaded, once its HMAC proves that this cache wrote it under this name; raises
    ``signing.UntrustedProgram`` otherwise (and ``FileNotFoundError`` when there is none)."""
    header, _, payload = signing.verified_body(path.read_bytes(), path.stem, key).partition(b"\n")
    calls = set(json.loads(header)["custom_calls"])
    if not calls <= _lapack_calls():
        raise signing.UntrustedProgram(f"it calls {sorted(calls - _lapack_calls())}, which brdffit cannot make ready")
    if calls:
        _ready_lapack()
    from jax.experimental.serialize_executable import deserialize_and_load

    return deserialize_and_load(payload, in_tree, out_tree)


@cache
def _lapack_calls() -> frozenset[str]:
    """The custom calls into LAPACK that this jaxlib registers, which :func:`_ready_lapack` makes ready; none (no
    executable calling any is stored) where this jaxlib does not say them in the way known here."""
    try:
        from jax._src.lax import linalg
        from jax._src.lib import lapack

        if not callable(getattr(linalg, "initialize_lapack", None)):
            return frozenset()
        return frozenset(str(name) for name in lapack._lapack.registrations())
    except Exception:
        return frozenset()


def _ready_lapack() -> None:
    """Fill jaxlib's table of LAPACK functions (from SciPy's), as lowering a LAPACK call does first."""
    from jax._src.lax import linalg

    linalg.initialize_lapack()


@cache
def machine() -> str | None:
    """What an executable compiled here depends on besides its program: the CPU's architecture, model and features
    (``/proc/cpuinfo``), ``XLA_FLAGS``, the backend's version and its number of devices. None where the features
    cannot be read: executables are then neither stored nor read."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return None
    lines = text.splitlines()
    features = next((line for line in lines if line.startswith(("flags", "Features"))), None)
    if features is None:
        return None
    model = next((line for line in lines if line.startswith(("model name", "CPU part"))), "")
    devices = jax.devices()
    client = devices[0].client
    parts = [platform.machine(), model, features, os.environ.get("XLA_FLAGS", ""), str(client.platform_version)]
    parts.append(f"{len(devices)} devices")
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def _digest(name: str, machine_name: str) -> str:
    return hashlib.sha256(f"{name}\n{machine_name}".encode()).hexdigest()[:40]


def shapes_of(tree):
    """``tree`` with each array as a ``jax.ShapeDtypeStruct`` of its shape, dtype and weak type."""
    return jax.tree.map(
        lambda leaf: jax.ShapeDtypeStruct(leaf.shape, leaf.dtype, weak_type=bool(getattr(leaf, "weak_type", False))),
        tree,
    )
