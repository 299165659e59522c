"""One fit per texel of a capture: :func:`fit_capture`, the maps of a spatially varying material.

The texels are fitted a tile at a time (:data:`TILE_TEXELS` texels, row by row) through the batch machinery
(``fitting/many``: the texels' problems stacked in a few compiled programs, spread over the CPU cores), with the
options of a single fit (model and its options, loss, ``fixed``/``bounds``, starts, caveats). Memory stays bounded
by a tile's samples beside the photographs.

The default loss is ``relative``, ``(f − y)/y``, not a single fit's ``log``: a photograph's noise grows with its
signal, and relative residuals of such noise share one scatter, which Laplace's Gauss-Newton errors assume. On a
synthetic capture with 1% multiplicative noise (16 × 16 texels, 24 images, Ward) the 68% intervals of the relative
loss covered 68–70% of the true parameters; the log loss's, whose residuals scale with the signal, 44–72%.

With an ``output`` folder each finished tile is kept in ``output/.tiles/`` as it ends (atomically), and the maps
are written only when every tile is done (``maps.py``): an interrupted fit leaves no maps, and ``resume=True``
fits only the tiles that are not kept, provided they were fitted from the same capture file with the same
options (``.tiles/key.json``); a fit without ``resume`` starts afresh.
"""

import hashlib
import json
import os
import shutil
import warnings
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, write_text_atomic
from .._progress import progress_bar
from .._version import __version__
from ..checks import choice, whole_number
from ..errors import Argument, BrdfInputError, FitWarning, UncertaintyWarning, warn
from ..fitting.many.cluster import fit_here, fit_on_cluster
from ..fitting.objective.losses import RELATIVE_FLOOR, get_loss
from ..fitting.options import holding_of, solving_of
from ..fitting.single.result import FitResult
from ..physics.models.registry import get_model
from ..uncertainty.methods import with_uncertainty
from .capture import Capture, read_capture
from .gltf_maps import write_glb
from .maps import FIT_ARRAYS, Maps, flat_params, nested_params, write_maps
from .mitsuba_maps import TEXTURED, write_mitsuba_maps
from .texels import TexelSamples, read_photographs, texel_samples

#: Texels fitted at a time: a tile's samples (32 photographs: about 20 MB) and results are what grows with it.
TILE_TEXELS = 4096
#: The folder of finished tiles inside an output folder, and the file naming what they were fitted from.
TILES = ".tiles"
TILES_KEY = "key.json"
UNCERTAINTIES = ("laplace",)
#: A texel whose cost is above this many times a neighbour's is fitted again from the neighbour's parameters: a
#: fit stuck in a local minimum ends far above (a principled texel of noise-free photographs: 0.01–0.09 against
#: 4·10⁻¹⁴), while neighbours' costs at one noise level differ by tens of percent. At most this many passes.
RESTART_ABOVE = 2.0
NEIGHBOUR_PASSES = 3
#: A refit from a neighbour's start replaces a fit when its cost is lower by more than this (relative).
SAME_COST = 1e-9
#: A tile's array of the caveats of its first texel that has any (not a map: left out of the maps).
EXAMPLES = "caveat_examples"


def fit_capture(
    capture: str | os.PathLike | Capture,
    model: str = "ward",
    loss: str = "relative",
    *,
    output: str | os.PathLike | None = None,
    resume: bool = False,
    progress: bool | None = None,
    threads: int | None = None,
    n_starts: int | None = None,
    max_steps: int | None = None,
    seed: int | None = None,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    uncertainty: str | None = None,
    textures: bool = True,
    tile_texels: int = TILE_TEXELS,
    client=None,
    **model_options: Any,
) -> Maps:
    """Fit ``model`` to every texel of ``capture`` (a capture folder, its ``capture.json``, or a read
    :class:`~brdffit.svbrdf.capture.Capture`) and return the :class:`~brdffit.svbrdf.maps.Maps`, written to
    ``output`` (a folder) where one is given (module docstring). The options are those of :func:`brdffit.fit`;
    ``uncertainty="laplace"`` adds a standard-error map per parameter; ``textures``: write the ``textures/`` images
    too; ``progress``: a bar over the texels on stderr (default: when stderr is a terminal); ``client``: a
    ``dask.distributed.Client`` whose workers fit each tile's texels (this process reads the photographs and writes
    the maps; the results are this process's, ``fitting/many/cluster.py``)."""
    capture = capture if isinstance(capture, Capture) else read_capture(capture)
    if uncertainty is not None:
        choice("uncertainty", uncertainty, UNCERTAINTIES)
    tile_texels = whole_number("tile_texels", tile_texels)
    built = get_model(model, **model_options)
    solving = solving_of(None, n_starts=n_starts, max_steps=max_steps, seed=seed)
    holding = holding_of(None, fixed=fixed, bounds=bounds)
    if resume and output is None:
        raise BrdfInputError("resume=True continues a fit written to an output folder: give output")
    if output is not None:
        _check_output(Path(output), capture)
    photographs = read_photographs(capture)  # every photograph checked before anything is written
    tiles = None if output is None else _tile_folder(Path(output), capture, built, loss, solving, holding, resume)
    least = built.physical.size(1) + 1  # a texel with fewer samples than one channel's parameters is not fitted
    positive = get_loss(loss).name == "relative"  # a value of 0 has no relative residual
    notes = _scale_notes(photographs, loss)
    then = None if uncertainty is None else partial(with_uncertainty, method=uncertainty)
    fit_tile = partial(
        _fit_tile,
        model=built,
        loss=loss,
        least=least,
        then=then,
        client=client,
        threads=threads,
        solving=solving,
        holding=holding,
    )
    starts = range(0, capture.n_texels, tile_texels)
    bar = progress_bar(capture.n_texels, "texel", progress)
    columns: dict[str, np.ndarray] = {}
    examples: list[str] = []
    try:
        for number, start in enumerate(starts):
            texels = np.arange(start, min(start + tile_texels, capture.n_texels))
            kept = None if tiles is None else tiles / f"{number:06d}.npz"
            if kept is not None and kept.exists():
                with np.load(kept, allow_pickle=False) as stored:
                    tile = {name: stored[name] for name in stored.files}
            else:
                tile = fit_tile(texel_samples(photographs, texels, positive), capture)
                if kept is not None:
                    with atomic_path(kept) as temporary, open(temporary, "wb") as stream:
                        np.savez(stream, **tile)
            examples += [str(text) for text in tile.pop(EXAMPLES)]
            _gather(columns, tile, capture.n_texels, texels)
            bar.update(len(texels))
    finally:
        bar.close()
    retried = _neighbour_starts(columns, capture, photographs, fit_tile, positive)
    maps = _maps(columns, capture, built, loss, examples)
    maps.neighbour_starts, maps.notes = retried, notes
    for note in notes:
        warn(FitWarning(note))
    caveats = maps.caveats()
    if caveats:
        warn(FitWarning(caveats))
    if output is not None:
        glb = write_glb(output, maps) if textures and maps.model == "gltf" else None
        first = capture.shots[0]
        mitsuba = None
        if textures and maps.model in TEXTURED:
            mitsuba = write_mitsuba_maps(output, maps, first.light_mm, float(np.max(first.intensity)), first.camera_mm)
        write_maps(output, maps, textures, glb, mitsuba)
        shutil.rmtree(Path(output) / TILES, ignore_errors=True)
    return maps


def _fit_tile(
    run: TexelSamples,
    capture: Capture,
    *,
    model,
    loss: str,
    least: int,
    then: Callable | None,
    starts: list[dict[str, Any]] | None = None,
    client=None,
    **options,
) -> dict[str, Any]:  # arrays; Any: savez's stubs take allow_pickle among its keywords
    """The flat arrays (one row per texel of ``run``) of its texels' fits: every parameter, its standard error
    (``then`` adding Laplace's), ``cost``, ``rmse``, ``converged``, ``n_samples``, ``n_caveats``; NaN where a texel
    has fewer than ``least`` samples; and :data:`EXAMPLES`, the caveats of its first texel that has any. ``starts``:
    one start per texel of ``run`` (``neighbour_starts``), in place of the start search."""
    counts = run.kept.sum(axis=1)
    fitted = np.flatnonzero(counts >= least)
    width = capture.shape[1]
    datasets = [run.samples(int(index), capture.channels, _texel_name(capture, run.texels[index])) for index in fitted]
    if starts is not None:
        options["start"] = [starts[index] for index in fitted]
    with warnings.catch_warnings():  # a texel's caveats are counted (n_caveats) and summed up once (_caveats)
        warnings.simplefilter("ignore", FitWarning)
        warnings.simplefilter("ignore", UncertaintyWarning)
        if not datasets:
            results = []
        elif client is not None:
            results = fit_on_cluster(client, datasets, model, loss, then=then, progress=False, **options)
        else:
            results = fit_here(datasets, model, loss, then=then, progress=False, **options)
    tile: dict[str, np.ndarray] = {
        "n_samples": counts.astype(np.int32),
        "n_caveats": np.zeros(len(counts), dtype=np.int32),
        "converged": np.zeros(len(counts), dtype=bool),
    }
    examples: list[str] = []
    for position, result in zip(fitted, results, strict=True):
        for name, value in _texel_values(result).items():
            if name not in tile:
                tile[name] = np.full((len(counts), *np.shape(value)), np.nan)
            tile[name][position] = value
        said = list(result.warnings) + (list(result.uncertainty.warnings) if result.uncertainty else [])
        tile["n_caveats"][position] = len(said)
        tile["converged"][position] = result.converged
        if said and not examples:
            row, column = divmod(int(run.texels[position]), width)
            examples = [f"texel ({row}, {column}): {text}" for text in said]
    for name in ("cost", "rmse"):
        tile.setdefault(name, np.full(len(counts), np.nan))
    tile[EXAMPLES] = np.array(examples, dtype=str)
    return tile


#: Values (1/sr) the relative loss weighs as relative only well above its floor (``losses.RELATIVE_FLOOR``): a capture
#: whose median BRDF is below this many times the floor is said to be in too small a unit.
FLOOR_MARGIN = 100.0


def _scale_notes(photographs, loss: str) -> list[str]:
    """What a user must know of the capture's values as BRDF: with the relative loss, a median far below its floor
    (lights' intensities in another unit than the photographs') makes its residuals absolute."""
    if get_loss(loss).name != "relative":
        return []
    sample = texel_samples(
        photographs, np.arange(0, photographs.capture.n_texels, max(1, photographs.capture.n_texels // 256))
    )
    values = sample.values[sample.kept]
    median = float(np.median(values)) if values.size else float("nan")
    if not median < FLOOR_MARGIN * RELATIVE_FLOOR:
        return []
    return [
        f"the photographs' values as BRDF have a median of {median:.3g} 1/sr: the relative loss counts values below"
        f" {RELATIVE_FLOOR:g} 1/sr as absolute differences; give the lights' intensities in the photographs' units"
        " (a white diffuse surface is then 1/π ≈ 0.32 1/sr)"
    ]


def _neighbour_starts(
    columns: dict[str, np.ndarray], capture: Capture, photographs, fit_tile: Callable, positive: bool
) -> dict[str, int]:
    """Each texel whose fit ended at more than :data:`RESTART_ABOVE` times the cost of one of its four neighbours'
    fitted again from that neighbour's parameters (the one of lowest cost), kept where it ends lower; up to
    :data:`NEIGHBOUR_PASSES` times, so that a good fit spreads across a patch of texels stuck in a local minimum.
    Updates ``columns`` (the capture's flat arrays); returns how many fits were ``retried`` and ``improved``."""
    rows, width = capture.shape
    names = [name for name in columns if name not in FIT_ARRAYS and not name.endswith("_stderr")]
    retried = improved = 0
    for _ in range(NEIGHBOUR_PASSES):
        cost = columns["cost"].reshape(rows, width)
        finite = np.where(np.isfinite(cost), cost, np.inf)
        padded = np.pad(finite, 1, constant_values=np.inf)
        shifted = np.stack([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]])
        best = shifted.argmin(axis=0)
        lowest = np.take_along_axis(shifted, best[None], axis=0)[0]
        again = np.isfinite(cost) & (cost > RESTART_ABOVE * lowest)
        if not again.any():
            break
        texels = np.flatnonzero(again.ravel())
        offsets = np.array([-width, width, -1, 1])  # up, down, left, right, as ``shifted`` stacks them
        sources = texels + offsets[best.ravel()[texels]]
        starts = [nested_params({name: columns[name][source].tolist() for name in names}) for source in sources]
        tile = fit_tile(texel_samples(photographs, texels, positive), capture, starts=starts)
        tile.pop(EXAMPLES)
        lower = tile["cost"] < columns["cost"][texels] * (1.0 - SAME_COST)
        for name, values in tile.items():
            if name in columns:
                columns[name][texels[lower]] = values[lower]
        retried, improved = retried + len(texels), improved + int(lower.sum())
        if not lower.any():
            break
    return {"retried": retried, "improved": improved}


def _texel_name(capture: Capture, texel) -> str:
    row, column = divmod(int(texel), capture.shape[1])
    return f"{capture.file} texel ({row}, {column})"


def _texel_values(result: FitResult) -> dict[str, Any]:
    values = flat_params(result.params) | {"cost": result.cost, "rmse": result.rmse}
    if result.uncertainty is not None:
        values |= {f"{name}_stderr": value for name, value in flat_params(result.uncertainty.stderr).items()}
    return {name: np.nan if value is None else value for name, value in values.items()}


def _gather(columns: dict[str, np.ndarray], tile: dict[str, np.ndarray], n_texels: int, texels: np.ndarray) -> None:
    """A tile's arrays into the capture's flat ``columns`` (made on first sight, NaN or 0 elsewhere)."""
    for name, values in tile.items():
        if name not in columns:
            fill = 0 if values.dtype.kind in "biu" else np.nan
            columns[name] = np.full((n_texels, *values.shape[1:]), fill, dtype=values.dtype)
        columns[name][texels] = values


def _maps(columns: dict[str, np.ndarray], capture: Capture, model, loss: str, examples: list[str]) -> Maps:
    rows, width = capture.shape
    grid = {name: values.reshape(rows, width, *values.shape[1:]) for name, values in columns.items()}
    for name in ("cost", "rmse"):
        grid.setdefault(name, np.full((rows, width), np.nan))
    fit = {name: grid.pop(name) for name in FIT_ARRAYS}
    stderr = {name[: -len("_stderr")]: grid.pop(name) for name in [n for n in grid if n.endswith("_stderr")]}
    return Maps(
        model.name,
        dict(model.model_options),
        loss,
        capture.channels,
        grid,
        fit,
        capture.width_mm,
        capture.height_mm,
        str(capture.file.resolve()),
        stderr,
        examples,
    )


def _stamp(path: Path) -> tuple[int, int]:
    """A file's size and modification time (ns): a photograph changed since a tile was fitted changes them."""
    status = path.stat()
    return status.st_size, status.st_mtime_ns


def _check_output(output: Path, capture: Capture) -> None:
    """An output folder the maps can be written into: not a file, not the capture's folder (its photographs are
    never overwritten), its parent a folder."""
    if output.exists() and not output.is_dir():
        raise BrdfInputError(f"{output}: not a folder; the maps are written into a folder")
    if output.resolve() == capture.folder.resolve():
        raise BrdfInputError(f"{output}: is the capture's folder; give another folder for the maps")
    if not output.resolve().parent.is_dir():
        raise BrdfInputError(f"{output}: folder {output.resolve().parent} does not exist")


def _tile_folder(output: Path, capture: Capture, model, loss: str, solving, holding, resume: bool) -> Path:
    """``output/.tiles``, ready: kept from an unfinished fit of the same capture and options with ``resume``,
    else emptied."""
    key = {
        "capture": hashlib.sha256(capture.file.read_bytes()).hexdigest(),
        "photographs": [[str(shot.file), *_stamp(shot.file)] for shot in capture.shots],
        "fit": repr((model.name, sorted(model.model_options.items()), loss, solving, holding)),
        "brdffit": __version__,
    }
    tiles = output / TILES
    if resume:
        try:
            kept = json.loads((tiles / TILES_KEY).read_text())
        except (OSError, ValueError):
            kept = None
        if kept == key:
            return tiles
        if kept is not None:
            raise BrdfInputError(
                f"{output}: the unfinished fit there is of another capture, other photographs or other options;"
                " fit afresh, without ",
                Argument("resume"),
            )
    shutil.rmtree(tiles, ignore_errors=True)
    tiles.mkdir(parents=True)
    write_text_atomic(tiles / TILES_KEY, json.dumps(key))
    return tiles
