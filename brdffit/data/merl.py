"""MERL ``.binary`` BRDF tables: reader and table writer (a fitted model is tabulated by ``brdffit/export``).

The format is that of the MERL BRDF database (Matusik, Pfister, Brand and
McMillan, "A data-driven reflectance model", SIGGRAPH 2003), as read by MERL's
reference code ``BRDFRead.cpp``:

* a header of three little-endian int32, the table dimensions ``(90, 90, 180)``;
* three planes of ``90·90·180 = 1,458,000`` little-endian float64, red, then
  green, then blue, each complete before the next;
* a stored number times the channel's scale (``1/1500``, ``1.15/1500``,
  ``1.66/1500`` for r, g, b) is the BRDF in 1/sr; stored values < 0 mark
  missing data.

The table is indexed by Rusinkiewicz's half/difference angles (Rusinkiewicz,
"A new change of variables for efficient BRDF representation", EGWR 1998) of an
isotropic BRDF (``φh`` dropped): bin ``(i, j, k)`` at flat index
``k + 180 j + 16200 i`` holds ``θh = (i/90)² · π/2`` (a square-root grid, dense
near the specular peak), ``θd = j/90 · π/2`` and ``φd = k/180 · π``; ``φd`` is
folded into ``[0, π)`` by reciprocity (``φd → φd + π`` swaps light and viewer).
These are the angles ``BRDFRead.cpp``'s lookup maps to the bin (each bin's
lower edge).

A bin's directions (brdffit's shading frame, ``docs/conventions.md``; ``φh = 0``): the difference vector
``d = (sin θd cos φd, sin θd sin φd, cos θd)`` and its mirror image about the
half vector ``d' = (-d_x, -d_y, d_z)`` are rotated about the binormal ``y`` by
``θh``: ``wi = R_y(θh) d``, ``wo = R_y(θh) d'``; the half vector is then
``h = R_y(θh) z = (sin θh, 0, cos θh)``.
"""

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from .._files import atomic_path, reading
from .._jax import first_bad
from ..checks import choice, whole_number
from ..checks import max_theta as checked_max_theta
from ..errors import Argument, BrdfInputError
from ..physics.merl_table import HORIZON, N_BINS, SHAPE, bin_directions
from .samples import Provenance, Samples

HEADER_BYTES = 12
FILE_BYTES = HEADER_BYTES + 3 * N_BINS * 8
#: Stored number × scale = BRDF in 1/sr, for r, g, b (Matusik et al. 2003, ``BRDFRead.cpp``).
SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
CHANNELS = ("r", "g", "b")
SUBSAMPLE_METHODS = ("random", "stratified")


# ---------------------------------------------------------------------- reading
def read_merl(
    path: str | os.PathLike,
    *,
    max_theta: float | None = None,
    subsample: int | None = None,
    subsample_method: str = "random",
    seed: int = 0,
    bin_centres: bool = False,
) -> Samples:
    """Read a MERL ``.binary`` file (Matusik et al. 2003) into :class:`Samples` with channels r, g, b in 1/sr.

    Every valid bin becomes one sample at its Rusinkiewicz (1998) directions, at the bin's lower edge as MERL's
    ``BRDFRead.cpp`` looks it up, or at its centre with ``bin_centres`` (``physics/merl_table.py``): all three
    channels ≥ 0,
    both directions above the horizon and, with ``max_theta`` (degrees, in (0, 90]), θi and θo at most
    that. ``subsample``: keep that many of the valid samples, chosen with ``numpy.random.default_rng(seed)``;
    ``subsample_method`` ``"random"`` (uniform, without replacement) or ``"stratified"`` (an equal share
    from each θh bin, the rest spread over the bins that have more). Bad input raises
    :class:`~brdffit.errors.BrdfInputError` with one line naming the file.
    """
    source = str(path)
    checked_max_theta(max_theta)
    if subsample is not None:
        subsample = whole_number("subsample", subsample)
    choice("subsample_method", subsample_method, SUBSAMPLE_METHODS)
    whole_number("seed", seed, minimum=0)
    table = _read_table(Path(path))  # (3, N) stored numbers
    bad = first_bad(~np.isfinite(table))
    if bad is not None:
        channel, bin_index = bad
        where = np.unravel_index(bin_index, SHAPE)
        raise BrdfInputError(
            f"{source}: stored value {table[channel, bin_index]} in channel {CHANNELS[channel]} at bin"
            f" (θh {where[0]}, θd {where[1]}, φd {where[2]}) is not allowed (values must be finite)"
        )
    wi, wo = bin_directions(bin_centres)
    present = np.all(table >= 0, axis=0)
    above = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    index = np.flatnonzero(present & above)
    if index.size == 0:
        raise BrdfInputError(f"{source}: no valid sample (every bin is missing or below the horizon)")
    values = (table[:, index] * SCALES[:, None]).T
    samples = Samples.from_arrays(wi[index], wo[index], values, channels=CHANNELS, source=source)
    dropped = [
        ("bins below the horizon, which MERL never looks up", int(np.sum(~above))),
        ("missing bins (stored value < 0)", int(np.sum(above & ~present))),
    ]
    if max_theta is not None:  # selected as Samples.within selects, on the same directions
        inside = samples.inside(max_theta)
        if not np.any(inside):
            raise BrdfInputError(
                f"{source}: no valid sample within ", Argument("max_theta", f"{max_theta:g}"), " degrees"
            )
        samples, index = samples.select(inside), index[inside]
        dropped.append((f"beyond θ = {max_theta:g}°", int(np.sum(~inside))))
    if subsample is not None:
        samples = samples.select(_subsample(index, subsample, subsample_method, seed, source))
        dropped.append((f"left out by the subsample of {subsample:,} ({subsample_method})", index.size - subsample))
    provenance = Provenance("merl", rows=N_BINS, dropped=tuple((why, n) for why, n in dropped if n))
    return replace(samples, provenance=provenance)


def _read_table(path: Path) -> np.ndarray:
    """The stored numbers (3, 1,458,000) of a MERL file, after checking its header and size."""
    return np.array(stored_planes(path), dtype=np.float64)


def stored_planes(path: str | os.PathLike) -> np.ndarray:
    """The stored numbers of a MERL file as a read-only memory map (3, 1,458,000), after checking its header and
    size: a library of many tables is read bin block by bin block, never whole (``datadriven/build.py``)."""
    path = Path(path)
    with reading(path, "a MERL file"), path.open("rb") as handle:
        size = os.fstat(handle.fileno()).st_size
        if size < HEADER_BYTES:
            raise BrdfInputError(
                f"{path}: holds {size} bytes, shorter than the {HEADER_BYTES}-byte header of a MERL file"
            )
        header = handle.read(HEADER_BYTES)
        dims = tuple(int(n) for n in np.frombuffer(header, dtype="<i4")) if len(header) == HEADER_BYTES else ()
        if dims != SHAPE:
            raise BrdfInputError(f"{path}: dimensions {dims}, expected {SHAPE}; not a MERL BRDF file")
        if size != FILE_BYTES:
            raise BrdfInputError(f"{path}: holds {size:,} bytes; a MERL file of 90×90×180 needs {FILE_BYTES:,}")
        return np.memmap(handle, dtype="<f8", mode="r", offset=HEADER_BYTES, shape=(3, N_BINS))


def stored_block(path: str | os.PathLike, start: int, stop: int) -> np.ndarray:
    """The stored numbers (3, stop − start) of bins ``start:stop`` of a MERL file checked by :func:`stored_planes`,
    read, not mapped: a library of many tables read block by block keeps only the block in memory."""
    count = stop - start
    block = np.empty((3, count))
    with reading(path, "a MERL file"), open(path, "rb") as handle:
        for plane in range(3):
            handle.seek(HEADER_BYTES + (plane * N_BINS + start) * 8)
            block[plane] = np.fromfile(handle, dtype="<f8", count=count)
    return block


def _subsample(index: np.ndarray, count: int, method: str, seed: int, source: str) -> np.ndarray:
    """Positions in ``index`` (the valid bins, sorted, file order) of ``count`` of them, drawn with
    ``default_rng(seed)``, in file order."""
    if count > index.size:
        raise BrdfInputError(
            f"{source}: ",
            Argument("subsample", f"{count:,}"),
            f" is more than the {index.size:,} valid samples; give at most {index.size:,}",
        )
    rng = np.random.default_rng(seed)
    if method == "random":
        return np.sort(rng.choice(index.size, size=count, replace=False))
    # Stratified over θh: bin i gets min(n_i, level), the largest level the count allows; the remainder
    # goes one each to bins (chosen at random) that have more. Within a bin, the samples are random.
    stratum = index // (SHAPE[1] * SHAPE[2])
    available = np.bincount(stratum, minlength=SHAPE[0])
    level = _water_level(available, count)
    share = np.minimum(available, level)
    spare = np.flatnonzero(available > level)
    extra = rng.choice(spare, size=count - int(share.sum()), replace=False)
    share[extra] += 1
    order = np.lexsort((rng.random(index.size), stratum))  # by stratum, random within it
    ordered = stratum[order]
    rank = np.arange(index.size) - np.searchsorted(ordered, ordered, side="left")
    return np.sort(order[rank < share[ordered]])


def _water_level(available: np.ndarray, count: int) -> int:
    """The largest ``level`` with ``Σ min(available, level) ≤ count``."""
    low, high = 0, int(available.max())
    while low < high:
        middle = (low + high + 1) // 2
        if np.minimum(available, middle).sum() <= count:
            low = middle
        else:
            high = middle - 1
    return low


# ---------------------------------------------------------------------- writing
def write_merl_table(values_rgb, path: str | os.PathLike) -> None:
    """Write BRDF values (1/sr) as a MERL ``.binary`` file (Matusik et al. 2003), atomically.

    ``values_rgb``: shape (90, 90, 180, 3) indexed ``[θh bin, θd bin, φd bin, channel]``, or
    (1,458,000, 3) in file order; channels r, g, b. Negative values mark missing bins; NaN and
    infinity are not allowed. Each is divided by its channel's scale before it is stored.
    """
    try:
        values = np.asarray(values_rgb, dtype=np.float64)
    except (TypeError, ValueError):
        raise BrdfInputError(f"{path}: values must be an array of numbers") from None
    if values.shape not in ((*SHAPE, 3), (N_BINS, 3)):
        raise BrdfInputError(f"{path}: values must have shape {(*SHAPE, 3)} or {(N_BINS, 3)}, got {values.shape}")
    values = values.reshape(N_BINS, 3)
    if not np.all(np.isfinite(values)):
        raise BrdfInputError(f"{path}: values contain NaN or infinity; a MERL file holds finite numbers")
    planes = np.ascontiguousarray((values / SCALES).T, dtype="<f8")
    header = np.array(SHAPE, dtype="<i4")
    try:
        with atomic_path(path) as temporary, temporary.open("wb") as handle:
            handle.write(header.tobytes())
            handle.write(planes.tobytes())
    except OSError as error:
        raise BrdfInputError(f"{path}: cannot be written ({error.strerror or error})") from None
