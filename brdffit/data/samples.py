"""Measured BRDF samples: the :class:`Samples` container.

Samples always hold BRDF values in 1/sr at unit direction pairs above the horizon, checked when they
are built (:meth:`Samples.from_arrays`, or a reader of ``load.py``).
"""

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..checks import max_theta as checked_max_theta
from ..errors import Argument, BrdfInputError
from ..physics.geometry import zenith_degrees
from .cells import TableChecks, named


@dataclass(frozen=True)
class Provenance:
    """How samples were read from a file: what a user may want to know and check.

    ``format``: the format's name. ``rows``: the data rows read. ``dropped``: ``(reason, rows)`` for every
    kind of row left out (below the horizon, missing). ``header_quantity``: what the file's header says its
    values are (None where it does not say). ``quantity``: what they were read as (``quantities.py``),
    ``quantity_given``: whether a user said so. ``sigma_from``: where a sigma came from, if not a column.
    ``reading``: the options of :func:`brdffit.load_samples`, other than ``quantity``, that were not their defaults
    and that make what is read (the format given, radians, a spectral conversion, MERL's bin centres), as ``(name,
    value)`` pairs: a fit's result records them, so that its export reads the file as the fit did.
    """

    format: str
    rows: int
    dropped: tuple[tuple[str, int], ...] = ()
    header_quantity: str | None = None
    quantity: str = "brdf"
    quantity_given: bool = False
    sigma_from: str | None = None
    reading: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True, eq=False)
class Samples:
    """BRDF measurements: direction pairs and per-channel values.

    ``wi``, ``wo``: (N, 3) unit vectors in the local frame (``z`` the normal, ``wi`` towards the light,
    ``wo`` towards the viewer), ``z > 0``. ``values``: (N, C) BRDF in 1/sr. ``channels``: C names.
    ``sigma``: (N, C) 1-σ uncertainties in 1/sr, or None. ``weight``: (N,) non-negative weights, or
    None. ``source`` names where they came from, ``provenance`` how they were read from a file (None for
    arrays). Build one with :func:`brdffit.load_samples` or :meth:`Samples.from_arrays`, which check the values.
    """

    wi: np.ndarray
    wo: np.ndarray
    values: np.ndarray
    channels: tuple[str, ...]
    sigma: np.ndarray | None = None
    weight: np.ndarray | None = None
    source: str = "<arrays>"
    provenance: Provenance | None = None

    def __repr__(self) -> str:
        extras = [name for name in ("sigma", "weight") if getattr(self, name) is not None]
        shown = ", ".join(self.channels[:4]) + (", …" if self.n_channels > 4 else "")
        return (
            f"Samples({self.n_samples} × {self.n_channels} channel(s) [{shown}]"
            f"{' with ' + ' and '.join(extras) if extras else ''} from {self.source})"
        )

    def _repr_html_(self) -> str:
        """What a notebook shows for bare samples: the counts, the angles' and the values' ranges, per channel."""
        import html

        theta_i, theta_o = self.theta_i, self.theta_o
        rows = "".join(
            f"<tr><td>{html.escape(str(name))}</td><td>{column.min():.4g}</td><td>{np.median(column):.4g}</td>"
            f"<td>{column.max():.4g}</td></tr>"
            for name, column in zip(self.channels, self.values.T, strict=True)
        )
        return (
            f"<div><b>{html.escape(repr(self))}</b><br>θi {theta_i.min():.1f}–{theta_i.max():.1f}°, θo"
            f" {theta_o.min():.1f}–{theta_o.max():.1f}°<table><tr><th>channel</th><th>min (1/sr)</th><th>median</th>"
            f"<th>max</th></tr>{rows}</table></div>"
        )

    @classmethod
    def from_arrays(
        cls,
        wi,
        wo,
        values,
        channels: Sequence[str] | None = None,
        sigma=None,
        weight=None,
        source: str = "<arrays>",
    ) -> "Samples":
        """Samples from arrays, with every check of the samples file; rows are named by index."""
        wi = _float_array(wi, "wi", source)
        wo = _float_array(wo, "wo", source)
        values = _float_array(values, "values", source)
        if values.ndim == 1:
            values = values[:, None]
        n = values.shape[0]
        for name, array in (("wi", wi), ("wo", wo)):
            if array.shape != (n, 3):
                raise BrdfInputError(f"{source}: {name} must have shape ({n}, 3), got {array.shape}")
        if channels is None:
            channels = ("value",) if values.shape[1] == 1 else tuple(f"c{k}" for k in range(values.shape[1]))
        channels = tuple(str(c) for c in channels)
        if len(channels) != values.shape[1]:
            raise BrdfInputError(f"{source}: {len(channels)} channel names for {values.shape[1]} value columns")
        if sigma is not None:
            sigma = _float_array(sigma, "sigma", source)
            try:  # one number, one per sample (N,) or (N, 1), or one per value (N, C)
                sigma = np.broadcast_to(sigma if sigma.ndim == 0 else sigma.reshape(n, -1), values.shape).copy()
            except ValueError:
                raise BrdfInputError(
                    f"{source}: sigma of shape {sigma.shape} does not fit values of shape {values.shape}"
                ) from None
        if weight is not None:
            weight = _float_array(weight, "weight", source).reshape(n)
        checks = TableChecks(lambda row: f"{source}: row {row}")
        for name, column in (("wi", wi), ("wo", wo)):
            checks.finite(column, named([f"{name}_x", f"{name}_y", f"{name}_z"]))
        checks.finite(values, named(channels))
        wi = checks.unit_directions(wi, "wi")
        wo = checks.unit_directions(wo, "wo")
        sigma, weight = checks.values_sigma_weight(values, channels, sigma, weight, source)
        return cls(wi, wo, values, channels, sigma, weight, source)

    # ------------------------------------------------------------------ views
    @property
    def n_samples(self) -> int:
        return self.values.shape[0]

    @property
    def n_channels(self) -> int:
        return self.values.shape[1]

    @property
    def theta_i(self) -> np.ndarray:
        """Zenith angle of the light, degrees."""
        return zenith_degrees(self.wi)

    @property
    def theta_o(self) -> np.ndarray:
        """Zenith angle of the viewer, degrees."""
        return zenith_degrees(self.wo)

    def light_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """The distinct light directions (L, 3) and, for each sample, the index of its own (N,): directions equal
        to 6 decimals (printed files round) are one. A gonioreflectometer has a few; random data one per sample."""
        distinct, index = np.unique(np.round(self.wi, 6), axis=0, return_inverse=True)
        return distinct, index.reshape(-1)

    def select(self, keep: np.ndarray) -> "Samples":
        """The samples where ``keep`` (a boolean mask or index array) selects."""
        return replace(
            self,
            wi=self.wi[keep],
            wo=self.wo[keep],
            values=self.values[keep],
            sigma=None if self.sigma is None else self.sigma[keep],
            weight=None if self.weight is None else self.weight[keep],
        )

    def inside(self, max_theta: float) -> np.ndarray:
        """Which samples have both θi and θo at most ``max_theta`` degrees: the one test of every selection by angle."""
        checked_max_theta(max_theta)
        return (self.theta_i <= max_theta) & (self.theta_o <= max_theta)

    def within(self, max_theta: float | None) -> "Samples":
        """The samples with both θi and θo at most ``max_theta`` degrees (all of them for None)."""
        if max_theta is None:
            return self
        kept = self.select(self.inside(max_theta))
        if kept.n_samples == 0:
            raise BrdfInputError(
                f"{self.source}: no samples have θi and θo ≤ ", Argument("max_theta", f"{max_theta:g}"), " degrees"
            )
        return kept


def _float_array(value, name: str, source: str) -> np.ndarray:
    try:
        return np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise BrdfInputError(f"{source}: {name} must be an array of numbers") from None
