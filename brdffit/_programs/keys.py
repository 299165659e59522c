"""Cache keys: what names the static arguments of a compiled program across processes.

A program stored on disk (``stored.py``) is found by a signature computed from its call alone, so a wrong key would load
a wrong program for a right-looking call and give wrong numbers with no error. Static arguments (a model, a loss, a step
count, a dtype) therefore enter by an explicit key, never by their ``repr``: a plain value (a number, a string, None, a
tuple of them) is its own key; any other object says what its programs depend on through its ``cache_key()`` method,
which the classes brdffit passes as static arguments implement (``Model`` and ``Lobe`` in ``physics/models``, ``Loss``
in ``fitting/objective/losses.py``). :func:`key_of` adds the object's class: its module and qualified name and, for a
class defined outside brdffit (a lobe of one's own), the ``cache_version`` its author sets (a string bumped whenever the
class or what it calls changes; without one its programs are never stored) and the digest of its module's source, so a
changed class never reuses a program (brdffit's own source, and its version, are in every signature:
``stored._environment``). An object whose key is None, or that has no ``cache_key``, cannot be named across processes
(the data-driven model, whose programs call back into Python; a loss of one's own): its calls are compiled in each
process and never stored.
"""

import hashlib
import inspect
from dataclasses import fields, is_dataclass
from functools import cache

#: A key: JSON (lists, strings, numbers, booleans, None).
Key = list


def key_of(value) -> Key | None:
    """The cache key of a static argument, or None when it has none (then its programs are never stored)."""
    if value is None or isinstance(value, bool | int | float | str):
        return [type(value).__name__, value]
    if isinstance(value, tuple | list):
        items = [key_of(item) for item in value]
        return None if any(item is None for item in items) else ["tuple", items]
    method = getattr(value, "cache_key", None)
    key = method() if callable(method) else None
    kind = class_key(type(value))  # type: ignore[arg-type]  # a class is hashable; mypy takes type[Any] as not
    return None if key is None or kind is None else [kind, key]


def dataclass_key(value) -> Key | None:
    """The key of a frozen dataclass (a lobe family): each field's name and :func:`key_of` its value; None when a
    field has no key, or ``value`` is not a dataclass."""
    if not is_dataclass(value):
        return None
    items = [[field.name, key_of(getattr(value, field.name))] for field in fields(value)]
    return None if any(item[1] is None for item in items) else items


@cache
def class_key(kind: type) -> Key | None:
    """A class's module and qualified name; for a class that is not brdffit's own, also the ``cache_version`` its
    author sets and the SHA-256 of its module's source. None for a class defined in a function, one outside brdffit
    without a ``cache_version`` (what its code calls elsewhere, which no digest sees, may change: its programs are
    compiled in each process), or one whose source cannot be read (a notebook cell)."""
    module, name = kind.__module__, kind.__qualname__
    if "<" in name:
        return None
    if module == "brdffit" or module.startswith("brdffit."):
        return [module, name]
    version = getattr(kind, "cache_version", None)
    if not isinstance(version, str):
        return None
    try:
        source = inspect.getsourcefile(kind)
        if source is None:  # no file to read
            return None
        with open(source, "rb") as stream:
            digest = hashlib.sha256(stream.read()).hexdigest()
    except (TypeError, OSError):
        return None
    return [module, name, version, digest]
