"""The fitted maps of a spatially varying material: ``params.npz``, ``maps.json`` and textures, written and read.

A maps folder holds:

* ``params.npz``: one array per parameter, named as in a result file (a Lafortune lobe's as ``lobe0_n``, …), (H, W) for
  a parameter shared by the channels and (H, W, C) for one per channel; ``cost`` and ``rmse`` (H, W; the fit's, as a
  result file's), ``converged`` (H, W, bool), ``n_samples`` (H, W: the samples each texel's fit used; 0 where it was not
  fitted), ``n_caveats`` (H, W: how many caveats its fit and its uncertainty have, as a result's warnings) and, with
  ``uncertainty="laplace"``, ``<parameter>_stderr`` for each parameter (the Laplace standard error, same shape), and
  ``normal`` (H, W, 3), the capture's normal map, where it had one. A texel that was not fitted (masked out, or with
  fewer samples than its model has parameters) holds NaN;
* ``maps.json``: what the arrays are: the model and its options, the loss, the channels, the texel grid and the
  plane's size, the capture they came from, and counts (texels fitted, converged; the rmse's median);
* ``material.glb``, for the maps of a ``gltf`` fit: a quad the size of the sample with the maps as its material's
  textures (``gltf_maps.py``), which ``maps.json``'s ``glb`` describes (its notes, the 8-bit textures' rounding, or
  why it was not written);
* ``textures/``: each parameter as a linear OpenEXR image (``<parameter>.exr``: one channel, or RGB) and an 8-bit
  PNG preview (``<parameter>.png``: an albedo or colour sRGB-encoded, any other parameter linear over the map's own
  range, its 1st to 99th percentile, which ``maps.json`` records as ``preview_range``).
"""

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, parse_json, read_json_file, read_json_text, reading, write_text_atomic
from ..errors import BrdfInputError
from .images import srgb_encoded, write_exr, write_png

PARAMS_FILE = "params.npz"
MAPS_FILE = "maps.json"
TEXTURES = "textures"
GLB_FILE = "material.glb"
#: The capture's normal map in ``params.npz``, where it had one.
NORMALS = "normal"
VERSION = 1
#: The per-texel arrays beside the parameters.
FIT_ARRAYS = ("cost", "rmse", "converged", "n_samples", "n_caveats")
#: A standard-error map's name: the parameter's with this after it.
STDERR_SUFFIX = "_stderr"
#: Parameters previewed as colours (sRGB-encoded): albedos and a glTF/principled base colour.
COLOUR_PARAMETERS = ("rho_d", "rho_s", "kd", "ks", "base_color", "sheen_color")


@dataclass
class Maps:
    """Maps of one model's parameters over a texel grid (module docstring): ``params`` and, with Laplace errors,
    ``stderr`` (name → (H, W) or (H, W, C)), ``fit`` (:data:`FIT_ARRAYS` → (H, W)); ``model``, ``model_options``,
    ``loss``, ``channels``; the plane's ``width_mm`` and ``height_mm``; ``capture``: the capture file's path;
    ``caveat_examples``: the caveats of the first texel that has any (``n_caveats`` counts every texel's);
    ``neighbour_starts``: how many texels were fitted again from a neighbour's parameters, and how many ended lower
    (``neighbours.py``); ``notes``: what a user must know of the fit as a whole (the capture's values far below the
    relative loss's floor); ``normals``: the capture's normal map (H, W, 3), where it had one, which relighting
    needs; ``exports``: what the fit that made the maps wrote beside them, the ``material.glb`` (``"glb"``) and the
    ``mitsuba/`` folder (``"mitsuba"``), as ``maps.json`` says of them (``gltf_maps.write_glb``,
    ``mitsuba_maps.write_mitsuba_maps``; None: not made). Maps read from a folder have none: written elsewhere, or
    changed, they no longer have those files beside them. ``smoothing``: the smoothness prior the texels were fitted
    under (``smoothing.smoothed``: ``tau``, ``lambda``, ``passes``, ``largest_change``, ``converged``), empty for
    none."""

    model: str
    model_options: dict[str, Any]
    loss: str
    channels: tuple[str, ...]
    params: dict[str, np.ndarray]
    fit: dict[str, np.ndarray]
    width_mm: float
    height_mm: float
    capture: str = ""
    stderr: dict[str, np.ndarray] = field(default_factory=dict)
    caveat_examples: list[str] = field(default_factory=list)
    neighbour_starts: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    normals: np.ndarray | None = None
    exports: dict[str, dict[str, Any] | None] = field(default_factory=lambda: {"glb": None, "mitsuba": None})
    smoothing: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        rows, columns = self.fit["n_samples"].shape
        return rows, columns

    @property
    def fitted(self) -> np.ndarray:
        """Which texels were fitted (H, W)."""
        return self.fit["n_samples"] > 0

    def texel_params(self, row: int, column: int) -> dict[str, Any]:
        """The parameters of texel (``row``, ``column``) as a result file's ``params`` (numbers and lists)."""
        return nested_params({name: np.asarray(array[row, column]).tolist() for name, array in self.params.items()})

    def caveats(self) -> str | None:
        """One line on every texel's caveats: how many texels have any, and the first one's; None where none has."""
        with_caveats = int(np.sum(self.fit["n_caveats"] > 0))
        if not with_caveats:
            return None
        shown = "; ".join(self.caveat_examples[:2]) + ("; …" if len(self.caveat_examples) > 2 else "")
        return (
            f"{with_caveats:,} of {int(self.fitted.sum()):,} texels have caveats (n_caveats in params.npz maps them),"
            f" e.g. {shown}"
        )

    def summary(self) -> dict[str, Any]:
        """The counts ``maps.json`` holds: texels (``n_texels``), fitted, converged, the fitted ones' median rmse."""
        fitted = self.fitted
        return {
            "n_texels": int(fitted.size),
            "fitted": int(fitted.sum()),
            "converged": int(np.sum(self.fit["converged"] & fitted)),
            "median_rmse": _median(self.fit["rmse"][fitted]),
        }


def _median(values: np.ndarray) -> float | None:
    """The median of the finite ``values``; None where there is none (JSON has no NaN)."""
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else None


def flat_params(params: dict[str, Any]) -> dict[str, Any]:
    """A result's ``params`` with a lobe list's entries as names of their own: ``lobes[0]["n"]`` as ``lobe0_n``."""
    flat = {name: value for name, value in params.items() if name != "lobes"}
    for index, lobe in enumerate(params.get("lobes", ())):
        flat |= {f"lobe{index}_{name}": value for name, value in lobe.items()}
    return flat


def column_params(columns: dict[str, np.ndarray], texel: int) -> dict[str, Any]:
    """Texel ``texel``'s parameters (a result file's ``params``) from a capture's flat arrays ``columns`` (name →
    (H·W[, C]); the fit's own arrays and standard errors beside them are not parameters)."""
    names = [name for name in columns if name not in FIT_ARRAYS and not name.endswith(STDERR_SUFFIX)]
    return nested_params({name: columns[name][texel].tolist() for name in names})


def nested_params(flat: dict[str, Any]) -> dict[str, Any]:
    """The inverse of :func:`flat_params`."""
    lobes: dict[int, dict[str, Any]] = {}
    params: dict[str, Any] = {}
    for name, value in flat.items():
        head, _, rest = name.partition("_")
        if head.startswith("lobe") and head[4:].isdigit() and rest:
            lobes.setdefault(int(head[4:]), {})[rest] = value
        else:
            params[name] = value
    if lobes:
        params["lobes"] = [lobes[index] for index in sorted(lobes)]
    return params


def write_maps(folder: str | os.PathLike, maps: Maps, textures: bool = True) -> list[Path]:
    """``maps`` into ``folder`` (made if missing): ``params.npz``, ``maps.json`` and, with ``textures``, the
    ``textures/`` images, each atomically; returns the paths written, and ``maps.exports``' files, written
    beside them before."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, Any] = dict(maps.params) | dict(maps.fit)  # Any: savez's stubs take allow_pickle among them
    arrays |= {f"{name}{STDERR_SUFFIX}": array for name, array in maps.stderr.items()}
    if maps.normals is not None:
        arrays[NORMALS] = maps.normals
    params_path = folder / PARAMS_FILE
    with atomic_path(params_path) as temporary, open(temporary, "wb") as stream:
        np.savez_compressed(stream, **arrays)
    written = [params_path]
    ranges: dict[str, list[float]] = {}
    if textures:
        (folder / TEXTURES).mkdir(exist_ok=True)
        for name, array in maps.params.items():
            write_exr(folder / TEXTURES / f"{name}.exr", array, maps.channels)
            written.append(folder / TEXTURES / f"{name}.exr")
            if array.ndim == 2 or array.shape[-1] in (1, 3):  # an image's channels; no preview of other counts
                preview, ranges[name] = _preview(name, array)
                write_png(folder / TEXTURES / f"{name}.png", preview)
                written.append(folder / TEXTURES / f"{name}.png")
    glb, mitsuba = maps.exports.get("glb"), maps.exports.get("mitsuba")
    if glb and glb.get("file"):
        written.append(folder / glb["file"])
    if mitsuba and mitsuba.get("folder"):
        written += [folder / mitsuba["folder"] / name for name in mitsuba["files"]]
    _remove_stale(folder, written)
    description = {
        "brdffit_maps": VERSION,
        "model": maps.model,
        "model_options": maps.model_options,
        "loss": maps.loss,
        "channels": list(maps.channels),
        "texels": list(maps.shape),
        "plane": {"width_mm": maps.width_mm, "height_mm": maps.height_mm},
        "capture": maps.capture,
        "parameters": list(maps.params),
        "uncertainty": "laplace" if maps.stderr else None,
        "preview_range": ranges,
        "caveat_examples": maps.caveat_examples,
        "neighbour_starts": maps.neighbour_starts,
        "smoothing": maps.smoothing or None,
        "notes": maps.notes,
        "glb": glb,
        "mitsuba": mitsuba,
        **maps.summary(),
    }
    write_text_atomic(folder / MAPS_FILE, json.dumps(description, indent=1) + "\n")
    return [*written, folder / MAPS_FILE]


def _remove_stale(folder: Path, written: list[Path]) -> None:
    """The files of the fit whose ``maps.json`` ``folder`` holds (its textures, ``material.glb``, ``mitsuba/``) that
    this fit does not write again (another model's parameters and exports): the folder then holds one fit. Only
    files that ``maps.json`` names go, never anything else in the folder."""
    try:
        earlier = parse_json(read_json_text(folder / MAPS_FILE))
    except (OSError, ValueError):
        return
    if not isinstance(earlier, dict):
        return
    names = [name for name in earlier.get("parameters") or [] if isinstance(name, str)]
    stale = [folder / TEXTURES / f"{name}{suffix}" for name in names for suffix in (".exr", ".png")]
    glb, mitsuba = earlier.get("glb") or {}, earlier.get("mitsuba") or {}
    if isinstance(glb, dict) and glb.get("file") == GLB_FILE:
        stale.append(folder / GLB_FILE)
    if isinstance(mitsuba, dict) and mitsuba.get("folder") == "mitsuba":
        stale += [folder / "mitsuba" / Path(str(name)).name for name in mitsuba.get("files") or []]
    kept = {path.resolve() for path in written}
    for path in stale:
        if path.is_file() and path.resolve() not in kept:
            path.unlink()


def _preview(name: str, array: np.ndarray) -> tuple[np.ndarray, list[float]]:
    """A parameter map as an image in [0, 1] and the values its 0 and 1 stand for (module docstring)."""
    if name in COLOUR_PARAMETERS:
        return srgb_encoded(array), [0.0, 1.0]
    finite = array[np.isfinite(array)]
    low, high = (float(np.percentile(finite, q)) for q in (1, 99)) if finite.size else (0.0, 1.0)
    span = high - low if high > low else 1.0
    return (array - low) / span, [low, high]


def read_maps(folder: str | os.PathLike) -> Maps:
    """The maps in ``folder`` (written by :func:`write_maps`)."""
    folder = Path(folder)
    described = folder / MAPS_FILE
    description = read_json_file(described, "a maps description")
    if not isinstance(description, dict) or description.get("brdffit_maps") != VERSION:
        raise BrdfInputError(f'{described}: not a brdffit maps description (no "brdffit_maps": {VERSION})')
    with reading(folder / PARAMS_FILE, "a maps file"), np.load(folder / PARAMS_FILE, allow_pickle=False) as arrays:
        loaded = {name: arrays[name] for name in arrays.files}
    names = description["parameters"]
    missing = [name for name in (*names, *FIT_ARRAYS) if name not in loaded]
    if missing:
        raise BrdfInputError(f"{folder / PARAMS_FILE}: no {missing[0]} array, which {MAPS_FILE} names")
    return Maps(
        description["model"],
        description["model_options"],
        description["loss"],
        tuple(description["channels"]),
        {name: loaded[name] for name in names},
        {name: loaded[name] for name in FIT_ARRAYS},
        description["plane"]["width_mm"],
        description["plane"]["height_mm"],
        description.get("capture", ""),
        {name: loaded[f"{name}{STDERR_SUFFIX}"] for name in names if f"{name}{STDERR_SUFFIX}" in loaded},
        list(description.get("caveat_examples", [])),
        dict(description.get("neighbour_starts") or {}),
        list(description.get("notes") or []),
        loaded.get(NORMALS),
        smoothing=dict(description.get("smoothing") or {}),
    )
