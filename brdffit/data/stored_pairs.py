"""The reciprocal pairs of large files, kept in the compilation cache's folder so that a machine pairs a geometry once.

Pairing a MERL-size file's directions (``reciprocity.py``) takes ~0.3 s, half of a warm MERL-size fit, and
depends on the directions alone: every MERL table has the same 1,458,000, and a user fits one file with several
models. So pairings of at least :data:`STORED_FROM` samples are kept in ``programs/`` of the enabled cache
(``brdffit.enable_compilation_cache``; the command line's default), one ``.pairs`` file each, named by a digest of
the directions (``reciprocity._geometry_key``), the kind of pairing and this module's and ``reciprocity.py``'s
source. The folder is untrusted input: like a stored program, a file is read only when its HMAC proves that this
cache wrote it under that name (``_programs/signing.py``), and its indices must lie within the samples; anything
else is said in one warning and paired again.
"""

import hashlib
import io
from functools import cache
from pathlib import Path

import numpy as np

from .._programs import cache as compilation_cache
from .._programs import signing
from ..errors import InputWarning, warn

SUFFIX = ".pairs"
#: Pairings of fewer samples are not stored: they take milliseconds (500 samples: ~3 ms), less than a file.
STORED_FROM = 2**17


def stored_pairs(geometry: tuple, general: bool) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The pairs stored for ``geometry`` (``(digest, n_samples)``) and kind, or None (none stored, the cache off, or
    a file not signed by this cache or not of these samples: then also one warning, and the file removed)."""
    path, key = _place(geometry, general)
    if path is None or key is None:
        return None
    try:
        content = path.read_bytes()
    except OSError:
        return None
    try:
        body = signing.verified_body(content, path.stem, key)
        with np.load(io.BytesIO(body), allow_pickle=False) as arrays:
            first, second, within = arrays["first"], arrays["second"], float(arrays["within"])
        n_samples = geometry[1]
        for indices in (first, second):
            if indices.dtype != np.int64 or indices.ndim != 1 or len(indices) != len(first):
                raise ValueError("its indices are not two lists of one length")
            if len(indices) and (indices.min() < 0 or indices.max() >= n_samples):
                raise ValueError(f"its indices lie outside the {n_samples} samples")
    except Exception as error:
        signing.remove_quietly(path)
        warn(InputWarning(f"the stored pairs {path} are not used ({error}); they are looked up again"))
        return None
    return first, second, within


def store_pairs(geometry: tuple, general: bool, pairs: tuple[np.ndarray, np.ndarray, float]) -> None:
    """Keep ``pairs`` for ``geometry`` and kind in the cache's folder, signed (nothing when the cache is off)."""
    path, key = _place(geometry, general)
    if path is None or key is None:
        return
    stream = io.BytesIO()
    first, second, within = pairs
    np.savez(stream, first=np.asarray(first, np.int64), second=np.asarray(second, np.int64), within=within)
    body = stream.getvalue()
    signing.write_atomically(path, signing.signed_file(key, path.stem, body))


def _place(geometry: tuple, general: bool) -> tuple[Path | None, bytes | None]:
    """The file for ``geometry`` and kind, and the cache's key; (None, None) while the cache is off."""
    folder = compilation_cache.programs_folder()
    if folder is None:
        return None, None
    digest, n_samples = geometry
    name = hashlib.sha256(b"\n".join([digest, str(n_samples).encode(), str(general).encode(), _source()])).hexdigest()
    return folder / f"{name[:40]}{SUFFIX}", signing.secret(folder)


@cache
def _source() -> bytes:
    """What a pairing depends on besides its directions: the code that pairs and stores them, and the versions of
    NumPy (its seeded choice of queries) and SciPy (its k-d tree)."""
    import scipy

    here = Path(__file__).parent
    code = (here / "reciprocity.py").read_bytes() + Path(__file__).read_bytes()
    return hashlib.sha256(code + f"{np.__version__} {scipy.__version__}".encode()).hexdigest().encode()
