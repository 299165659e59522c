"""Checks of a table's values, shared by every reader: each reports the first bad cell in one line.

``_jax.arrays.first_bad`` is the one scan for "the first row, then column, where something is wrong";
:class:`TableChecks` phrases what was wrong there, naming the row as the caller's ``locate`` does
(``samples.csv: row 3 (line 5)``, ``tape.dat: line 12``) and the column as its ``column`` does
(``column theta_o``, ``channel g``).
"""

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .._jax import first_bad
from ..errors import BrdfInputError
from ..physics.geometry import UNIT_LENGTH_TOLERANCE, normalised, spherical_to_direction

#: How a message names column ``k``.
ColumnName = Callable[[int], str]


def named(names: Sequence[str], kind: str = "column") -> ColumnName:
    """Columns named ``column theta_i`` (or ``channel g`` for ``kind="channel"``) after ``names``."""
    return lambda k: f"{kind} {names[k]}"


@dataclass(frozen=True)
class TableChecks:
    """One-line errors for the first bad cell of a table; ``locate(row)`` names a row in messages."""

    locate: Callable[[int], str]

    def fail_first(self, bad: np.ndarray, table, column: ColumnName, problem: Callable[[float], str]) -> None:
        """Raise for the first True of ``bad``: ``<row>, <column>: <problem(value)>``."""
        where = first_bad(bad)
        if where is None:
            return
        row, k = where
        value = np.asarray(table).reshape(len(bad), -1)[row, k]
        raise BrdfInputError(f"{self.locate(row)}, {column(k)}: {problem(value)}")

    def finite(self, table: np.ndarray, column: ColumnName) -> None:
        self.fail_first(~np.isfinite(table), table, column, lambda v: f"{v} is not allowed (values must be finite)")

    def non_negative(self, table: np.ndarray, column: ColumnName, problem: Callable[[float], str]) -> None:
        self.fail_first(table < 0, table, column, problem)

    def angles_to_directions(
        self,
        theta: np.ndarray,
        phi: np.ndarray,
        unit: str,
        theta_names: Sequence[str],
        phi_names: Sequence[str],
        because: str = "",
    ) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors (N, 3) of light and viewer from zeniths ``theta`` and azimuths ``phi`` (N, 2) in ``unit``.

        θ must lie in [0, 90°) (above the horizon) and φ within ±360°; ``because`` ends the message
        (why the angles were read in that unit).
        """
        right, full = (90.0, 360.0) if unit == "degrees" else (math.pi / 2, 2 * math.pi)
        self.fail_first(
            (theta < 0) | (theta >= right),
            theta,
            named(theta_names),
            lambda v: f"{v:g} is outside [0, {right:g}) {unit} (directions must be above the horizon){because}",
        )
        self.fail_first(
            np.abs(phi) > full,
            phi,
            named(phi_names),
            lambda v: f"{v:g} is outside [-{full:g}, {full:g}] {unit}{because}",
        )
        if unit == "degrees":
            theta, phi = np.radians(theta), np.radians(phi)
        directions = spherical_to_direction(theta, phi)
        return directions[:, 0], directions[:, 1]

    def unit_directions(self, vectors: np.ndarray, name: str) -> np.ndarray:
        """``vectors`` (N, 3) normalised, after checking they point above the horizon and have unit length."""
        components = [f"{name}_x", f"{name}_y", f"{name}_z"]
        self.fail_first(
            np.c_[np.zeros((len(vectors), 2), bool), vectors[:, 2] <= 0],
            vectors,
            named(components),
            lambda v: f"{v:g} ≤ 0: the direction is below the horizon (z must be > 0)",
        )
        return normalised(
            vectors,
            lambda row, length: (
                f"{self.locate(row)}, columns {', '.join(components)}: length {length:.6g} is not 1"
                f" (directions must be unit vectors, within {UNIT_LENGTH_TOLERANCE:g})"
            ),
        )

    def values_sigma_weight(
        self, values, channels: Sequence[str], sigma, weight, source: str, sigma_names: Sequence[str] | None = None
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Check values (≥ 0), sigma (finite, > 0) and weight (finite, ≥ 0, not all 0); returns sigma and weight.

        ``sigma_names``: the sigma column of each channel (default ``sigma_<channel>``).
        """
        self.non_negative(values, named(channels), lambda v: f"{v:g}: negative reflectance is not allowed")
        if sigma is not None:
            sigma = np.array(sigma, dtype=float)
            column = named(sigma_names or [f"sigma_{c}" for c in channels])
            self.finite(sigma, column)
            self.fail_first(sigma <= 0, sigma, column, lambda v: f"{v:g}: sigma must be > 0")
        if weight is not None:
            self.finite(weight, named(["weight"]))
            self.fail_first(weight < 0, weight, named(["weight"]), lambda v: f"{v:g}: weight must be ≥ 0")
            if not np.any(weight > 0):
                raise BrdfInputError(f"{source}: every weight is 0; at least one sample must count")
        return sigma, weight
