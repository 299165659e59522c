"""Reciprocity, ``f(wi, wo) = f(wo, wi)`` (Helmholtz): a check of what a file's values are.

Every BRDF is reciprocal; a cosine-weighted value is not. So on data that measure both directions of a
pair, the ratio of the two values says what the file holds: a median ratio ``f(a→b) / f(b→a)`` near 1 for
BRDF values, ``cos θb / cos θa`` away from 1 for values weighted by the light's cosine, its inverse for the
view's. Pairs are oriented with the light nearer the normal (``θi < θo``), so that a cosine reading moves
every ratio the same way.

A pair is two samples whose directions are swapped: ``wi`` and ``wo`` exchanged where the data hold at least
:data:`ENOUGH_PAIRS` of those, else whichever finds more of these and the isotropic pairs (for isotropic
measurements, the light at one azimuth): the zeniths exchanged at the same ``|φo − φi|``. Directions match
within a tolerance the file's own angular spacing sets (:func:`tolerance`: half the median distance between
neighbouring measurements, at most 0.5°), looked up in k-d trees: a real gonioreflectometer's positions carry
jitter, so exact matches are rare. Pairs a cosine factor hardly changes (:data:`INFORMATIVE`) are left out.

Where the file's header names a quantity, the check also says whether the data agree with it
(:attr:`Reciprocity.header_contradicted`): a header that calls BRDF values cosine-weighted is caught.
"""

import collections
import hashlib
import itertools
import math
import threading
from dataclasses import dataclass
from types import TracebackType
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ..errors import warn, warnings_deferred
from .memory import return_freed_memory
from .quantities import stored_factor
from .samples import Samples
from .stored_pairs import STORED_FROM, store_pairs, stored_pairs

if TYPE_CHECKING:  # scipy.spatial takes 0.3 s to import: every fit imports this module, few look pairs up
    from scipy.spatial import cKDTree

#: Below this many pairs the check says nothing.
MIN_PAIRS = 20
#: Fewer pairs of swapped directions than this, and the isotropic pairing is tried too, the one with more pairs
#: used: a few dozen pairs whose zeniths differ little (a MERL table's 20,000-sample subsample has 22 within 0.5°)
#: barely tell a cosine factor from 1, where the isotropic pairs (hundreds) do.
ENOUGH_PAIRS = 100
#: Median ratios inside this band are reciprocal; outside it a fit warns (a factor of 1.25 either way).
RECIPROCAL = (0.8, 1.25)
#: The pairing tolerance (:func:`tolerance`) is this fraction of the median distance between neighbouring samples,
SPACING_FRACTION = 0.5
#: within [MIN_TOLERANCE, MAX_TOLERANCE] (radians). Below the floor (angles written to 2 decimals of a degree) two
#: samples are one direction measured again; the cap is the issue's "within 0.5°".
MIN_TOLERANCE = float(np.radians(0.01))
MAX_TOLERANCE = float(np.radians(0.5))
#: How many samples' neighbours estimate the spacing (a seeded choice), and how many neighbours each is asked for
#: (repeated measurements of one direction are skipped to find the nearest other one).
SPACING_SAMPLE = 4096
SPACING_NEIGHBOURS = 9


@dataclass(frozen=True)
class Reciprocity:
    """What the reciprocal pairs of some samples say about their values.

    ``pairs``: how many were found, and of which ``kind`` (``"swapped directions"`` or ``"isotropic"``), their
    directions matched within ``tolerance_degrees``. ``ratios``: for each reading of the file's values
    (``brdf``, ``cosine-weighted-in``, ``cosine-weighted-out``), the median of ``f(a→b) / f(b→a)`` over pairs
    and channels. ``in_force``: the quantity the samples were read as; ``header``: the one the file's header
    names (None where it names none).
    """

    pairs: int
    kind: str
    ratios: dict[str, float]
    in_force: str
    tolerance_degrees: float = 0.0
    header: str | None = None

    @property
    def as_read(self) -> float:
        """The median ratio of the samples as they were read."""
        return self.ratios[_reading(self.in_force)]

    @property
    def reciprocal(self) -> bool:
        """Whether the samples as read are reciprocal (median ratio within :data:`RECIPROCAL`)."""
        return _within(self.as_read)

    @property
    def best(self) -> str:
        """The reading whose median ratio is nearest 1."""
        return min(self.ratios, key=lambda reading: abs(np.log(self.ratios[reading])))

    @property
    def header_contradicted(self) -> bool:
        """Whether the file's header names a quantity under which the data are not reciprocal, while another
        reading (:attr:`best`) is: the header is wrong about what the values are."""
        if self.header is None:
            return False
        return not _within(self.ratios[_reading(self.header)]) and _within(self.ratios[self.best])


#: Pairs whose two cosines differ by less than this factor (``cos θa / cos θb``) are left out: a cosine factor
#: hardly moves their ratio, and dozens of them would pull every reading's median towards 1.
INFORMATIVE = 1.1
#: How many geometries' pairs :func:`_pairs` keeps.
KEPT_GEOMETRIES = 8
#: The most samples whose partners are looked for, per pairing: a check of the median ratio needs no more. Above
#: it, a seeded random choice of them (the same each run); in a file above :data:`REGION_ABOVE` samples, of those in a
#: region (:func:`_region`). A MERL-size file (1.4 million pairs of directions) is then paired in ~0.3 s on 2 cores
#: (~0.6 s asking samples from every cell: ~0.25 s of it building k-d trees of every sample); 500 samples in ~3 ms.
MAX_QUERIES = 2**17
_kept: collections.OrderedDict = collections.OrderedDict()
_kept_lock = threading.Lock()
_pairing: dict[tuple, threading.Event] = {}  # the geometries being paired now, each set when it is done


def reciprocity(samples: Samples) -> Reciprocity | None:
    """The reciprocity of ``samples`` (None when they hold fewer than :data:`MIN_PAIRS` pairs: at once where fewer
    samples than that have ``θi < θo``, each pair's first, as a capture's texel seen from above has)."""
    if len(_firsts(samples)) < MIN_PAIRS:
        return None
    provenance = samples.provenance
    in_force = provenance.quantity if provenance is not None else "brdf"
    geometry = _geometry_key(samples)
    (first, second, within), kind = _pairs(geometry, samples, general=True), "swapped directions"
    if len(first) < ENOUGH_PAIRS:
        isotropic = _pairs(geometry, samples, general=False)
        if len(isotropic[0]) > len(first):
            (first, second, within), kind = isotropic, "isotropic (zeniths swapped, same |φo − φi|)"
    if len(first) < MIN_PAIRS:
        return None
    both = np.concatenate([first, second])  # the paired samples only (a MERL-size file: 123 pairs of 1.4 million)
    wi, wo = samples.wi[both], samples.wo[both]
    stored = samples.values[both] * stored_factor(in_force, wi, wo)
    ratios = {}
    for reading in ("brdf", "cosine-weighted-in", "cosine-weighted-out"):
        brdf = stored / stored_factor(reading, wi, wo)
        a, b = brdf[: len(first)], brdf[len(first) :]
        usable = (a > 0) & (b > 0)
        ratios[reading] = float(np.median(a[usable] / b[usable])) if np.any(usable) else float("nan")
    header = provenance.header_quantity if provenance is not None else None
    return Reciprocity(len(first), kind, ratios, in_force, float(np.degrees(within)), header)


class ReciprocityAhead:
    """:func:`reciprocity` of some samples, computed in a thread from when it is made, while the caller does other work
    (a fit traces and compiles meanwhile: pairing a MERL-size file's directions is ~0.3 s, most of it in NumPy and the
    k-d trees, which release the GIL). :meth:`result` waits for it, issues the warnings it met (in the caller's
    thread, :func:`~brdffit.errors.warnings_deferred`) and returns what it found or raises what it raised."""

    def __init__(self, samples: Samples):
        self._done = threading.Event()
        self._found: Reciprocity | None = None
        self._error: BaseException | None = None
        self._traceback: TracebackType | None = None  # the error's own: raised again as it was
        self._warnings: list[Warning] = []
        threading.Thread(target=self._find, args=(samples,), name="brdffit-reciprocity", daemon=True).start()

    def _find(self, samples: Samples) -> None:
        try:
            with warnings_deferred() as said:
                try:
                    self._found = reciprocity(samples)
                except BaseException as error:  # raised by result(), in the caller's thread
                    self._error, self._traceback = error, error.__traceback__
            self._warnings = said
            return_freed_memory()  # the trees' pages, kept by this thread's arena, back before the caller goes on
        finally:
            self._done.set()  # whatever happened: a solve waits for it

    def wait(self) -> None:
        """Wait until the check is done."""
        self._done.wait()

    def result(self, timeout: float | None = None) -> Reciprocity | None:
        """What :func:`reciprocity` found, once done (``TimeoutError`` after ``timeout`` seconds), its warnings issued
        once."""
        if not self._done.wait(timeout):
            raise TimeoutError(f"the reciprocity check took over {timeout} s")
        said, self._warnings = self._warnings, []
        for warning in said:
            warn(warning)
        if self._error is not None:
            raise self._error.with_traceback(self._traceback)
        return self._found


def header_contradiction(found: Reciprocity) -> str:
    """The line that says a file's header names the wrong quantity (:attr:`Reciprocity.header_contradicted`)."""
    assert found.header is not None  # contradicted: the header named a quantity
    header = _reading(found.header)
    return (
        f"the file's header says its values are {found.header}, but its {found.pairs} reciprocal pairs contradict it:"
        f" the median of f(a→b)/f(b→a) is {found.ratios[header]:.3g} read as {header},"
        f" {found.ratios[found.best]:.3g} read as {found.best}"
    )


def _within(ratio: float) -> bool:
    return RECIPROCAL[0] <= ratio <= RECIPROCAL[1]


def _reading(quantity: str) -> str:
    """The reading a quantity stands for (a reflectance factor is a BRDF times π: the same ratios)."""
    return "brdf" if quantity in ("brdf", "reflectance-factor") else quantity


#: ``(first, second, tolerance)``: the indices of each pair's two samples and the tolerance (radians) they matched to.
Pairs = tuple[np.ndarray, np.ndarray, float]


def _geometry_key(samples: Samples) -> tuple:
    """What names the directions of ``samples``: a digest of their bytes (~10 µs for 500 pairs) and their count."""
    digest = hashlib.blake2b(digest_size=16)
    digest.update(np.ascontiguousarray(samples.wi).data)
    digest.update(np.ascontiguousarray(samples.wo).data)
    return digest.digest(), len(samples.wi)


def _firsts(samples: Samples) -> np.ndarray:
    """Indices of the samples that can be a pair's first: ``θi < θo`` (each pair is found once, from its first)."""
    return np.flatnonzero(samples.wi[:, 2] > samples.wo[:, 2])


def _pairs(geometry: tuple, samples: Samples, general: bool) -> Pairs:
    """Indices ``(first, second)`` of reciprocal pairs, ``first`` with ``θi < θo``, each pair once, and the tolerance
    (radians) they matched within: with the directions swapped (``general``), or with the zeniths swapped at the
    same ``|φo − φi|`` (isotropic measurements).

    They depend on the directions alone, which the texels of a capture or the materials of a gonioreflectometer
    share: the last :data:`KEPT_GEOMETRIES` are kept, by ``geometry`` (:func:`_geometry_key` of ``samples``), and
    threads that ask for one at once (``fit_batch``'s) pair it once."""
    key = (*geometry, general)
    while True:  # one thread pairs a geometry; others asking meanwhile wait for its answer (or, if it failed, try)
        with _kept_lock:
            if key in _kept:
                _kept.move_to_end(key)
                return _kept[key]
            underway = _pairing.get(key)
            if underway is None:
                done = _pairing[key] = threading.Event()
                break
        underway.wait()
    try:
        found = _stored_or_paired(geometry, samples, general)
        for indices in found[:2]:
            indices.flags.writeable = False  # shared by every later caller
        with _kept_lock:
            _kept[key] = found
            while len(_kept) > KEPT_GEOMETRIES:
                _kept.popitem(last=False)
        return found
    finally:
        with _kept_lock:
            del _pairing[key]
        done.set()


def _stored_or_paired(geometry: tuple, samples: Samples, general: bool) -> Pairs:
    """:func:`_paired`; for a file of at least ``STORED_FROM`` samples, the pairs a previous process stored in the
    compilation cache's folder, else paired now and stored there (``stored_pairs.py``)."""
    if geometry[1] < STORED_FROM:
        return _paired(samples, general)
    found = stored_pairs(geometry, general)
    if found is None:
        found = _paired(samples, general)
        store_pairs(geometry, general, found)
    return found


def _points(wi: np.ndarray, wo: np.ndarray, general: bool) -> np.ndarray:
    """Each pair of directions ``(wi, wo)`` (N, 3 each) as a point in 6 dimensions, (N, 6); the point of its partner
    is ``_points(wo, wi, general)``.

    ``general``: ``(wi, wo)`` as they are. Else (isotropic) each pair of directions turned about the normal until
    the first lies at azimuth 0, and mirrored in ``y`` so that the second lies at ``y ≥ 0`` (:func:`_canonical`).
    The distance between two points is the root-sum-square of the chords between their two directions, ≈ the
    angles in radians."""
    return np.hstack([wi, wo]) if general else _canonical(wi, wo)


def _canonical(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """``(first, second)`` (N, 3) each turned about ``z`` to put ``first`` at azimuth 0, ``second`` mirrored to
    ``y ≥ 0``: what an isotropic BRDF depends on (θ of each, ``|φ2 − φ1|``), as (N, 6)."""
    azimuth = np.arctan2(first[:, 1], first[:, 0])
    cos, sin = np.cos(azimuth), np.sin(azimuth)
    first_x = cos * first[:, 0] + sin * first[:, 1]  # turned by -azimuth: on the +x half of the x-z plane
    second_x = cos * second[:, 0] + sin * second[:, 1]
    second_y = np.abs(cos * second[:, 1] - sin * second[:, 0])
    return np.column_stack([first_x, np.zeros(len(first)), first[:, 2], second_x, second_y, second[:, 2]])


#: Up to this many samples the nearest points are found by comparing every pair (:class:`_EveryPair`): a k-d tree's
#: construction and its worker threads cost more there (a capture's texels: 32 samples each, 4,096 texels paired in
#: 5.1 s with trees, most of it starting threads).
EVERY_PAIR_UP_TO = 256


class _EveryPair:
    """The nearest points of a few by their whole distance matrix, with the ``query`` of ``scipy.spatial.cKDTree``
    (k nearest in order; at ``distance_upper_bound`` or beyond, inf and index N)."""

    def __init__(self, points: np.ndarray):
        self.points, self.n = points, len(points)

    def query(self, asked: np.ndarray, k: int = 1, distance_upper_bound: float = np.inf, workers: int = 1):
        distances = np.linalg.norm(asked[:, None, :] - self.points[None, :, :], axis=-1)
        order = np.argsort(distances, axis=1, kind="stable")[:, :k]
        nearest = np.take_along_axis(distances, order, axis=1)
        beyond = nearest >= distance_upper_bound  # as cKDTree: a neighbour lies strictly within the bound
        nearest, order = np.where(beyond, np.inf, nearest), np.where(beyond, len(self.points), order)
        return (nearest[:, 0], order[:, 0]) if k == 1 else (nearest, order)


def _tree(points: np.ndarray, few: bool, **options) -> "cKDTree | _EveryPair":
    """What finds the nearest of ``points``: every pair compared where the file has ``few`` samples (at most
    :data:`EVERY_PAIR_UP_TO`), else a k-d tree (``options``: its). A band of a large file is never few: its whole
    distance matrix to 4,096 spacing queries would outweigh its tree."""
    if few:
        return _EveryPair(points)
    from scipy.spatial import cKDTree

    return cKDTree(points, **options)


#: The most samples in one k-d tree: larger files are paired band by band of ``cos θi − cos θo`` (:func:`_bands`), each
#: band's tree built, asked and dropped in turn, in the same time as one tree. A MERL-size file's pairing held ~130 MB
#: with one tree of every sample, and holds ~60 MB with bands (a fit compiles beside it: :class:`ReciprocityAhead`).
BAND_SAMPLES = 2**17
#: How far (in ``cos θi − cos θo``) a partner can lie from a first's swapped point: two points within ``r`` of each
#: other (at most :data:`MAX_TOLERANCE`) differ by at most ``√2·r`` in it, their two ``z`` differing by ``a`` and ``b``
#: with ``a² + b² ≤ r²``; 2 rather than √2 is a margin for rounding.
PARTNER_SLACK = 2 * MAX_TOLERANCE


def _cosine_difference(samples: Samples) -> np.ndarray:
    """``cos θi − cos θo`` of each sample: negative for a pair's second (and its first's swapped point)."""
    return samples.wi[:, 2] - samples.wo[:, 2]


def _bands(difference: np.ndarray) -> list[np.ndarray]:
    """Indices of the samples in bands of ``difference`` (:func:`_cosine_difference`), bounded by its quantiles: each
    of about :data:`BAND_SAMPLES` (more where many samples share a difference, as a grid's do); one band for most
    files."""
    count = -(-len(difference) // BAND_SAMPLES)
    if count <= 1:
        return [np.arange(len(difference))]
    edges = np.quantile(difference, np.arange(1, count) / count)  # a partition, not a sort: 20 ms, not 200
    edges = np.concatenate([[-np.inf], edges, [np.inf]])
    bands = [np.flatnonzero((difference > low) & (difference <= high)) for low, high in itertools.pairwise(edges)]
    return [band for band in bands if len(band)]  # a grid's repeated differences can make two edges one


def _spacing_asked(samples: Samples, general: bool, among: np.ndarray) -> np.ndarray:
    """The points whose neighbours estimate the spacing (:func:`_points`): those of the samples at indices ``among``,
    or of :data:`SPACING_SAMPLE` of them (a seeded choice)."""
    asked = among
    if len(asked) > SPACING_SAMPLE:
        asked = np.random.default_rng(0).choice(among, SPACING_SAMPLE, replace=False)
    return _points_at(samples, asked, general)


def _points_at(samples: Samples, indices: np.ndarray, general: bool) -> np.ndarray:
    """:func:`_points` of the samples at ``indices``, gathered into one array (in about a third of the time of
    gathering ``wi`` and ``wo`` first and stacking them)."""
    if not general:
        return _canonical(samples.wi[indices], samples.wo[indices])
    points = np.empty((len(indices), 6))
    np.take(samples.wi, indices, axis=0, out=points[:, :3])
    np.take(samples.wo, indices, axis=0, out=points[:, 3:])
    return points


#: Neighbours farther than this (radians) are not looked for when the spacing is estimated: where the median spacing
#: lies beyond it, or straddles it, half of it is beyond :data:`MAX_TOLERANCE`, the cap, whatever its value. (A band's
#: tree is asked for the neighbours of samples far outside it: unbounded, a MERL-size file's 4,096 queries took 130 ms
#: in a tree of half its samples, 7 ms bounded.)
SPACING_REACH = 2 * MAX_TOLERANCE / SPACING_FRACTION


def _nearest(asked: np.ndarray, tree: "cKDTree | _EveryPair", k: int) -> np.ndarray:
    """The distances from each of ``asked`` (M, 6) to its ``k`` nearest points of ``tree`` in order, inf beyond
    :data:`SPACING_REACH` and past the tree's size: (M, k)."""
    distances, _ = tree.query(asked, k=min(k, tree.n), distance_upper_bound=SPACING_REACH, workers=-1)
    distances = distances.reshape(len(asked), -1)  # one neighbour: one distance a point
    return np.pad(distances, ((0, 0), (0, k - distances.shape[1])), constant_values=np.inf)


def tolerance(nearest: np.ndarray) -> float:
    """The distance (radians, :func:`_points`) within which a partner is taken for the swapped point:
    :data:`SPACING_FRACTION` of the median distance from a sample to its nearest distinct neighbour, within
    [:data:`MIN_TOLERANCE`, :data:`MAX_TOLERANCE`]. ``nearest``: the distances from each asked sample
    (:func:`_spacing_asked`) to its :data:`SPACING_NEIGHBOURS` nearest samples (fewer where there are fewer), itself
    among them, in order; inf beyond :data:`SPACING_REACH`. A sample whose neighbours are all itself again says
    nothing.

    Half the spacing takes a partner nearer the swapped point than to any other measurement of the grid;
    the cap keeps a dense file's pairs close enough that a sharp lobe (a retro peak a few degrees wide) does not
    change between a pair's two samples."""
    if nearest.shape[1] < 2:
        return MIN_TOLERANCE
    again = nearest <= MIN_TOLERANCE  # the same point again is no neighbour
    spacing = np.where(again, np.inf, nearest).min(axis=1)[~again.all(axis=1)]
    if not len(spacing):
        return MIN_TOLERANCE
    return float(np.clip(SPACING_FRACTION * np.median(spacing), MIN_TOLERANCE, MAX_TOLERANCE))


#: Files of more samples than this are paired within a region of their pairs of directions (:func:`_region`).
REGION_ABOVE = 2**19
#: The region's grid: this many cells along each of ``s = cos θi + cos θo`` (in [0, 2]) and ``u = wi · wo`` (in
#: [−1, 1]), 0.25 wide,
REGION_CELLS = 8
#: each cut into this many along each for the lookups: 2 / (8 × 14) = 0.0179 wide, at least :data:`PARTNER_SLACK`.
REGION_FINE = 14


class _Region(NamedTuple):
    """Where a large file's pairs are looked for (:func:`_region`): ``queried``, a mask (N,) of the samples in it
    (a first there is asked for its partner); ``kept``, the indices of the samples in it or within
    :data:`PARTNER_SLACK` of it (the trees hold these alone); ``inner``, the indices of those that lie at least
    twice :data:`SPACING_REACH` inside it (the spacing's samples are chosen among these)."""

    queried: np.ndarray
    kept: np.ndarray
    inner: np.ndarray


def _swap_invariants(samples: Samples) -> tuple[np.ndarray, np.ndarray]:
    """``s = cos θi + cos θo`` and ``u = wi · wo`` of each sample: alike for a sample and its swapped point, the
    general one's and the isotropic one's alike (turning about the normal and mirroring keep both). Two points
    (:func:`_points`) ``r`` apart differ in each by at most ``√2·r``: ``|Δs| ≤ |Δwi| + |Δwo|``, and
    ``|a·b − a'·b'| = |a·(b − b') + (a − a')·b'| ≤ |Δwi| + |Δwo|`` for unit vectors."""
    wi, wo = samples.wi, samples.wo
    return wi[:, 2] + wo[:, 2], np.einsum("ij,ij->i", wi, wo)


def _region(samples: Samples, firsts: np.ndarray) -> _Region | None:
    """The region of a large file whose pairs are looked for: cells of the :data:`REGION_CELLS` grid of
    :func:`_swap_invariants`, taken in a seeded order until they hold :data:`MAX_QUERIES` of ``firsts`` (the indices
    of :func:`_firsts`; as many as are asked of any file). A first's partner lies within :data:`MAX_TOLERANCE` of its
    swapped point, whose ``s`` and ``u`` are its own: within ``√2`` × 0.5° (≤ :data:`PARTNER_SLACK`) of its cell. So
    the trees hold the region's
    samples and those beside it alone (a MERL-size file: 23% of its samples), and find every partner one tree of
    every sample finds for the same firsts; the spacing is estimated among samples whose neighbours within
    :data:`SPACING_REACH` all lie in the region (twice that inside it, ``√2`` × it in ``s`` and ``u``, with a margin
    for rounding). None where the file has too few firsts or inner samples for that (then every sample is asked)."""
    s, u = _swap_invariants(samples)
    lines = REGION_CELLS * REGION_FINE  # the fine grid's cells along each
    width = 2.0 / lines
    fine = np.clip((s / width).astype(np.intp), 0, lines - 1) * lines
    fine += np.clip(((u + 1.0) / width).astype(np.intp), 0, lines - 1)
    in_fine = np.bincount(fine[firsts], minlength=lines * lines)
    in_cells = in_fine.reshape(REGION_CELLS, REGION_FINE, REGION_CELLS, REGION_FINE).sum(axis=(1, 3)).ravel()
    order = np.random.default_rng(0).permutation(len(in_cells))
    enough = np.flatnonzero(np.cumsum(in_cells[order]) >= MAX_QUERIES)
    if not len(enough):
        return None
    cells = np.zeros(len(in_cells), bool)
    cells[order[: enough[0] + 1]] = True
    chosen = np.kron(cells.reshape(REGION_CELLS, REGION_CELLS), np.ones((REGION_FINE, REGION_FINE), bool))
    beside = _dilated(chosen, math.ceil(PARTNER_SLACK / width))
    inner = _eroded(chosen, math.ceil(2 * SPACING_REACH / width))
    region = _Region(chosen.ravel()[fine], np.flatnonzero(beside.ravel()[fine]), np.flatnonzero(inner.ravel()[fine]))
    return region if len(region.inner) >= SPACING_SAMPLE else None


def _dilated(grid: np.ndarray, reach: int) -> np.ndarray:
    """The cells of a boolean ``grid`` that lie within ``reach`` cells (along each axis) of one of its true cells."""
    return np.asarray(_windows(np.pad(grid, reach, constant_values=False), reach).any(axis=(2, 3)))


def _eroded(grid: np.ndarray, reach: int) -> np.ndarray:
    """The cells of a boolean ``grid`` whose cells within ``reach`` (along each axis) are all true; beyond the grid
    counts as true (no sample lies there)."""
    return np.asarray(_windows(np.pad(grid, reach, constant_values=True), reach).all(axis=(2, 3)))


def _windows(padded: np.ndarray, reach: int) -> np.ndarray:
    """The (2·reach + 1)² windows of a grid padded by ``reach``, one a cell of the grid: (rows, columns, w, w)."""
    return np.lib.stride_tricks.sliding_window_view(padded, (2 * reach + 1, 2 * reach + 1))


def _paired(samples: Samples, general: bool) -> Pairs:
    """:func:`_pairs`, computed: each queried sample's swapped point (:func:`_points`) looked up among the samples, its
    nearest taken within :func:`tolerance`. Not asked: a sample whose cosines differ by less than :data:`INFORMATIVE`,
    or that lies within twice the tolerance of its own swapped point (``wi`` near ``wo``: it would pair with itself or
    its neighbour); their ratios say nothing of a cosine factor.

    Band by band (:func:`_bands`): a band's k-d tree gives the spacing's nearest neighbours among its samples, and the
    nearest partner, within :data:`MAX_TOLERANCE`, of each swapped point that lies within :data:`PARTNER_SLACK` of it;
    the nearest of all bands are those of every sample at once (where two samples are equally near, a direction
    measured twice, either may be taken, as in one tree), and the tolerance, known at the end, keeps those within it.
    A file above :data:`REGION_ABOVE` samples asks those of a region alone, and its trees hold the samples in the
    region and beside it (:func:`_region`)."""
    wi, wo = samples.wi, samples.wo
    queries = _firsts(samples)
    region = _region(samples, queries) if len(wi) > REGION_ABOVE else None
    every = np.arange(len(wi))
    kept, among = (every, every) if region is None else (region.kept, region.inner)
    asked, k = _spacing_asked(samples, general, among), min(len(wi), SPACING_NEIGHBOURS)
    few = len(wi) <= EVERY_PAIR_UP_TO
    if region is not None:
        queries = queries[region.queried[queries]]
    if len(queries) > MAX_QUERIES:
        queries = np.sort(np.random.default_rng(0).choice(queries, MAX_QUERIES, replace=False))
    queries = queries[wi[queries, 2] >= INFORMATIVE * wo[queries, 2]]
    swapped = _points(wo[queries], wi[queries], general)  # only the queried ones' (N × 48 bytes less)
    own = np.linalg.norm(_points(wi[queries], wo[queries], general) - swapped, axis=1)
    difference = _cosine_difference(samples)
    swapped_difference = -difference[queries]
    nearest = np.full((len(asked), k), np.inf)
    distance, found = np.full(len(queries), np.inf), np.zeros(len(queries), np.int64)
    for band in _bands(difference[kept]):
        band = kept[band]
        tree = _tree(_points_at(samples, band, general), few, balanced_tree=False, compact_nodes=False)  # ~2× faster
        nearest = np.sort(np.hstack([nearest, _nearest(asked, tree, k)]), axis=1)[:, :k]
        lowest, highest = difference[band].min() - PARTNER_SLACK, difference[band].max() + PARTNER_SLACK
        near = np.flatnonzero((swapped_difference >= lowest) & (swapped_difference <= highest))
        if len(near):
            to, at = tree.query(swapped[near], k=1, distance_upper_bound=MAX_TOLERANCE, workers=-1)
            nearer = to < distance[near]
            distance[near[nearer]], found[near[nearer]] = to[nearer], band[at[nearer]]
    within = tolerance(nearest)
    matched = (distance < within) & (own > 2 * within)
    return queries[matched], found[matched], within
