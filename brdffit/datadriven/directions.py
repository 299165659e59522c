"""The direction pairs that best condition a coefficient fit (Nielsen, Jensen and Ramamoorthi 2015, §4).

Measured at pairs ``Ω``, the mapped material is ``m_Ω = mean_Ω + Q_Ω c`` with ``Q_Ω`` the components' rows at
those bins: the coefficients are best determined where ``Q_Ω`` is best conditioned. Nielsen et al. choose the
pairs greedily: each next pair is the candidate bin that gives the smallest condition number (largest over
smallest singular value) of the rows chosen so far plus its own; while fewer pairs than components are chosen
(every condition number is then that of a wide matrix), the one whose smallest singular value is largest.
Candidates are the bins the basis holds with both zenith angles at most ``max_theta`` and light and viewer at least
:data:`MIN_SEPARATION` apart, a seeded random subset of them when there are more than ``candidates``.

A directions file is a CSV of the pairs' angles in degrees, ``theta_i,phi_i,theta_o,phi_o``: what a
gonioreflectometer runs, ``brdffit synth --directions`` reads, and, with a value column added per channel, a
samples file ``brdffit fit`` reads.
"""

import csv
import io
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._files import reading, write_text_atomic
from ..errors import Argument, BrdfInputError
from ..physics.geometry import direction_to_spherical, spherical_to_direction
from ..physics.merl_table import bin_directions
from .basis import Basis

COLUMNS = ("theta_i", "phi_i", "theta_o", "phi_o")
#: Candidate bins scored at each greedy step (a seeded subset of the bins the basis holds).
CANDIDATES = 20_000
#: A condition number of the chosen rows beyond which the pairs barely determine the coefficients: the data's
#: errors reach them amplified 10⁴ times (greedy pairs of a real library: 7 to 70).
POOR_CONDITION = 1e4
#: Smallest angle between light and viewer, in degrees: no instrument puts its detector on its source.
MIN_SEPARATION = 5.0
#: Zenith angles beyond this are not chosen by default: few instruments reach them and the map weighs them little.
MAX_THETA = 80.0


def select_bins(
    basis: Basis,
    count: int,
    *,
    max_theta: float = MAX_THETA,
    candidates: int = CANDIDATES,
    seed: int = 0,
    progress=None,
) -> np.ndarray:
    """Flat bin indices (count,) chosen greedily to minimise the condition number of the components' rows;
    ``progress`` is called after each pair chosen (each scores every candidate: ~0.1 s early, more as rows grow)."""
    wi, wo = bin_directions()
    limit = np.cos(np.radians(max_theta))
    apart = np.sum(wi * wo, axis=1) <= np.cos(np.radians(MIN_SEPARATION))
    eligible = np.flatnonzero(basis.filled & (wi[:, 2] >= limit) & (wo[:, 2] >= limit) & apart)
    if eligible.size < count:
        raise BrdfInputError(
            Argument("n", count), f" pairs asked for, but only {eligible.size} bins lie within θ ≤ {max_theta:g}°"
        )
    if candidates < count:
        raise BrdfInputError(Argument("candidates", candidates), f" is fewer than the {count} pairs asked for")
    rng = np.random.default_rng(seed)
    pool = np.sort(rng.choice(eligible, size=min(candidates, eligible.size), replace=False))
    rows = basis.components[:, pool].T.astype(np.float64)  # (candidates, K)
    chosen: list[int] = []
    available = np.ones(pool.size, bool)
    for _ in range(count):
        trial = np.concatenate(
            [np.broadcast_to(rows[chosen], (pool.size, len(chosen), rows.shape[1])), rows[:, None]], 1
        )
        singular = np.linalg.svd(trial, compute_uv=False)  # (candidates, min(t+1, K)), largest first
        with np.errstate(divide="ignore", invalid="ignore"):
            if len(chosen) + 1 < rows.shape[1]:  # fewer rows than components: the largest smallest singular value
                condition = np.where(singular[:, -1] > 0, 1.0 / singular[:, -1], np.inf)
            else:
                condition = np.where(singular[:, -1] > 0, singular[:, 0] / singular[:, -1], np.inf)
        condition[~available] = np.inf
        best = int(np.argmin(condition))
        if not np.isfinite(condition[best]):  # rank-deficient whatever is added: take the row of largest norm
            norms = np.where(available, np.linalg.norm(rows, axis=1), -1.0)
            best = int(np.argmax(norms))
        chosen.append(best)
        available[best] = False
        if progress is not None:
            progress(1)
    return pool[chosen]


def choose_directions(
    basis: "Basis | str | os.PathLike",
    n: int = 20,
    *,
    max_theta: float = MAX_THETA,
    candidates: int = CANDIDATES,
    seed: int = 0,
    progress=None,
) -> "Chosen":
    """The ``n`` pairs that best condition a coefficient fit (:func:`select_bins`): their angles (n, 4) in degrees,
    ``theta_i, phi_i, theta_o, phi_o`` (what :func:`write_directions` writes), and the condition number there;
    ``basis`` a :class:`Basis` or its file."""
    from ..checks import whole_number
    from .basis import load_basis

    if not isinstance(basis, Basis):
        basis = load_basis(basis)
    whole_number("n", n)
    whole_number("candidates", candidates)
    whole_number("seed", seed, minimum=0)
    if not 0 < max_theta <= 90:
        raise BrdfInputError(Argument("max_theta", f"{max_theta:g}"), ": must lie in (0, 90] degrees")
    bins = select_bins(basis, n, max_theta=max_theta, candidates=candidates, seed=seed, progress=progress)
    return Chosen(bin_angles_degrees(bins), condition_number(basis, bins))


class Chosen(NamedTuple):
    """Pairs chosen to measure: ``angles`` (n, 4) in degrees and the ``condition`` number of the fit there."""

    angles: np.ndarray
    condition: float

    @property
    def poorly_conditioned(self) -> bool:
        """Whether the pairs barely determine the coefficients (:data:`POOR_CONDITION`): a fit then leans on the
        ridge, not on the measurements."""
        return not self.condition < POOR_CONDITION


def condition_number(basis: Basis, bins: np.ndarray) -> float:
    """The condition number of the components' rows at ``bins``."""
    singular = np.linalg.svd(basis.components[:, bins].T.astype(np.float64), compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")


def bin_angles_degrees(bins: np.ndarray) -> np.ndarray:
    """``theta_i, phi_i, theta_o, phi_o`` (count, 4) in degrees of the bins' directions."""
    wi, wo = bin_directions()
    theta_i, phi_i = direction_to_spherical(wi[bins])
    theta_o, phi_o = direction_to_spherical(wo[bins])
    return np.degrees(np.stack([theta_i, phi_i, theta_o, phi_o], axis=1))


def write_directions(angles: np.ndarray, path: str | os.PathLike) -> None:
    """Write pairs' angles (count, 4) in degrees as a directions CSV, atomically."""
    angles = np.asarray(angles, dtype=float)
    if angles.ndim != 2 or angles.shape[1] != 4 or angles.shape[0] == 0:
        raise BrdfInputError(
            f"{path}: angles must have shape (N, 4) (theta_i, phi_i, theta_o, phi_o), got {angles.shape}"
        )
    zenith = angles[:, [0, 2]]
    if not np.all(np.isfinite(angles)) or np.any((zenith < 0) | (zenith > 90)):
        raise BrdfInputError(f"{path}: angles must be finite, zenith angles in [0, 90] degrees")
    lines = [",".join(COLUMNS)] + [",".join(f"{value:.10g}" for value in row) for row in angles]
    write_text_atomic(path, "\n".join(lines) + "\n")


def read_directions(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """``wi, wo`` (N, 3) of a directions CSV (its angle columns; other columns are ignored), with one-line errors
    naming the file and row."""
    with reading(path, "a directions file"):
        data = Path(path).read_bytes()
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise BrdfInputError(f"{path}: not a text file (not UTF-8); a directions file is text") from None
    lines = csv.reader(io.StringIO(text, newline=None))  # universal newlines: a bare \r ends a line, as elsewhere
    try:
        rows = [row for row in lines if row and not row[0].lstrip().startswith("#")]
    except csv.Error as error:  # a field beyond csv's limit (128 KiB), an unpaired quote at the end
        raise BrdfInputError(f"{path}: line {lines.line_num}: not a CSV row ({error})") from None
    if not rows:
        raise BrdfInputError(f"{path}: empty; a directions file has a header {','.join(COLUMNS)} and a row per pair")
    header = [name.strip().lower() for name in rows[0]]
    missing = [name for name in COLUMNS if name not in header]
    if missing:
        raise BrdfInputError(f"{path}: header lacks {', '.join(missing)}; a directions file has {','.join(COLUMNS)}")
    positions = [header.index(name) for name in COLUMNS]
    angles = np.empty((len(rows) - 1, 4))
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise BrdfInputError(f"{path}: row {number}: {len(row)} fields, but the header names {len(header)}")
        try:
            angles[number - 2] = [float(row[position]) for position in positions]
        except (ValueError, IndexError):
            raise BrdfInputError(f"{path}: row {number}: the angles must be four numbers (degrees)") from None
        zenith = angles[number - 2, [0, 2]]
        if not np.all(np.isfinite(angles[number - 2])) or np.any((zenith < 0) | (zenith > 90)):
            raise BrdfInputError(f"{path}: row {number}: zenith angles must lie in [0, 90] degrees")
    if angles.shape[0] == 0:
        raise BrdfInputError(f"{path}: no pairs after the header")
    radians = np.radians(angles)
    return spherical_to_direction(radians[:, 0], radians[:, 1]), spherical_to_direction(radians[:, 2], radians[:, 3])
