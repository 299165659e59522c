"""What a stored file must carry to be read: the cache's secret key, and the HMAC-SHA256 of each file under it.

The folder of stored programs (``stored.py``), executables (``executables.py``) and pairs (``data/stored_pairs.py``)
is untrusted input (issue 29, item 8): each file begins with an HMAC-SHA256 of its name and content under a key that
only this cache knows (:data:`KEY_FILE`, 32 random bytes, mode 0600, made by the first process that stores one):
:func:`signed_file` writes it, :func:`verified_body` checks it. A file that fails the check is never deserialized,
never run (:class:`UntrustedProgram`). Files are written atomically, so a reader never sees half of one.
"""

import hashlib
import hmac
import os
import secrets
import tempfile
import threading
from pathlib import Path

from .._files import atomic_path

#: The file in ``programs/`` holding the cache's secret key (32 random bytes), which signs every program it stores.
KEY_FILE = "key"
KEY_BYTES = 32


class UntrustedProgram(Exception):
    """A stored program that is not run: not signed by this cache, changed since, or naming a type it may not."""


def signed(key: bytes, signature: str, body: bytes) -> bytes:
    """The HMAC-SHA256 (hex) of a program's ``body`` stored for ``signature`` (a file moved to another name fails)."""
    return hmac.new(key, signature.encode() + b"\n" + body, hashlib.sha256).hexdigest().encode()


def signed_file(key: bytes, name: str, body: bytes) -> bytes:
    """A stored file's content: the HMAC of ``body`` under ``name`` (:func:`signed`) on one line, then ``body``."""
    return signed(key, name, body) + b"\n" + body


def verified_body(content: bytes, name: str, key: bytes | None) -> bytes:
    """The body of a stored file's ``content`` (:func:`signed_file`), once its HMAC proves that this cache (``key``)
    wrote it under ``name``; raises :class:`UntrustedProgram` otherwise."""
    mac, _, body = content.partition(b"\n")
    if key is None or not hmac.compare_digest(mac, signed(key, name, body)):
        raise UntrustedProgram("not signed by this cache: written elsewhere, or changed since")
    return body


def remove_quietly(path: Path) -> None:
    """Remove a stored file if it can be (a cache that cannot be written keeps it; it is never read unless signed)."""
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass


def secret(folder: Path) -> bytes | None:
    """This cache's key (``folder/key``), made now if there is none; None if it can be neither read nor made."""
    path = folder / KEY_FILE
    with _key_lock:
        if path not in _keys:
            _keys[path] = _read_or_make_key(path)
        return _keys[path]


_key_lock = threading.Lock()
_keys: dict[Path, bytes | None] = {}


def _read_or_make_key(path: Path) -> bytes | None:
    try:
        key = path.read_bytes()
        if len(key) == KEY_BYTES:
            return key
    except FileNotFoundError:
        pass
    except OSError:
        return None
    # None yet (or not a key): 32 random bytes, mode 0600 (mkstemp's), published by a link, which fails if another
    # process published its key first (then that one is everyone's)
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=".key.")
        try:
            with os.fdopen(handle, "wb") as stream:
                stream.write(secrets.token_bytes(KEY_BYTES))
            if path.exists():  # a key of the wrong length: replaced
                os.replace(temporary, path)
            else:
                try:
                    os.link(temporary, path)
                except FileExistsError:
                    pass
        finally:
            Path(temporary).unlink(missing_ok=True)
        key = path.read_bytes()
    except OSError:
        return None
    return key if len(key) == KEY_BYTES else None


def write_atomically(path: Path, data: bytes) -> None:
    """``data`` into ``path`` atomically (``_files.atomic_path``): a reader never sees half a program. A cache that
    cannot be written (read-only, full) stores nothing; the program is still used in this process."""
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        with atomic_path(path) as temporary:
            temporary.write_bytes(data)
    except OSError:
        pass
