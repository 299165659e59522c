"""Reciprocity, ``f(wi, wo) = f(wo, wi)`` (Helmholtz): a check of what a file's values are.

Every BRDF is reciprocal; a cosine-weighted value is not. So on data that measure both directions of a
pair, the ratio of the two values says what the file holds: a median ratio ``f(a→b) / f(b→a)`` near 1 for
BRDF values, ``cos θb / cos θa`` away from 1 for values weighted by the light's cosine, its inverse for the
view's. Pairs are oriented with the light nearer the normal (``θi < θo``), so that a cosine reading moves
every ratio the same way.

A pair is two samples whose directions are swapped: ``wi`` and ``wo`` exchanged where the data hold at least
:data:`MIN_PAIRS` of those, else (isotropic measurements, the light at one azimuth) the zeniths exchanged at
the same ``|φo − φi|``. Angles match on a 0.01° grid.
"""

import collections
import functools
import hashlib
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.geometry import direction_to_spherical, zenith_degrees
from .quantities import stored_factor
from .samples import Samples

#: Below this many pairs the check says nothing.
MIN_PAIRS = 20
#: Median ratios inside this band are reciprocal; outside it a fit warns (a factor of 1.25 either way).
RECIPROCAL = (0.8, 1.25)
#: Angles are matched on a grid of this step, degrees.
GRID_DEGREES = 0.01


@dataclass(frozen=True)
class Reciprocity:
    """What the reciprocal pairs of some samples say about their values.

    ``pairs``: how many were found, and of which ``kind`` (``"swapped directions"`` or ``"isotropic"``).
    ``ratios``: for each reading of the file's values (``brdf``, ``cosine-weighted-in``,
    ``cosine-weighted-out``), the median of ``f(a→b) / f(b→a)`` over pairs and channels. ``in_force``: the
    quantity the samples were read as.
    """

    pairs: int
    kind: str
    ratios: dict[str, float]
    in_force: str

    @property
    def as_read(self) -> float:
        """The median ratio of the samples as they were read."""
        return self.ratios[_reading(self.in_force)]

    @property
    def reciprocal(self) -> bool:
        """Whether the samples as read are reciprocal (median ratio within :data:`RECIPROCAL`)."""
        return RECIPROCAL[0] <= self.as_read <= RECIPROCAL[1]

    @property
    def best(self) -> str:
        """The reading whose median ratio is nearest 1."""
        return min(self.ratios, key=lambda reading: abs(np.log(self.ratios[reading])))


#: How many geometries' pairs :func:`_pairs` keeps.
KEPT_GEOMETRIES = 8
#: The most samples whose partners are looked for, per pairing: a check of the median ratio needs no more, and a
#: MERL-size file (1.4 million samples, no partners when its directions are random) is paired in ~0.4 s, not 2 s.
#: Above it, a seeded random choice of them (the same each run).
MAX_QUERIES = 2**17
_kept: collections.OrderedDict = collections.OrderedDict()
_kept_lock = threading.Lock()


def reciprocity(samples: Samples) -> Reciprocity | None:
    """The reciprocity of ``samples`` (None when they hold fewer than :data:`MIN_PAIRS` pairs)."""
    in_force = samples.provenance.quantity if samples.provenance is not None else "brdf"
    geometry = _geometry_key(samples)
    bins = functools.cache(functools.partial(_bins, samples))  # binned at most once, for both pairings
    pairs, kind = _pairs(geometry, bins, general=True), "swapped directions"
    if len(pairs[0]) < MIN_PAIRS:
        pairs, kind = _pairs(geometry, bins, general=False), "isotropic (zeniths swapped, same |φo − φi|)"
    if len(pairs[0]) < MIN_PAIRS:
        return None
    first, second = pairs
    stored = samples.values * stored_factor(in_force, samples.wi, samples.wo)
    ratios = {}
    for reading in ("brdf", "cosine-weighted-in", "cosine-weighted-out"):
        brdf = stored / stored_factor(reading, samples.wi, samples.wo)
        a, b = brdf[first], brdf[second]
        usable = (a > 0) & (b > 0)
        ratios[reading] = float(np.median(a[usable] / b[usable])) if np.any(usable) else float("nan")
    return Reciprocity(len(first), kind, ratios, in_force)


def _reading(quantity: str) -> str:
    """The reading a quantity stands for (a reflectance factor is a BRDF times π: the same ratios)."""
    return "brdf" if quantity in ("brdf", "reflectance-factor") else quantity


Pairs = tuple[np.ndarray, np.ndarray]


def _geometry_key(samples: Samples) -> tuple:
    """What names the directions of ``samples``: a digest of their bytes (~10 µs for 500 pairs) and their count."""
    digest = hashlib.blake2b(digest_size=16)
    digest.update(np.ascontiguousarray(samples.wi).data)
    digest.update(np.ascontiguousarray(samples.wo).data)
    return digest.digest(), len(samples.wi)


def _pairs(geometry: tuple, bins: Callable[[], tuple[np.ndarray, ...]], general: bool) -> Pairs:
    """Indices ``(first, second)`` of reciprocal pairs, ``first`` with ``θi < θo``, each pair once: with the
    directions swapped (``general``), or with the zeniths swapped at the same ``|φo − φi|`` (isotropic
    measurements).

    They depend on the directions alone, which the texels of a capture or the materials of a gonioreflectometer
    share: the last :data:`KEPT_GEOMETRIES` are kept, by ``geometry`` (:func:`_geometry_key`; pairing 500 takes
    ~0.2 ms). ``bins``: :func:`_bins` of the samples, asked only when the pairs are not kept."""
    key = (*geometry, general)
    with _kept_lock:
        if key in _kept:
            _kept.move_to_end(key)
            return _kept[key]
    found = _paired(bins(), general)
    for indices in found:
        indices.flags.writeable = False  # shared by every later caller
    with _kept_lock:
        _kept[key] = found
        while len(_kept) > KEPT_GEOMETRIES:
            _kept.popitem(last=False)
    return found


def _bins(samples: Samples) -> tuple[np.ndarray, ...]:
    """Each direction's zenith and azimuth on a 0.01° grid, and the samples whose partners are looked for (those
    with ``θi < θo``, at most :data:`MAX_QUERIES`, a seeded choice)."""
    theta_i, theta_o = (np.rint(zenith_degrees(w) / GRID_DEGREES).astype(np.int64) for w in (samples.wi, samples.wo))
    phi_i, phi_o = (
        np.rint(np.degrees(direction_to_spherical(w)[1]) % 360.0 / GRID_DEGREES).astype(np.int64) % 36000
        for w in (samples.wi, samples.wo)
    )
    queries = np.flatnonzero(theta_i < theta_o)
    if len(queries) > MAX_QUERIES:
        queries = np.sort(np.random.default_rng(0).choice(queries, MAX_QUERIES, replace=False))
    return theta_i, phi_i, theta_o, phi_o, queries


def _paired(bins: tuple[np.ndarray, ...], general: bool) -> Pairs:
    """:func:`_pairs`, computed from :func:`_bins`: the directions packed into one integer key per sample, and the
    partner keys of the queried samples looked up among the sorted keys."""
    theta_i, phi_i, theta_o, phi_o, queries = bins
    if general:
        keys = _packed(theta_i, phi_i, theta_o, phi_o)
        partners = _packed(theta_o[queries], phi_o[queries], theta_i[queries], phi_i[queries])
    else:
        delta = np.abs(phi_o - phi_i)
        delta = np.minimum(delta, 36000 - delta)
        keys = _packed(theta_i, theta_o, delta)
        partners = _packed(theta_o[queries], theta_i[queries], delta[queries])
    return _matched(keys, partners, queries)


def _matched(keys: np.ndarray, partners: np.ndarray, queries: np.ndarray) -> Pairs:
    """``(queries[j], i)`` for each ``partners[j]`` equal to some ``keys[i]``."""
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    by_partner = np.argsort(partners)  # sorted lookups walk the sorted keys once: ~2× faster on a million
    position = np.empty(len(partners), dtype=np.int64)
    position[by_partner] = np.searchsorted(ordered, partners[by_partner])
    position = np.minimum(position, len(keys) - 1)
    found = ordered[position] == partners
    return queries[found], order[position[found]]


def _packed(*columns: np.ndarray) -> np.ndarray:
    """Integer columns (each < 2¹⁶, the first < 2¹⁵: a zenith, ≤ 9000) as one int64 key."""
    key = np.zeros(len(columns[0]), dtype=np.int64)
    for column in columns:
        key = key * 65536 + column
    return key
