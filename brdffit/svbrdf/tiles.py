"""The finished tiles of a fit kept in its output folder, so that an interrupted fit resumes where it stopped.

Each tile's arrays are kept in ``MAPS/.tiles/<number>.npz`` as the tile ends (atomically), beside ``key.json``: what
they were fitted from, as JSON (the capture file's SHA-256; each photograph's, mask's and normal map's path, size and
modification time; the model, its options, the loss, how it was solved and held, the uncertainty, the tile size;
brdffit's version). A fit with ``resume`` takes the kept tiles of an unfinished fit whose key is its own, and refuses
another's in one line; a fit without starts afresh. The folder is removed once the maps are written.
"""

import dataclasses
import hashlib
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, write_text_atomic
from .._version import __version__
from ..errors import Argument, BrdfInputError
from .capture import Capture

FOLDER = ".tiles"
KEY = "key.json"


class TileStore:
    """The kept tiles of a fit into ``output`` (module docstring), or none (``output`` None: nothing is kept)."""

    def __init__(self, output: Path | None, capture: Capture, fit: dict[str, Any], resume: bool):
        self.folder = None if output is None else output / FOLDER
        if self.folder is None:
            return
        key = {"capture": hashlib.sha256(capture.file.read_bytes()).hexdigest(), "files": _stamps(capture)}
        key |= {"fit": json.loads(json.dumps(fit, default=_plain)), "brdffit": __version__}
        if resume:
            try:
                kept = json.loads((self.folder / KEY).read_text())
            except (OSError, ValueError):
                kept = None
            if kept == key:
                return
            if kept is not None:
                raise BrdfInputError(
                    f"{output}: the unfinished fit there is of another capture, other photographs or other options;"
                    " fit afresh, without ",
                    Argument("resume"),
                )
        shutil.rmtree(self.folder, ignore_errors=True)
        self.folder.mkdir(parents=True)
        write_text_atomic(self.folder / KEY, json.dumps(key))

    def kept(self, number: int) -> dict[str, np.ndarray] | None:
        """Tile ``number``'s arrays, where it was kept."""
        path = self._path(number)
        if path is None or not path.exists():
            return None
        with np.load(path, allow_pickle=False) as stored:
            return {name: stored[name] for name in stored.files}

    def keep(self, number: int, tile: dict[str, Any]) -> None:
        """Tile ``number``'s arrays kept, atomically."""
        path = self._path(number)
        if path is not None:
            with atomic_path(path) as temporary, open(temporary, "wb") as stream:
                np.savez(stream, **tile)

    def remove(self) -> None:
        """Every kept tile gone: the maps are written."""
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)

    def _path(self, number: int) -> Path | None:
        return None if self.folder is None else self.folder / f"{number:06d}.npz"


def _stamps(capture: Capture) -> list[list]:
    """Each photograph's, the mask's and the normal map's absolute path, size and modification time (ns): the same
    whether the capture was given by a relative path or not (a cluster's fit resolves it)."""
    files = [shot.file for shot in capture.shots] + [path for path in (capture.mask, capture.normal_map) if path]
    return [[str(path.resolve()), path.stat().st_size, path.stat().st_mtime_ns] for path in files]


def _plain(value: Any):
    """A key's value as JSON: a dataclass (``Solving``, ``Holding``) as its fields, anything else as text."""
    return dataclasses.asdict(value) if dataclasses.is_dataclass(value) and not isinstance(value, type) else str(value)
