"""Measured BRDF samples: the :class:`Samples` container and the CSV samples file.

The file format is SPEC section 4: one measurement per row, comma- or
whitespace-separated, ``#`` comments, one header row naming

* the geometry: ``theta_i, phi_i, theta_o, phi_o`` (degrees unless
  ``angles="radians"``) or ``wi_x, wi_y, wi_z, wo_x, wo_y, wo_z``;
* the values: ``value``, or ``r, g, b``, or any other numeric columns, taken
  as named channels in file order (spectral bands named by wavelength);
* optionally ``sigma`` (or ``sigma_<channel>`` for each channel), the 1-σ
  uncertainty in the units of the values, and ``weight``.

``quantity`` says what the values are: ``brdf`` (1/sr, the default),
``reflectance-factor`` (``R = π f``) or ``cosine-weighted`` (``f · cos θi``).
Samples always hold BRDF values in 1/sr.

Bad input raises :class:`~brdffit.errors.BrdfInputError` with one line naming the
file, the row (and its line in the file) and the column.
"""

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .._files import reading, write_text_atomic
from ..errors import BrdfInputError
from ..physics.geometry import direction_to_spherical, spherical_to_direction

ANGLE_COLUMNS = ("theta_i", "phi_i", "theta_o", "phi_o")
VECTOR_COLUMNS = ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")
RGB_COLUMNS = ("r", "g", "b")
QUANTITIES = ("brdf", "reflectance-factor", "cosine-weighted")
ANGLE_UNITS = ("degrees", "radians")
#: Column-name prefixes that belong to the geometry, never to a channel.
_GEOMETRY_PREFIXES = ("theta", "phi", "wi_", "wo_")
#: Direction vectors may deviate this much from unit length (printed files round); they are then normalised.
UNIT_LENGTH_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class Samples:
    """BRDF measurements: direction pairs and per-channel values.

    ``wi``, ``wo``: (N, 3) unit vectors in the local frame (SPEC section 1),
    ``z > 0``. ``values``: (N, C) BRDF in 1/sr. ``channels``: C names.
    ``sigma``: (N, C) 1-σ uncertainties in 1/sr, or None. ``weight``: (N,)
    non-negative weights, or None. ``source`` names where they came from.
    Build one with :func:`load_samples` or :meth:`Samples.from_arrays`, which check the values.
    """

    wi: np.ndarray
    wo: np.ndarray
    values: np.ndarray
    channels: tuple[str, ...]
    sigma: np.ndarray | None = None
    weight: np.ndarray | None = None
    source: str = "<arrays>"

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
        locate = lambda row: f"{source}: row {row}"
        checked = _Checked(locate)
        for name, column in (("wi", wi), ("wo", wo)):
            checked.finite(column, [f"{name}_x", f"{name}_y", f"{name}_z"])
        checked.finite(values, list(channels))
        wi = checked.unit_directions(wi, "wi")
        wo = checked.unit_directions(wo, "wo")
        return checked.samples(wi, wo, values, channels, sigma, weight, source)

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
        return np.degrees(np.arccos(np.clip(self.wi[:, 2], -1.0, 1.0)))

    @property
    def theta_o(self) -> np.ndarray:
        """Zenith angle of the viewer, degrees."""
        return np.degrees(np.arccos(np.clip(self.wo[:, 2], -1.0, 1.0)))

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

    def within(self, max_theta: float | None) -> "Samples":
        """The samples with both θi and θo at most ``max_theta`` degrees (all of them for None)."""
        if max_theta is None:
            return self
        if not (isinstance(max_theta, int | float) and 0 < max_theta <= 90):
            raise BrdfInputError(f"--max-theta {max_theta!r} is not allowed; give degrees in (0, 90]")
        kept = self.select((self.theta_i <= max_theta) & (self.theta_o <= max_theta))
        if kept.n_samples == 0:
            raise BrdfInputError(f"{self.source}: no samples have θi and θo ≤ --max-theta {max_theta:g} degrees")
        return kept


# ---------------------------------------------------------------------- loading
def load_samples(
    path: str | os.PathLike,
    *,
    format: str | None = None,
    angles: str = "degrees",
    quantity: str = "brdf",
    spectral_to: str = "keep",
    illuminant: str = "D65",
    observer: str = "CIE 1931 2 Degree Standard Observer",
    subsample: int | None = None,
    subsample_method: str = "random",
    seed: int = 0,
) -> Samples:
    """Read a measurement file into :class:`Samples` holding BRDF values in 1/sr.

    ``format``: ``csv`` (SPEC section 4), ``merl``, ``alta`` or ``astm``
    (``brdffit/formats``); default: from the file's extension and first lines.
    ``angles``: ``"degrees"`` (default) or ``"radians"`` for a CSV file's angle
    columns. ``quantity``: what the values are, one of ``brdf``,
    ``reflectance-factor``, ``cosine-weighted``. ``spectral_to``: for value
    columns named by wavelength in nm, ``xyz`` or ``rgb`` (linear sRGB) under
    ``illuminant`` and ``observer`` (colour-science names), or ``keep`` every
    band as a channel (default). ``subsample`` (MERL): keep that many samples,
    ``subsample_method`` ``random`` or ``stratified`` over θh, seeded by ``seed``.
    """
    _check_choice("--angles", angles, ANGLE_UNITS)
    _check_choice("--quantity", quantity, QUANTITIES)
    from .load import detect_format

    path = Path(path)
    kind = detect_format(path, format)
    if kind != "csv" and angles != "degrees":
        raise BrdfInputError(f"--angles applies to CSV files; {path} is {kind} (its angle units are fixed)")
    if kind != "merl" and subsample is not None:
        raise BrdfInputError(f"--subsample applies to MERL files; {path} is {kind}")
    if kind == "csv":
        samples = _parse_csv(_read_text(path), str(path), angles)
    elif kind == "merl":
        from .merl import read_merl

        samples = read_merl(path, subsample=subsample, subsample_method=subsample_method, seed=seed)
    elif kind == "alta":
        from .alta import read_alta

        samples = read_alta(path)
    else:
        from .astm import read_astm

        samples = read_astm(path)
    if quantity != "brdf":
        scale = _brdf_scale(quantity, samples.wi[:, 2])
        samples = replace(
            samples, values=samples.values * scale, sigma=None if samples.sigma is None else samples.sigma * scale
        )
    from .spectral import spectral_to as convert  # "keep" returns the samples as they are

    return convert(samples, spectral_to, illuminant=illuminant, observer=observer)


def _check_choice(option: str, value: str, allowed: Sequence[str]) -> None:
    if value not in allowed:
        raise BrdfInputError(f"{option} {value!r} is not allowed; choose one of: {', '.join(allowed)}")


def _read_text(path: Path) -> str:
    with reading(path, "a samples file"):
        try:
            return path.read_text(encoding="utf-8-sig")  # a byte-order mark (Excel) is not part of the header
        except UnicodeDecodeError:
            raise BrdfInputError(f"{path}: not a text file (not UTF-8); samples files are CSV text") from None


def _parse_csv(text: str, source: str, angles: str) -> Samples:
    lines = [(number, line) for number, line in enumerate(text.splitlines(), start=1)]
    content = [(number, line) for number, line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not content:
        raise BrdfInputError(f"{source}: empty table (no header row and no data)")
    header_line, header = content[0]
    rows = content[1:]
    if not rows:
        raise BrdfInputError(f"{source}: empty table (a header row but no data rows)")
    delimiter = "," if "," in header else None
    names = [name.strip() for name in header.split(delimiter)]
    layout = _Layout.from_header(names, source, header_line)
    line_numbers = np.array([number for number, _ in rows])
    table = _parse_numbers([line for _, line in rows], line_numbers, names, delimiter, source)

    locate = lambda row: f"{source}: row {row + 1} (line {line_numbers[row]})"
    checked = _Checked(locate)
    checked.finite(table, names)
    if layout.angles:
        wi, wo = checked.directions_from_angles(table[:, layout.geometry], angles)
    else:
        geometry = table[:, layout.geometry]
        wi = checked.unit_directions(geometry[:, :3], "wi")
        wo = checked.unit_directions(geometry[:, 3:], "wo")
    values = table[:, layout.values]
    sigma = None if layout.sigma is None else np.broadcast_to(table[:, layout.sigma], values.shape)
    weight = None if layout.weight is None else table[:, layout.weight]
    return checked.samples(wi, wo, values, layout.channels, sigma, weight, source, layout.sigma_names)


def _brdf_scale(quantity: str, cos_i: np.ndarray) -> np.ndarray:
    """Factor (N, 1) that turns values of ``quantity`` into BRDF values (1/sr)."""
    if quantity == "reflectance-factor":
        return np.full((cos_i.size, 1), 1.0 / math.pi)
    if quantity == "cosine-weighted":
        return (1.0 / cos_i)[:, None]
    return np.ones((cos_i.size, 1))


def _parse_numbers(lines: list[str], line_numbers, names: list[str], delimiter, source: str) -> np.ndarray:
    """The data rows as an (N, columns) float array; on any failure, name the first bad cell."""
    try:
        table = np.loadtxt(lines, delimiter=delimiter, comments="#", dtype=float, ndmin=2)
        if table.shape == (len(lines), len(names)):
            return table
    except ValueError:
        pass
    for row, line in enumerate(lines):
        cells = [cell.strip() for cell in line.split("#", 1)[0].split(delimiter)]
        where = f"{source}: row {row + 1} (line {line_numbers[row]})"
        if len(cells) != len(names):
            raise BrdfInputError(f"{where}: {len(cells)} cells, but the header names {len(names)} columns")
        for name, cell in zip(names, cells, strict=True):
            try:
                float(cell)
            except ValueError:
                shown = "an empty cell" if not cell else repr(cell)
                raise BrdfInputError(f"{where}, column {name}: {shown} is not a number") from None
    raise BrdfInputError(
        f"{source}: the table could not be read as numbers"
    )  # pragma: no cover - loadtxt and the scan agree


@dataclass(frozen=True)
class _Layout:
    """Which header columns hold the geometry, values, sigma and weight."""

    angles: bool
    geometry: list[int]
    values: list[int]
    channels: tuple[str, ...]
    sigma: list[int] | None
    sigma_names: list[str] | None
    weight: int | None

    @classmethod
    def from_header(cls, names: list[str], source: str, line: int) -> "_Layout":
        where = f"{source}: header (line {line})"
        lower = [name.lower() for name in names]
        for index, name in enumerate(lower):
            if not name:
                raise BrdfInputError(f"{where}: column {index + 1} has no name")
            if name in lower[:index]:
                raise BrdfInputError(f"{where}: column {names[index]!r} appears twice")
        position = {name: index for index, name in enumerate(lower)}
        has_angles = any(name in position for name in ANGLE_COLUMNS)
        has_vectors = any(name in position for name in VECTOR_COLUMNS)
        geometry_help = f"geometry is {', '.join(ANGLE_COLUMNS)} or {', '.join(VECTOR_COLUMNS)}"
        if has_angles and has_vectors:
            raise BrdfInputError(
                f"{where}: both angle and direction-vector columns; give one geometry ({geometry_help})"
            )
        if not (has_angles or has_vectors):
            raise BrdfInputError(f"{where}: no geometry columns; {geometry_help}")
        wanted = ANGLE_COLUMNS if has_angles else VECTOR_COLUMNS
        for name in wanted:
            if name not in position:
                raise BrdfInputError(f"{where}: missing column {name!r}; {geometry_help}")
        geometry = [position[name] for name in wanted]

        rest = [index for index in range(len(names)) if lower[index] not in wanted]
        weight = position.get("weight")
        sigma_columns = [i for i in rest if lower[i] == "sigma" or lower[i].startswith("sigma_")]
        value_columns = [i for i in rest if i != weight and i not in sigma_columns]
        for index in value_columns:
            if lower[index].startswith(_GEOMETRY_PREFIXES):
                raise BrdfInputError(f"{where}: unknown column {names[index]!r}; {geometry_help}")
        value_names = [lower[i] for i in value_columns]
        if "value" in value_names or any(name in RGB_COLUMNS for name in value_names):
            expected = ["value"] if "value" in value_names else list(RGB_COLUMNS)
            for index in value_columns:
                if lower[index] not in expected:
                    raise BrdfInputError(
                        f"{where}: unknown column {names[index]!r}; with {', '.join(expected)} no other value columns"
                        " are allowed (optional: sigma, sigma_<channel>, weight)"
                    )
            for name in expected:
                if name not in value_names:
                    raise BrdfInputError(f"{where}: missing column {name!r}; RGB values need r, g and b")
            value_columns = [position[name] for name in expected]
            channels = tuple(expected)
        else:
            channels = tuple(names[i] for i in value_columns)
        if not value_columns:
            raise BrdfInputError(f"{where}: no value columns; give value, or r, g, b, or named channels")

        sigma, sigma_names = None, None
        if sigma_columns:
            if len(sigma_columns) == 1 and lower[sigma_columns[0]] == "sigma":
                sigma, sigma_names = sigma_columns, [names[sigma_columns[0]]] * len(channels)
            else:
                by_channel = {lower[i][len("sigma_") :]: i for i in sigma_columns}
                for index in sigma_columns:
                    if lower[index] == "sigma":
                        raise BrdfInputError(
                            f"{where}: give either one 'sigma' column or one sigma_<channel> per channel, not both"
                        )
                    if lower[index][len("sigma_") :] not in [c.lower() for c in channels]:
                        raise BrdfInputError(
                            f"{where}: unknown column {names[index]!r}; sigma columns are sigma_<channel>"
                            f" for channels {', '.join(channels)}"
                        )
                missing = [c for c in channels if c.lower() not in by_channel]
                if missing:
                    raise BrdfInputError(
                        f"{where}: missing column 'sigma_{missing[0]}'; give a sigma for every channel or one 'sigma'"
                    )
                sigma = [by_channel[c.lower()] for c in channels]
                sigma_names = [names[i] for i in sigma]
        return cls(has_angles, geometry, value_columns, channels, sigma, sigma_names, weight)


class _Checked:
    """The value checks shared by files and arrays; ``locate(row)`` names a row in messages."""

    def __init__(self, locate: Callable[[int], str]):
        self.locate = locate

    def _fail_first(self, bad: np.ndarray, names: Sequence[str], problem: Callable[[float], str], table) -> None:
        if not np.any(bad):
            return
        bad = bad.reshape(bad.shape[0], -1)
        row, column = np.unravel_index(np.argmax(bad), bad.shape)
        value = np.asarray(table).reshape(bad.shape)[row, column]
        raise BrdfInputError(f"{self.locate(row)}, column {names[column]}: {problem(value)}")

    def finite(self, table: np.ndarray, names: Sequence[str]) -> None:
        self._fail_first(~np.isfinite(table), names, lambda v: f"{v} is not allowed (values must be finite)", table)

    def non_negative(self, table: np.ndarray, names: Sequence[str], message: str) -> None:
        self._fail_first(table < 0, names, lambda v: f"{v:g}: {message}", table)

    def directions_from_angles(self, angles: np.ndarray, unit: str) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors (N, 3) for light and viewer from ``theta_i, phi_i, theta_o, phi_o``."""
        right, full = (90.0, 360.0) if unit == "degrees" else (math.pi / 2, 2 * math.pi)
        theta = angles[:, [0, 2]]
        phi = angles[:, [1, 3]]
        self._fail_first(
            (theta < 0) | (theta >= right),
            ["theta_i", "theta_o"],
            lambda v: f"{v:g} is outside [0, {right:g}) {unit} (directions must be above the horizon)",
            theta,
        )
        self._fail_first(
            np.abs(phi) > full, ["phi_i", "phi_o"], lambda v: f"{v:g} is outside [-{full:g}, {full:g}] {unit}", phi
        )
        if unit == "degrees":
            theta, phi = np.radians(theta), np.radians(phi)
        directions = np.asarray(spherical_to_direction(theta, phi))
        return directions[:, 0], directions[:, 1]

    def unit_directions(self, vectors: np.ndarray, name: str) -> np.ndarray:
        """``vectors`` normalised after checking they point above the horizon and have unit length."""
        components = [f"{name}_x", f"{name}_y", f"{name}_z"]
        self._fail_first(
            np.c_[np.zeros((len(vectors), 2), bool), vectors[:, 2] <= 0],
            components,
            lambda v: f"{v:g} ≤ 0: the direction is below the horizon (z must be > 0)",
            vectors,
        )
        return normalised(
            vectors,
            lambda row, length: (
                f"{self.locate(row)}, columns {', '.join(components)}: length {length:.6g} is not 1"
                f" (directions must be unit vectors, within {UNIT_LENGTH_TOLERANCE:g})"
            ),
        )

    def samples(self, wi, wo, values, channels, sigma, weight, source, sigma_names=None) -> Samples:
        """Check values, sigma and weight, and build the :class:`Samples`.

        ``sigma_names``: the sigma column for each channel (default ``sigma_<channel>``).
        """
        self.non_negative(values, channels, "negative reflectance is not allowed")
        if sigma is not None:
            sigma = np.array(sigma, dtype=float)
            names = sigma_names or [f"sigma_{c}" for c in channels]
            self.finite(sigma, names)
            self._fail_first(sigma <= 0, names, lambda v: f"{v:g}: sigma must be > 0", sigma)
        if weight is not None:
            self.finite(weight, ["weight"])
            self._fail_first(weight < 0, ["weight"], lambda v: f"{v:g}: weight must be ≥ 0", weight)
            if not np.any(weight > 0):
                raise BrdfInputError(f"{source}: every weight is 0; at least one sample must count")
        return Samples(wi, wo, values, tuple(channels), sigma, weight, source)


def normalised(vectors: np.ndarray, message: Callable[[int, float], str]) -> np.ndarray:
    """``vectors`` (N, 3) divided by their lengths, each of which must be 1 within :data:`UNIT_LENGTH_TOLERANCE`;
    otherwise a :class:`BrdfInputError` with ``message(row, length)`` for the first that is not."""
    length = np.linalg.norm(vectors, axis=1)
    bad = np.abs(length - 1.0) > UNIT_LENGTH_TOLERANCE
    if np.any(bad):
        row = int(np.argmax(bad))
        raise BrdfInputError(message(row, float(length[row])))
    return vectors / length[:, None]


def _float_array(value, name: str, source: str) -> np.ndarray:
    try:
        return np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise BrdfInputError(f"{source}: {name} must be an array of numbers") from None


# ---------------------------------------------------------------------- writing
def save_samples(samples: Samples, path: str | os.PathLike) -> None:
    """Write ``samples`` as a samples file: angles in degrees, BRDF values, sigma and weight if present.

    Numbers are written with 17 significant digits, so reading the file back
    gives the same float64 values (up to the angle ↔ vector conversion, ~1e-16).
    """
    columns = [np.degrees(np.asarray(angle)) for w in (samples.wi, samples.wo) for angle in direction_to_spherical(w)]
    header = list(ANGLE_COLUMNS) + list(samples.channels)
    columns += list(samples.values.T)
    if samples.sigma is not None:
        header += ["sigma"] if samples.n_channels == 1 else [f"sigma_{c}" for c in samples.channels]
        columns += list(samples.sigma.T)
    if samples.weight is not None:
        header.append("weight")
        columns.append(samples.weight)
    table = np.column_stack(columns)
    body = "\n".join(",".join(f"{x:.17g}" for x in row) for row in table)
    write_text_atomic(path, ",".join(header) + "\n" + body + "\n")
