"""A basis file (``.npz``): the library's mean, reference and principal components over MERL's table, and the
basis evaluated at any pair of directions.

A library material ``x`` (one channel of one table, mapped by ``mapping.py``) is, up to what the kept components
leave out, ``x = mean + Σ_k c_k · components[k]``. The components are scaled so that the library's coefficients
have unit variance along each (``datadriven/build.py``): a coefficient is measured in library standard deviations, and a
coefficient of 3 lies at the library's edge.

At a pair that falls between bins (``tabulation.py``), each of its 8 neighbouring bins gives a BRDF from its own
mapped value, reference and cosine weight, and the BRDF is their trilinear blend: the interpolation happens in
BRDF values, so that a pair near the horizon, where the cosine weight of the map divides, stays as good as its
neighbouring bins. At the bins themselves the blend is the bin's value, so a basis reproduces a library table
exactly up to the components it leaves out.
"""

import hashlib
import io
import os
import zipfile
import zlib
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from .._files import atomic_path, reading
from ..errors import BrdfInputError
from ..physics.merl_table import HORIZON, N_BINS, bin_directions
from .mapping import MAPPINGS, cosine_weight, unmapped
from .tabulation import interpolation

#: What a basis file says it is (``kind``) and the layout's version.
KIND = "brdffit-pca-basis"
VERSION = 1
#: Pairs evaluated per block: 2¹⁵ pairs × 8 corners × 32 components is a 64 MB gather.
BLOCK = 2**15


@dataclass(frozen=True, eq=False)
class Basis:
    """A learned basis; arrays over MERL's 1,458,000 bins in file order (``data/merl.py``).

    ``mapping``: one of :data:`~brdffit.datadriven.mapping.MAPPINGS`; ``mean`` (bins,) the library's mean mapped value;
    ``reference`` (bins,) the library's median BRDF in 1/sr (log-relative's ``ρ_ref``); ``components`` (K, bins)
    float32, mapped units per library standard deviation; ``filled`` (bins,) the bins that hold a value;
    ``explained`` (K,) the fraction of the library's variance each component explains; ``materials`` the
    library's tables (file names); ``digest`` the SHA-256 of the file it was read from ('' before it is saved).
    """

    mapping: str
    mean: np.ndarray
    reference: np.ndarray
    components: np.ndarray
    filled: np.ndarray
    explained: np.ndarray
    materials: tuple[str, ...]
    digest: str = ""

    @property
    def n_components(self) -> int:
        return self.components.shape[0]

    def corners(self, wi: np.ndarray, wo: np.ndarray) -> "Corners":
        """The basis at the 8 bins around each pair ``wi``, ``wo`` (N, 3), with their trilinear weights."""
        index, weight = interpolation(wi, wo, self.filled)
        return Corners(
            weight=weight,
            mean=self.mean[index],
            reference=self.reference[index],
            cosine=bin_cosine_weights()[index],
            components=np.moveaxis(self.components[:, index], 0, -1),  # float32 as stored: exact, half the memory
        )

    def brdf(self, coefficients: np.ndarray, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        """BRDF (N, C) in 1/sr at coefficients (K, C), numpy, block by block (a MERL table's 1.46·10⁶ pairs fit in
        memory); 0 where a direction is below the horizon."""
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        out = np.zeros((wi.shape[0], coefficients.shape[1]))
        rows = np.flatnonzero(visible_pairs(wi, wo))
        for start in range(0, rows.size, BLOCK):
            block = rows[start : start + BLOCK]
            out[block] = self.corners(wi[block], wo[block]).brdf(self.mapping, coefficients)
        return out


def visible_pairs(wi, wo) -> np.ndarray:
    """Which pairs have both directions above the horizon (``z > 0``), as every model decides
    (``physics/geometry.above_horizon``); the model is 0 at the others."""
    return (np.asarray(wi)[:, 2] > 0) & (np.asarray(wo)[:, 2] > 0)


class Corners(NamedTuple):
    """The basis at the 8 bins around each of N pairs (numpy or JAX arrays): trilinear ``weight`` (N, 8), the
    bins' ``mean``, ``reference`` and ``cosine`` weight (N, 8) and ``components`` (N, 8, K), float32 as stored."""

    weight: np.ndarray
    mean: np.ndarray
    reference: np.ndarray
    cosine: np.ndarray
    components: np.ndarray

    def brdf(self, mapping: str, coefficients):
        """BRDF (N, C) at coefficients (K, C): each corner's BRDF from its mapped value, blended (numpy or JAX)."""
        mapped = self.mean[..., None] + self.components @ coefficients  # (N, 8, C), float64 with float64 coefficients
        cosine = self.cosine[..., None]
        cosine = cosine + (cosine <= 0)  # an empty corner (weight 0) divides by 1, not 0
        corner = unmapped(mapping, mapped, self.reference[..., None], cosine)
        return (self.weight[..., None] * corner).sum(axis=-2)


@cache
def bin_cosine_weights() -> np.ndarray:
    """``cos θi · cos θo`` (bins,) of every bin's directions, 0 below the horizon."""
    wi, wo = bin_directions()
    return cosine_weight(wi, wo) * ((wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON))


def horizon_filled() -> np.ndarray:
    """The bins whose directions are both above the horizon (MERL never looks the others up)."""
    return bin_cosine_weights() > 0


# ------------------------------------------------------------------------------------------------ the file
def save_basis(basis: Basis, path: str | os.PathLike) -> None:
    """Write ``basis`` to ``path`` (an ``.npz``, whatever its name), atomically."""
    arrays: dict[str, Any] = dict(  # keywords of savez_compressed, whose stubs take allow_pickle among them
        kind=np.array(KIND),
        version=np.array(VERSION),
        mapping=np.array(basis.mapping),
        mean=basis.mean.astype(np.float64),
        reference=basis.reference.astype(np.float64),
        components=basis.components.astype(np.float32),
        filled=basis.filled.astype(bool),
        explained=basis.explained.astype(np.float64),
        materials=np.array(basis.materials, dtype=str),
    )
    try:
        with atomic_path(path) as temporary, temporary.open("wb") as handle:
            np.savez_compressed(handle, **arrays)
    except OSError as error:
        raise BrdfInputError(f"{path}: cannot be written ({error.strerror or error})") from None


_loaded: dict[tuple, Basis] = {}


def load_basis(path: str | os.PathLike) -> Basis:
    """The basis in the file ``path``, checked, with one-line errors that name the file; kept in memory while the
    file is unchanged (a fit, its uncertainty and its export read it once)."""
    path = Path(path)
    with reading(path, "a basis file"):
        status = path.stat()
        key = (str(path.resolve()), status.st_mtime_ns, status.st_size)
        if key in _loaded:
            return _loaded[key]
        data = path.read_bytes()
    _check_declared(path, data)
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as stored:
            arrays = {name: stored[name] for name in stored.files}
    except (ValueError, OSError, zipfile.BadZipFile, EOFError, zlib.error):  # zlib: a member's data corrupt
        raise BrdfInputError(f"{path}: not a basis file (an .npz written by brdffit basis build)") from None
    basis = _checked(path, arrays, hashlib.sha256(data).hexdigest())
    _loaded.clear()  # one basis at a time: each holds ~10 MB per component
    _loaded[key] = basis
    return basis


#: How much larger than its file a basis may be once decompressed, beyond :data:`EXPANSION_SLACK`: a basis's
#: float32 components hardly compress, so a file that expands more is a zip bomb (200 components from 10 MB).
MAX_EXPANSION = 50
EXPANSION_SLACK = 64 * 2**20


def _check_declared(path: Path, data: bytes) -> None:
    """Refuse, before anything is decompressed, a file that is not an ``.npz`` (a ``.npy`` renamed), one that would
    expand more than :data:`MAX_EXPANSION` times its size, and an array whose header declares another size than its
    member holds (5 TiB declared in a small file: numpy would allocate it before reading)."""
    not_a_basis = BrdfInputError(f"{path}: not a basis file (an .npz written by brdffit basis build)")
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
        raise not_a_basis from None
    with archive:
        members = archive.infolist()
        expanded = sum(member.file_size for member in members)
        if expanded > MAX_EXPANSION * len(data) + EXPANSION_SLACK:
            raise BrdfInputError(
                f"{path}: expands to {expanded / 2**20:,.0f} MiB from {len(data) / 2**20:,.1f} MiB, more than a basis"
                f" does ({MAX_EXPANSION}×); not read"
            )
        for member in members:
            try:
                with archive.open(member) as stream:
                    version = np.lib.format.read_magic(stream)
                    if version != (1, 0) and version != (2, 0):
                        raise ValueError(f"npy format {version}")
                    read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else None
                    shape, _, dtype = (read_header or np.lib.format.read_array_header_2_0)(stream)
                    held = member.file_size - stream.tell()
            except (ValueError, OSError, EOFError, zipfile.BadZipFile):
                raise not_a_basis from None
            declared = int(np.prod(shape, dtype=object)) * dtype.itemsize
            if dtype.hasobject or declared != held:
                raise BrdfInputError(
                    f"{path}: {member.filename} declares an array of shape {shape} ({declared:,} bytes) but holds"
                    f" {held:,} bytes; not read"
                )


def _checked(path: Path, arrays: dict, digest: str) -> Basis:
    """The basis of a file's arrays, after checking that they are one."""
    if str(arrays.get("kind", "")) != KIND:
        raise BrdfInputError(f"{path}: not a basis file (an .npz written by brdffit basis build)")
    try:
        version = int(arrays.get("version", -1))
    except (TypeError, ValueError):
        version = None
    if version != VERSION:
        raise BrdfInputError(f"{path}: basis version {arrays.get('version')}, this brdffit reads version {VERSION}")
    missing = [
        name for name in ("mapping", "mean", "reference", "components", "filled", "explained") if name not in arrays
    ]
    if missing:
        raise BrdfInputError(f"{path}: basis file lacks {', '.join(missing)}")
    mapping = str(arrays["mapping"])
    if mapping not in MAPPINGS:
        raise BrdfInputError(f"{path}: mapping {mapping!r} is not one of {', '.join(MAPPINGS)}")
    components = arrays["components"]
    for name in ("mean", "reference", "components", "explained", "filled"):
        if arrays[name].dtype.kind not in "biuf":  # a basis's arrays are real numbers (filled: booleans)
            raise BrdfInputError(f"{path}: {name} holds {arrays[name].dtype} values, not numbers")
    materials = arrays.get("materials", np.array([], dtype=str))
    if materials.ndim != 1 or materials.dtype.kind != "U":
        raise BrdfInputError(f"{path}: materials is not a list of names (shape {materials.shape}, {materials.dtype})")
    shapes = {"mean": (N_BINS,), "reference": (N_BINS,), "filled": (N_BINS,)}
    for name, shape in shapes.items():
        if arrays[name].shape != shape:
            raise BrdfInputError(f"{path}: {name} has shape {arrays[name].shape}, expected {shape}")
    if components.ndim != 2 or components.shape[1] != N_BINS or components.shape[0] < 1:
        raise BrdfInputError(f"{path}: components have shape {components.shape}, expected (K, {N_BINS})")
    if not all(np.all(np.isfinite(arrays[name])) for name in ("mean", "reference", "components")):
        raise BrdfInputError(f"{path}: basis holds NaN or infinite values")
    if arrays["explained"].shape != (components.shape[0],):
        raise BrdfInputError(
            f"{path}: explained has shape {arrays['explained'].shape}, expected ({components.shape[0]},)"
        )
    if np.any(arrays["reference"] < 0):
        raise BrdfInputError(f"{path}: reference holds negative BRDF values")
    return Basis(
        mapping=mapping,
        mean=arrays["mean"].astype(np.float64),
        reference=arrays["reference"].astype(np.float64),
        components=components.astype(np.float32),
        filled=arrays["filled"].astype(bool) & horizon_filled(),  # a bin below the horizon never holds a value
        explained=arrays["explained"].astype(np.float64).reshape(-1),
        materials=tuple(str(name) for name in materials),
        digest=digest,
    )
