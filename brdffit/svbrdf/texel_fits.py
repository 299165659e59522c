"""One fit per texel of a capture: :func:`fit_capture`, the maps of a spatially varying material.

The texels are fitted a tile at a time (:data:`TILE_TEXELS` texels, row by row) through the batch machinery
(``fitting/many``: the texels' problems stacked in a few compiled programs, spread over the CPU cores), with the
options of a single fit (model and its options, loss, ``fixed``/``bounds``, starts, caveats). Memory stays bounded
by a tile's samples beside the photographs. On a Dask cluster the workers fit bands of tiles, each reading the
photographs at its own texels (:func:`_tiles_on_cluster`): no process holds the whole capture (but for the
smoothness prior's passes, which run here).

The default loss is ``relative``, ``(f − y)/y``, not a single fit's ``log``: a photograph's noise grows with its
signal, and relative residuals of such noise share one scatter, which Laplace's Gauss-Newton errors assume. On a
synthetic capture with 1% multiplicative noise (16 × 16 texels, 24 images, Ward) the 68% intervals of the relative
loss covered 68–70% of the true parameters; the log loss's, whose residuals scale with the signal, 44–72%.

With an ``output`` folder each finished tile is kept as it ends (``tiles.py``), and the maps are written only when
every tile is done (``maps.py``): an interrupted fit leaves no maps, and ``resume=True`` fits only the tiles that
are not kept, provided they were fitted from the same capture and options. Then texels stuck in a local minimum are
fitted again from a neighbour's parameters (``neighbours.py``).
"""

import os
import warnings
from collections.abc import Callable, Generator, Sequence
from contextlib import closing
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from .._progress import progress_bar
from ..checks import choice, positive_number, whole_number
from ..errors import BrdfInputError, FitWarning, UncertaintyWarning, warn
from ..fitting.many.cluster import fit_here, on_workers, one_thread_each, task_size, worker_count
from ..fitting.objective.losses import RELATIVE_FLOOR, get_loss
from ..fitting.options import holding_of, solving_of
from ..fitting.single.result import FitResult
from ..physics.models.registry import get_model
from ..uncertainty.methods import with_uncertainty
from .capture import Capture, read_capture
from .gltf_maps import write_glb
from .maps import FIT_ARRAYS, Maps, flat_params, write_maps
from .mitsuba_maps import TEXTURED, write_mitsuba_maps
from .neighbours import neighbour_starts
from .smoothing import shape_mask, smoothed
from .texels import Photographs, TexelSamples, read_normals, read_photographs, texel_samples
from .tiles import TileStore

#: Texels fitted at a time: a tile's samples (32 photographs: about 20 MB) and results are what grows with it.
TILE_TEXELS = 4096
#: The most texels one task of a cluster fits (:func:`_groups_on_cluster`), in tiles of ``tile_texels``: each task
#: decodes every EXR, PNG or TIFF photograph whole (a .npy's rows alone), ~1 s for 32 photographs of 1024² pixels,
#: against ~16 s of fitting at 0.25 ms a texel; its tiles are kept (``resume``) as it ends, and a worker lost
#: mid-task loses at most this many.
BAND_TEXELS = 65536
UNCERTAINTIES = ("laplace",)
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
    smoothness: float | None = None,
    textures: bool = True,
    tile_texels: int = TILE_TEXELS,
    client=None,
    **model_options: Any,
) -> Maps:
    """Fit ``model`` to every texel of ``capture`` (a capture folder, its ``capture.json``, or a read
    :class:`~brdffit.svbrdf.capture.Capture`) and return the :class:`~brdffit.svbrdf.maps.Maps`, written to
    ``output`` (a folder) where one is given (module docstring). The options are those of :func:`brdffit.fit`;
    ``uncertainty="laplace"`` adds a standard-error map per parameter (each texel's own photographs'); ``smoothness``:
    τ of a smoothness prior on the texels' shape parameters (``smoothing.py``; None: each texel its own data's);
    ``textures``: write the ``textures/`` images too; ``progress``: a bar over the texels on stderr (default: when
    stderr is a terminal); ``client``: a ``dask.distributed.Client`` whose workers fit the tiles, a band of them a
    task, each worker reading its band's texels of the photographs itself (:func:`_tiles_on_cluster`; the capture's
    files at the same absolute paths on every worker); this process checks every photograph, keeping a few texels,
    refits the neighbour starts' texels on the workers too, and writes the maps; the results are this process's. The
    smoothness prior's passes run here, on the photographs read here whole."""
    capture = capture if isinstance(capture, Capture) else read_capture(capture)
    if uncertainty is not None:
        choice("uncertainty", uncertainty, UNCERTAINTIES)
    tile_texels = whole_number("tile_texels", tile_texels)
    built = get_model(model, **model_options)
    if smoothness is not None:
        smoothness = positive_number("smoothness", smoothness)
        shape_mask(built, len(capture.channels))  # a model without shape parameters, refused before any fit
    solving = solving_of(None, n_starts=n_starts, max_steps=max_steps, seed=seed)
    holding = holding_of(None, fixed=fixed, bounds=bounds)
    if resume and output is None:
        raise BrdfInputError("resume=True continues a fit written to an output folder: give output")
    positive = get_loss(loss).name == "relative"  # a value of 0 has no relative residual
    if output is not None:
        _check_output(Path(output), capture)
    # every photograph checked before anything is written; with a cluster, its workers read the texels they fit
    on_cluster = client is not None
    if on_cluster:
        capture = capture.resolved()  # the workers open its files, in folders of their own
    # read whole here where the tiles or the smoothness prior's passes are fitted here; else the texels the scale note
    # looks at alone
    whole = not on_cluster or smoothness is not None
    photographs = read_photographs(capture) if whole else None
    probe = read_photographs(capture, _scale_texels(capture.n_texels)) if photographs is None else photographs
    how = {"model": built.name, "options": built.model_options, "loss": loss, "solving": solving, "holding": holding}
    how |= {"uncertainty": uncertainty, "tile_texels": tile_texels}  # the smoothing runs after the tiles
    store = TileStore(None if output is None else Path(output), capture, how, resume)
    least = built.physical.size(1) + 1  # a texel with fewer samples than one channel's parameters is not fitted
    notes = _scale_notes(probe, loss)
    then = None if uncertainty is None else partial(with_uncertainty, method=uncertainty)
    fit_tile = partial(
        _fit_tile,
        capture=capture,
        model=built,
        loss=loss,
        least=least,
        then=then,
        threads=threads,
        solving=solving,
        holding=holding,
    )
    on_worker = partial(fit_tile, **one_thread_each({"threads": threads}))
    tiles = [
        np.arange(start, min(start + tile_texels, capture.n_texels))
        for start in range(0, capture.n_texels, tile_texels)
    ]
    if on_cluster:
        finished = _tiles_on_cluster(client, capture, tiles, store, on_worker, positive)
    else:
        assert photographs is not None  # read whole above
        finished = _tiles_here(tiles, store, fit_tile, photographs, positive)
    bar = progress_bar(capture.n_texels, "texel", progress)
    columns: dict[str, np.ndarray] = {}
    examples_of: dict[int, list[str]] = {}
    try:
        with closing(finished) as done:
            for number, tile in done:
                examples_of[number] = [str(text) for text in tile.pop(EXAMPLES)]
                _gather(columns, tile, capture.n_texels, tiles[number])
                bar.update(len(tiles[number]))
    finally:
        bar.close()
    examples = [text for number in sorted(examples_of) for text in examples_of[number]]
    if not np.any(columns["n_samples"] > 0):
        store.remove()
        raise BrdfInputError(
            f"{capture.file}: no texel has the {least} samples a {built.name} fit needs; nothing written"
        )

    def refit(texels: np.ndarray, starts: list[dict[str, Any]]) -> dict[str, Any]:
        if on_cluster:
            return _refit_on_cluster(client, capture, texels, starts, on_worker, positive, tile_texels)
        assert photographs is not None  # read whole above
        tile = fit_tile(texel_samples(photographs, texels, positive), starts=starts)
        tile.pop(EXAMPLES)
        return tile

    retried = neighbour_starts(columns, capture, refit)
    smoothing: dict[str, Any] = {}
    if smoothness is not None:
        assert photographs is not None  # read whole above

        def refit_under(texels: np.ndarray, starts: list, priors: list, errors: bool) -> dict[str, Any]:
            samples = texel_samples(photographs, texels, positive)
            # fitted here (a pass is quick), and their Laplace errors only where asked for: at the descent's end
            tile = fit_tile(samples, starts=starts, priors=priors, then=then if errors else None)
            tile.pop(EXAMPLES)
            return tile

        smoothing = smoothed(columns, capture, built, smoothness, refit_under, tile_texels, then is not None)
        if not smoothing["converged"]:
            notes.append(
                f"the smoothness prior's descent stopped after {smoothing['passes']} passes, the last moving a shape"
                f" coordinate by {smoothing['largest_change']:.2g}: the maps lie between the texels' own fits and the"
                " prior's optimum"
            )
    normals = read_normals(capture) if photographs is None else photographs.normals
    maps = _maps(columns, capture, built, loss, examples, retried, notes, normals)
    maps.smoothing = smoothing
    for note in notes:
        warn(FitWarning(note))
    caveats = maps.caveats()
    if caveats:
        warn(FitWarning(caveats))
    if output is not None:
        first = capture.shots[0]
        if textures and maps.model == "gltf":
            maps.exports["glb"] = write_glb(output, maps)
        if textures and maps.model in TEXTURED:
            maps.exports["mitsuba"] = write_mitsuba_maps(output, maps, first.light_mm, first.intensity, first.camera_mm)
        write_maps(output, maps, textures)
        store.remove()
    return maps


def _fit_tile(
    run: TexelSamples,
    *,
    capture: Capture,
    model,
    loss: str,
    least: int,
    then: Callable | None,
    starts: list[dict[str, Any]] | None = None,
    priors: list[tuple[np.ndarray, np.ndarray]] | None = None,
    **options,
) -> dict[str, Any]:  # arrays; Any: savez's stubs take allow_pickle among its keywords
    """The flat arrays (one row per texel of ``run``) of its texels' fits: every parameter, its standard error
    (``then`` adding Laplace's), ``cost``, ``rmse``, ``converged``, ``n_samples``, ``n_caveats``; NaN where a texel
    has fewer than ``least`` samples; and :data:`EXAMPLES`, the caveats of its first texel that has any. ``starts``:
    one start per texel of ``run`` (``neighbour_starts``), in place of the start search; ``priors``: one prior per
    texel of ``run`` (``smoothing.py``)."""
    counts = run.kept.sum(axis=1)
    fitted = np.flatnonzero(counts >= least)
    file, width = str(capture.file), capture.shape[1]  # once, not once a texel
    datasets = [
        run.samples(int(index), capture.channels, _texel_name(file, width, run.texels[index])) for index in fitted
    ]
    if starts is not None:
        options["start"] = [starts[index] for index in fitted]
    if priors is not None:
        options["priors"] = [priors[index] for index in fitted]
    with warnings.catch_warnings():  # a texel's caveats are counted (n_caveats) and summed up once (_caveats)
        warnings.simplefilter("ignore", FitWarning)
        warnings.simplefilter("ignore", UncertaintyWarning)
        results = fit_here(datasets, model, loss, then=then, progress=False, **options) if datasets else []
    tile: dict[str, np.ndarray] = {
        "n_samples": np.where(counts >= least, counts, 0).astype(np.int32),  # 0: not fitted
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


def _tiles_here(
    tiles: list[np.ndarray], store: TileStore, fit_tile: Callable, photographs: Photographs, positive: bool
) -> Generator[tuple[int, dict[str, Any]]]:
    """Each tile's number and arrays, fitted in this process (``fit_tile``: :func:`_fit_tile` with the fit's options)
    or kept from an earlier run; each kept as it ends."""
    for number, texels in enumerate(tiles):
        tile = store.kept(number)
        if tile is None:
            tile = fit_tile(texel_samples(photographs, texels, positive))
            store.keep(number, tile)
        yield number, tile


def _tiles_on_cluster(
    client, capture: Capture, tiles: list[np.ndarray], store: TileStore, fit_tile: Callable, positive: bool
) -> Generator[tuple[int, dict[str, Any]]]:
    """Each tile's number and arrays, kept from an earlier run or fitted on ``client``'s workers
    (:func:`_groups_on_cluster`); each tile kept as its band ends."""
    pending = []
    for number in range(len(tiles)):
        tile = store.kept(number)
        if tile is None:
            pending.append(number)
        else:
            yield number, tile
    groups = [(tiles[number], None) for number in pending]
    with closing(_groups_on_cluster(client, capture, groups, fit_tile, positive)) as done:
        for index, tile in done:
            store.keep(pending[index], tile)
            yield pending[index], tile


def _refit_on_cluster(
    client,
    capture: Capture,
    texels: np.ndarray,
    starts: list[dict[str, Any]],
    fit_tile: Callable,
    positive: bool,
    tile_texels: int,
) -> dict[str, np.ndarray]:
    """The arrays of ``texels`` fitted again from ``starts`` (one each: the neighbour starts) on ``client``'s workers
    (:func:`_groups_on_cluster`), in runs of consecutive ones: at most ``tile_texels``, and
    ``cluster.TASKS_PER_WORKER`` runs a worker where there are enough."""
    size = task_size(len(texels), worker_count(client), tile_texels)
    runs = [np.arange(start, min(start + size, len(texels))) for start in range(0, len(texels), size)]
    groups = [(texels[run], [starts[i] for i in run]) for run in runs]
    columns: dict[str, np.ndarray] = {}
    with closing(_groups_on_cluster(client, capture, groups, fit_tile, positive)) as done:
        for index, tile in done:
            tile.pop(EXAMPLES)
            _gather(columns, tile, len(texels), runs[index])
    return columns


def _groups_on_cluster(
    client, capture: Capture, groups: Sequence[tuple[np.ndarray, list | None]], fit_tile: Callable, positive: bool
) -> Generator[tuple[int, dict[str, Any]]]:
    """Each of ``groups`` (texels and their starts, or None: the start search) fitted as a tile on ``client``'s
    workers, yielded as ``(index of the group, its arrays)``: the groups cut into bands of consecutive ones
    (``cluster.TASKS_PER_WORKER`` bands a worker where there are enough, at most :data:`BAND_TEXELS` texels each),
    each band one task that reads the photographs at its own texels (:func:`_fit_groups`)."""
    largest = max((len(texels) for texels, _ in groups), default=1)
    size = task_size(len(groups), worker_count(client), max(1, BAND_TEXELS // largest))
    bands = [range(start, min(start + size, len(groups))) for start in range(0, len(groups), size)]
    tasks = [(capture, fit_tile, [groups[i] for i in band], positive) for band in bands]
    with closing(on_workers(client, _fit_groups, tasks)) as done:
        for index, fitted in done:
            yield from zip(bands[index], fitted, strict=True)


def _fit_groups(
    capture: Capture, fit_tile: Callable, groups: Sequence[tuple[np.ndarray, list | None]], positive: bool
) -> list[dict[str, Any]]:
    """One task's work, on a worker: the photographs read at the texels of ``groups`` alone, each group's texels
    (flat indices) fitted as a tile, from its starts where it has them."""
    photographs = read_photographs(capture, np.concatenate([texels for texels, _ in groups]))
    return [fit_tile(texel_samples(photographs, texels, positive), starts=starts) for texels, starts in groups]


#: Values (1/sr) the relative loss weighs as relative only well above its floor (``losses.RELATIVE_FLOOR``): a capture
#: whose median BRDF is below this many times the floor is said to be in too small a unit.
FLOOR_MARGIN = 100.0


def _scale_texels(n_texels: int) -> np.ndarray:
    """The texels (flat indices) whose values :func:`_scale_notes` looks at: about 256, evenly spread."""
    return np.arange(0, n_texels, max(1, n_texels // 256))


def _scale_notes(photographs: Photographs, loss: str) -> list[str]:
    """What a user must know of the capture's values as BRDF: with the relative loss, a median far below its floor
    (lights' intensities in another unit than the photographs') makes its residuals absolute."""
    if get_loss(loss).name != "relative":
        return []
    sample = texel_samples(photographs, _scale_texels(photographs.capture.n_texels))
    values = sample.values[sample.kept]
    median = float(np.median(values)) if values.size else float("nan")
    if not median < FLOOR_MARGIN * RELATIVE_FLOOR:
        return []
    return [
        f"the photographs' values as BRDF have a median of {median:.3g} 1/sr: the relative loss counts values below"
        f" {RELATIVE_FLOOR:g} 1/sr as absolute differences; give the lights' intensities in the photographs' units"
        " (a white diffuse surface is then 1/π ≈ 0.32 1/sr)"
    ]


def _texel_name(file: str, width: int, texel) -> str:
    """A texel's samples' source: the capture ``file`` and the texel's (row, column) in a grid ``width`` wide."""
    row, column = divmod(int(texel), width)
    return f"{file} texel ({row}, {column})"


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


def _maps(
    columns: dict[str, np.ndarray],
    capture: Capture,
    model,
    loss: str,
    examples: list[str],
    retried: dict[str, int],
    notes: list[str],
    normals: np.ndarray | None,
) -> Maps:
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
        retried,
        notes,
        None if normals is None else normals.reshape(rows, width, 3),
    )


def _check_output(output: Path, capture: Capture) -> None:
    """An output folder the maps can be written into: not a file, not the capture's folder (its photographs are
    never overwritten), its parent a folder."""
    if output.exists() and not output.is_dir():
        raise BrdfInputError(f"{output}: not a folder; the maps are written into a folder")
    if output.resolve() == capture.folder.resolve():
        raise BrdfInputError(f"{output}: is the capture's folder; give another folder for the maps")
    if not output.resolve().parent.is_dir():
        raise BrdfInputError(f"{output}: folder {output.resolve().parent} does not exist")
