"""A basis learned from a library of MERL tables: principal components of the mapped tables, streamed.

Every channel of every table is one library vector over MERL's 1,458,000 bins (``x_i``, mapped by
``mapping.py``). With ``M`` vectors, the components are those of the centred matrix ``X`` (M × bins), found
from its ``M × M`` Gram matrix ``G = X Xᵀ = V Λ Vᵀ`` (the "snapshot" method, Sirovich 1987): the k-th
principal direction is ``Xᵀ v_k / sqrt(λ_k)``. Two passes over the files, bin block by bin block, build it:

1. the reference (the library's median BRDF per bin), the mean mapped value, and ``G``;
2. the kept components ``Xᵀ v_k / sqrt(M − 1)``, scaled so that the library's coefficients along each have unit
   variance.

It is exact (no randomised truncation) and its memory is ``M`` vectors of one block plus the output, whatever the
library's size: 100 MERL tables are 3.5 GB of files, read one block of bins at a time. A bin that a table lacks
(stored value < 0) takes the library's median there; a bin that every table lacks, or that lies below the
horizon, is *empty* and takes no weight when the basis is interpolated.
"""

import os
from collections.abc import Callable, Sequence

import numpy as np

from ..data.merl import N_BINS, SCALES, stored_block, stored_planes
from ..errors import Argument, BrdfInputError
from .basis import Basis, bin_cosine_weights, horizon_filled
from .mapping import MAPPINGS, mapped

#: Bins per block: 2¹⁴ bins × 300 library vectors × 8 bytes is 39 MB per array.
BLOCK = 2**14
DEFAULT_COMPONENTS = 16
#: A component whose variance is below this fraction of the first's carries rounding only (float64's ~1e-16,
#: squared by the Gram matrix to ~1e-12 of the largest eigenvalue's scale).
RANK_TOLERANCE = 1e-10


def build_basis(
    paths: Sequence[str | os.PathLike],
    *,
    components: int = DEFAULT_COMPONENTS,
    mapping: str = "log-relative",
    progress: Callable[[int], None] | None = None,
) -> Basis:
    """The basis of the MERL files ``paths`` (each table's r, g and b are three library vectors), keeping
    ``components`` principal components of the ``mapping``-mapped tables. ``progress`` is called with the number
    of bins done after each block of each pass (2 × 1,458,000 in all). Bad input: one-line errors naming the file
    or option."""
    if mapping not in MAPPINGS:
        raise BrdfInputError(Argument("mapping", mapping), f" is not a mapping; choose one of: {', '.join(MAPPINGS)}")
    if isinstance(paths, str | os.PathLike):
        raise BrdfInputError(Argument("paths"), " must be a list of MERL files, not one path")
    paths = list(paths)
    for path in paths:  # every file checked before any work
        stored_planes(path)
    n_vectors = 3 * len(paths)
    if isinstance(components, bool) or not isinstance(components, int | np.integer) or components < 1:
        raise BrdfInputError(Argument("components", components), " must be a whole number ≥ 1")
    if n_vectors < 2 or components > n_vectors - 1:
        raise BrdfInputError(
            Argument("components", components),
            f": {len(paths)} table(s) give {n_vectors} library vectors, which have at most {max(n_vectors - 1, 0)}"
            " principal components; give fewer components or more tables",
        )
    progress = progress or (lambda done: None)
    reference, mean, filled = np.zeros(N_BINS), np.zeros(N_BINS), horizon_filled().copy()
    gram = np.zeros((n_vectors, n_vectors))
    for block in _blocks():
        rho = _library_block(paths, block)
        present = ~np.isnan(rho)
        filled[block] &= present.any(axis=0)
        reference[block] = _median(rho, present)
        centred = _centred(mapping, rho, reference[block], block, filled[block], mean)
        gram += centred @ centred.T
        progress(block.stop - block.start)
    eigenvalues, vectors = np.linalg.eigh(gram)
    order = np.argsort(eigenvalues)[::-1]
    eigenvalues, vectors = np.maximum(eigenvalues[order], 0.0), vectors[:, order[:components]]
    rank = int(np.sum(eigenvalues > RANK_TOLERANCE * eigenvalues[0]))
    if components > rank:  # a component of no variance is noise of rounding: it would mislead the directions
        raise BrdfInputError(
            Argument("components", components),
            f": the library's tables span only {rank} direction(s) (grey tables, or tables repeated);"
            f" keep at most {rank} components, or add other tables",
        )
    kept = np.zeros((components, N_BINS), np.float32)
    for block in _blocks():
        rho = _library_block(paths, block)
        centred = _centred(mapping, rho, reference[block], block, filled[block], mean, known_mean=True)
        kept[:, block] = (vectors.T @ centred) / np.sqrt(n_vectors - 1)
        progress(block.stop - block.start)
    total = eigenvalues.sum()
    return Basis(
        mapping=mapping,
        mean=mean,
        reference=reference,
        components=kept,
        filled=filled,
        explained=eigenvalues[:components] / total if total > 0 else np.zeros(components),
        materials=tuple(os.path.basename(os.fspath(path)) for path in paths),
    )


def _blocks():
    return (slice(start, min(start + BLOCK, N_BINS)) for start in range(0, N_BINS, BLOCK))


def _library_block(paths, block: slice) -> np.ndarray:
    """BRDF values (M, bins of the block) in 1/sr of every table's channels; NaN where a table lacks the bin."""
    rho = np.concatenate([stored_block(path, block.start, block.stop) * SCALES[:, None] for path in paths])
    rho[~(rho >= 0) | ~np.isfinite(rho)] = np.nan
    return rho


def _median(rho: np.ndarray, present: np.ndarray) -> np.ndarray:
    """The library's median per bin over the tables that have it (0 where none has)."""
    if present.all():
        return np.median(rho, axis=0)
    median = np.zeros(rho.shape[1])
    some = present.any(axis=0)
    median[some] = np.nanmedian(rho[:, some], axis=0)
    return median


def _centred(mapping, rho, reference, block, filled, mean, *, known_mean=False) -> np.ndarray:
    """The block's mapped, centred library vectors (M, bins), 0 at empty bins; sets ``mean[block]`` unless known."""
    rho = np.where(np.isnan(rho), reference, rho)
    values = np.where(filled, mapped(mapping, rho, reference, bin_cosine_weights()[block]), 0.0)
    if not known_mean:
        mean[block] = values.mean(axis=0)
    return values - mean[block]
