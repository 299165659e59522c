"""ALTA data files: the text ``.dat`` format of the ALTA library (Belcour et al., github.com/belcour/alta).

A file is a header of ``#KEY value`` lines, then one measurement per line::

    #DIM 3 1
    #PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI
    #PARAM_OUT INV_STERADIAN
    #VS 0
    0.2617993877991494  0.2617993877991494  0  72.4568

* ``#DIM n_in n_out``: each row holds ``n_in`` input coordinates, then ``n_out`` values (required).
* ``#PARAM_IN NAME``: how the inputs describe the two directions (required); angles are in radians.
* ``#PARAM_OUT NAME``: what the values are (optional). ``INV_STERADIAN``, ``ENERGY``, ``RGB_COLOR``
  and ``XYZ_COLOR`` are BRDF values in 1/sr; ``INV_STERADIAN_COSINE_FACTOR`` is the BRDF times the
  cosine of the **output (view)** direction (ALTA's ``params.h``: "weighted by the cosine factor of the
  output direction"), the quantity ``cosine-weighted-out``, divided by ``cos θv`` when the samples are
  loaded. Without the line the values are read as BRDF, unless the user says otherwise.
* ``#VS k``: confidence intervals after the values (optional, default 0), either ``k`` columns in
  all (ALTA's text reader, ``core/data_storage.cpp``, applies them to the first output) or ``k``
  per output. ``k = 1`` is a half-width ``w``, ``k = 2`` the bounds ``lo, hi``; brdffit reads the
  interval as ±1σ: ``sigma = w`` or ``(hi − lo)/2`` (``k`` in all with several outputs: the first
  output's interval for every channel). An interval of width 0 is an error (sigma must be > 0).
* ``#CHANNELS name ...``: brdffit's own key (ALTA ignores keys it does not know): the channel names.
  Without it the channels are ``value`` (1 output), ``x, y, z`` (``XYZ_COLOR``), ``r, g, b``
  (3 outputs), else ``c0, c1, ...``.
* Other keys (``#SAMPLE``, ``#ORIGIN``, ``#URL``, ...) and blank lines are ignored. Binary ALTA
  files (``#FORMAT binary``, ``#BEGIN_STREAM``) are not read.

The input parameterisations read (ALTA's ``params::to_cartesian`` in ``core/params.cpp``; all
angles in radians; ``d(θ, φ) = (sin θ cos φ, sin θ sin φ, cos θ)``; ``wi`` towards the light,
``wo`` towards the viewer, ``z`` the normal):

* ``SPHERICAL_TL_PL_TV_PV`` (4): ``θl, φl, θv, φv``; ``wi = d(θl, φl)``, ``wo = d(θv, φv)``.
* ``ISOTROPIC_TL_TV_PROJ_DPHI`` (3): ``θl, θv cos Δφ, θv sin Δφ``; ``wi = d(θl, 0)``,
  ``wo = d(θv, Δφ)`` with ``θv = hypot(a, b)`` and ``Δφ = atan2(b, a)``, as in ALTA's
  ``to_cartesian``. The real retro-reflective tape (``retro-gray-tape.dat``, ALTA's
  ``documents/data``) confirms it: at θl = 15° and 30° its largest value (72 and 43 1/sr) lies at
  ``(a, b) = (θl, 0)``, i.e. ``wo = wi``, the retro direction; the mirror direction there holds
  values below 1 1/sr. (The opposite convention, viewer at ``Δφ + π``, would put that peak at
  the mirror direction.) ALTA's own ``from_cartesian`` writes ``Δφ = φl − φv``, the mirror image
  in ``y``, which an isotropic BRDF cannot tell apart.
* ``RUSIN_TH_PH_TD_PD`` (4): Rusinkiewicz's half/difference angles (EGWR 1998)
  ``θh, φh, θd, φd``; ``wi = Rz(φh) Ry(θh) d(θd, φd)`` and ``wo = Rz(φh) Ry(θh) (−dx, −dy, dz)``,
  the mirror image of ``wi`` about the half vector.
* ``RUSIN_TH_TD_PD`` (3): the same with ``φh = 0`` (isotropic).
* ``CARTESIAN`` (6): the two unit vectors, **viewer first**: ``wo_x, wo_y, wo_z, wi_x, wi_y, wi_z``
  (ALTA's ``params.h``: "We always pack the view vector first"), checked to be unit length
  within 1e-3 and normalised.

Rows with either direction at or below the horizon (``z ≤ 1e-12``; e.g. the tape's
``θv = 90°`` rows) are dropped, and counted in the samples' provenance (``brdffit info`` shows it); a
file where no row remains is an error. An angle beyond ±2π is an error: ALTA's angles are radians.

Bad input raises :class:`~brdffit.errors.BrdfInputError` with one line naming the file (and the
line in the file where there is one).
"""

import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from .._files import write_text_atomic
from .._jax import first_bad
from ..errors import BrdfInputError
from ..physics.geometry import (
    UNIT_LENGTH_TOLERANCE,
    direction_to_spherical,
    from_half_difference,
    normalised,
    spherical_to_direction,
)
from .cells import TableChecks, named
from .samples import Provenance, Samples
from .text import format_rows, parse_numbers, read_text

#: ``#PARAM_IN`` names read, with the number of input coordinates each takes.
PARAMETERISATIONS = {
    "SPHERICAL_TL_PL_TV_PV": 4,
    "ISOTROPIC_TL_TV_PROJ_DPHI": 3,
    "RUSIN_TH_PH_TD_PD": 4,
    "RUSIN_TH_TD_PD": 3,
    "CARTESIAN": 6,
}
#: ``#PARAM_OUT`` names read, with the quantity (``quantities.py``) each says the values are.
OUTPUTS = {
    "INV_STERADIAN": "brdf",
    "INV_STERADIAN_COSINE_FACTOR": "cosine-weighted-out",
    "ENERGY": "brdf",
    "RGB_COLOR": "brdf",
    "XYZ_COLOR": "brdf",
}
#: Directions with ``z`` at or below this are below the horizon; their rows are dropped.
HORIZON = 1e-12
_COORDINATES = {
    "SPHERICAL_TL_PL_TV_PV": ("theta_l", "phi_l", "theta_v", "phi_v"),
    "ISOTROPIC_TL_TV_PROJ_DPHI": ("theta_l", "theta_v*cos(dphi)", "theta_v*sin(dphi)"),
    "RUSIN_TH_PH_TD_PD": ("theta_h", "phi_h", "theta_d", "phi_d"),
    "RUSIN_TH_TD_PD": ("theta_h", "theta_d", "phi_d"),
    "CARTESIAN": ("v_x", "v_y", "v_z", "l_x", "l_y", "l_z"),
}
_BINARY_MARKERS = (b"#BEGIN_STREAM", b"#FORMAT binary")


# ---------------------------------------------------------------------- reading
def read_alta(path: str | os.PathLike) -> Samples:
    """Read an ALTA text data file into :class:`Samples` holding BRDF values in 1/sr.

    The parameterisations and header keys read are in the module's docstring. Rows with a
    direction at or below the horizon are dropped silently.
    """
    path = Path(path)
    source = str(path)
    text = _read_alta_text(path)
    header, data = _split(text, source)
    n_in, n_out = _dimensions(header, source)
    parameterisation = _parameterisation(header, n_in, source)
    output = _output(header, source)
    channels = _channels(header, n_out, output, source)
    extra = _vs_columns(header, n_out, source)
    if not data:
        raise BrdfInputError(f"{source}: no data rows after the header")

    lines = np.array([number for number, _ in data])
    rows = [line.split() for _, line in data]
    widths = {n_in + n_out + k for k in extra}
    first = len(rows[0])
    if first not in widths:
        raise BrdfInputError(
            f"{source}: line {lines[0]}: {first} numbers, but #DIM {n_in} {n_out}"
            f" (with #VS {_vs(header, source)}) means {' or '.join(str(w) for w in sorted(widths))}"
        )
    counts = np.fromiter(map(len, rows), dtype=np.int64, count=len(rows))
    uneven = first_bad(counts != first)
    if uneven is not None:
        row = uneven[0]
        raise BrdfInputError(
            f"{source}: line {lines[row]}: {counts[row]} numbers, but the rows before have {first}"
            f" (#DIM {n_in} {n_out})"
        )
    names = list(_COORDINATES[parameterisation]) + [f"channel {c}" for c in channels]
    column = lambda k: f"column {k + 1} ({names[k]})" if k < len(names) else f"column {k + 1} (confidence interval)"
    checks = TableChecks(lambda row: f"{source}: line {lines[row]}")
    table = parse_numbers(rows, checks, column)

    values = table[:, n_in : n_in + n_out]
    checks.non_negative(
        values, named(channels, "channel"), lambda v: f"{v:g} is negative (negative reflectance is not allowed)"
    )
    if parameterisation != "CARTESIAN":
        checks.fail_first(
            np.abs(table[:, :n_in]) > 2 * np.pi,
            table[:, :n_in],
            column,
            lambda v: f"{v:g} is beyond ±2π; ALTA angles are radians (was the file written in degrees?)",
        )
    sigma = _sigma(table[:, n_in + n_out :], _vs(header, source), channels, checks)
    with np.errstate(all="ignore"):
        wi, wo = _CONVERTERS[parameterisation](table[:, :n_in])
    no_direction = first_bad(~(np.isfinite(wi).all(axis=1) & np.isfinite(wo).all(axis=1)))
    if no_direction is not None:
        raise BrdfInputError(f"{checks.locate(no_direction[0])}: the coordinates give no direction (too large)")
    if parameterisation == "CARTESIAN":
        wi, wo = (_unit(w, lines, name, source) for w, name in ((wi, "light (l_x, l_y, l_z)"), (wo, "viewer")))

    keep = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    if not np.any(keep):
        raise BrdfInputError(
            f"{source}: every row has the light or the viewer at or below the horizon (z ≤ {HORIZON:g});"
            f" check #PARAM_IN {parameterisation} and that the angles are in radians"
        )
    dropped = int(np.sum(~keep))
    provenance = Provenance(
        "alta",
        rows=len(rows),
        dropped=(("with the light or the viewer at or below the horizon", dropped),) if dropped else (),
        header_quantity=None if output is None else OUTPUTS[output],
        sigma_from=None if sigma is None else f"#VS {_vs(header, source)} confidence intervals, read as ±1σ",
    )
    samples = Samples.from_arrays(
        wi[keep], wo[keep], values[keep], channels=channels, sigma=None if sigma is None else sigma[keep], source=source
    )
    return replace(samples, provenance=provenance)


def _sigma(intervals: np.ndarray, k: int, channels: tuple[str, ...], checks: TableChecks) -> np.ndarray | None:
    """The ±1σ width (N, C) of each value from its ``#VS k`` columns (N, k in all or k per channel), or None."""
    if k == 0:
        return None
    blocks = intervals.reshape(len(intervals), -1, k)  # (N, 1 or C, k)
    width = blocks[:, :, 0] if k == 1 else (blocks[:, :, 1] - blocks[:, :, 0]) / 2
    width = np.array(np.broadcast_to(width, (len(intervals), len(channels))))
    checks.fail_first(
        width <= 0,
        width,
        lambda c: f"confidence interval of channel {channels[c]}",
        lambda v: f"{v:g} wide; an interval read as sigma must be > 0",
    )
    return width


def _read_alta_text(path: Path) -> str:
    text = read_text(path, "an ALTA data file")
    head = text[:65536].encode("utf-8", errors="replace")
    if any(marker in head for marker in _BINARY_MARKERS):
        raise BrdfInputError(f"{path}: a binary ALTA data file (#FORMAT binary); only ALTA's text format is read")
    return text


def _split(text: str, source: str) -> tuple[dict[str, tuple[int, list[str]]], list[tuple[int, str]]]:
    """The ``#KEY`` lines as ``{KEY: (line, values)}`` and the data lines as ``(line, text)``."""
    header: dict[str, tuple[int, list[str]]] = {}
    data: list[tuple[int, str]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            data.append((number, stripped))
            continue
        words = stripped[1:].split()
        if not words:
            continue
        key = words[0].upper()
        if key in ("DIM", "PARAM_IN", "PARAM_OUT", "VS", "CHANNELS"):
            if key in header:
                raise BrdfInputError(f"{source}: line {number}: #{key} appears twice (first on line {header[key][0]})")
            header[key] = (number, words[1:])
    return header, data


def _dimensions(header, source: str) -> tuple[int, int]:
    if "DIM" not in header:
        raise BrdfInputError(f"{source}: no #DIM line; ALTA files start with '#DIM n_in n_out'")
    number, words = header["DIM"]
    if len(words) != 2 or not all(re.fullmatch(r"\+?[0-9]{1,6}", w) for w in words):
        raise BrdfInputError(f"{source}: line {number}: #DIM {' '.join(words)!r} is not two whole numbers n_in n_out")
    n_in, n_out = int(words[0]), int(words[1])
    if n_in < 1 or n_out < 1:
        raise BrdfInputError(f"{source}: line {number}: #DIM {n_in} {n_out}; both dimensions must be at least 1")
    return n_in, n_out


def _parameterisation(header, n_in: int, source: str) -> str:
    supported = ", ".join(PARAMETERISATIONS)
    if "PARAM_IN" not in header:
        raise BrdfInputError(f"{source}: no #PARAM_IN line; give one of: {supported}")
    number, words = header["PARAM_IN"]
    if len(words) != 1:
        raise BrdfInputError(f"{source}: line {number}: #PARAM_IN needs one name; give one of: {supported}")
    name = words[0].upper()
    if name not in PARAMETERISATIONS:
        raise BrdfInputError(f"{source}: line {number}: unknown #PARAM_IN {words[0]!r}; supported: {supported}")
    if PARAMETERISATIONS[name] != n_in:
        raise BrdfInputError(
            f"{source}: line {header['DIM'][0]}: #DIM gives {n_in} inputs, but #PARAM_IN {name} has"
            f" {PARAMETERISATIONS[name]} ({', '.join(_COORDINATES[name])})"
        )
    return name


def _output(header, source: str) -> str | None:
    if "PARAM_OUT" not in header:
        return None
    number, words = header["PARAM_OUT"]
    name = words[0].upper() if len(words) == 1 else ""
    if name not in OUTPUTS:
        raise BrdfInputError(
            f"{source}: line {number}: unknown #PARAM_OUT {' '.join(words)!r}; supported: {', '.join(OUTPUTS)}"
        )
    return name


def _channels(header, n_out: int, output: str | None, source: str) -> tuple[str, ...]:
    if "CHANNELS" in header:
        number, names = header["CHANNELS"]
        if len(names) != n_out:
            raise BrdfInputError(f"{source}: line {number}: #CHANNELS names {len(names)} channels, but #DIM {n_out}")
        if len(set(names)) != len(names):
            raise BrdfInputError(f"{source}: line {number}: #CHANNELS names a channel twice")
        return tuple(names)
    if n_out == 1:
        return ("value",)
    if n_out == 3:
        return ("x", "y", "z") if output == "XYZ_COLOR" else ("r", "g", "b")
    return tuple(f"c{k}" for k in range(n_out))


def _vs(header, source: str) -> int:
    if "VS" not in header:
        return 0
    number, words = header["VS"]
    if len(words) != 1 or words[0] not in ("0", "1", "2"):
        raise BrdfInputError(
            f"{source}: line {number}: #VS {' '.join(words)!r} is not allowed; give 0 (no confidence interval),"
            " 1 (a half-width) or 2 (lower and upper bounds)"
        )
    return int(words[0])


def _vs_columns(header, n_out: int, source: str) -> set[int]:
    """How many confidence-interval columns may follow the values: ``k`` in all (ALTA) or ``k`` per output."""
    k = _vs(header, source)
    return {k, k * n_out}


def _unit(w: np.ndarray, lines: np.ndarray, name: str, source: str) -> np.ndarray:
    return normalised(
        w,
        lambda row, length: (
            f"{source}: line {lines[row]}: the {name} vector has length {length:.6g}, not 1"
            f" (CARTESIAN directions must be unit vectors, within {UNIT_LENGTH_TOLERANCE:g})"
        ),
    )


# ---------------------------------------------------------------------- parameterisations
def _spherical_tl_pl_tv_pv(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return spherical_to_direction(x[:, 0], x[:, 1]), spherical_to_direction(x[:, 2], x[:, 3])


def _isotropic_tl_tv_proj_dphi(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    theta_v = np.hypot(x[:, 1], x[:, 2])
    return spherical_to_direction(x[:, 0], np.zeros(len(x))), spherical_to_direction(
        theta_v, np.arctan2(x[:, 2], x[:, 1])
    )


def _rusin_th_ph_td_pd(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return from_half_difference(x[:, 0], x[:, 1], x[:, 2], x[:, 3])


def _rusin_th_td_pd(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return from_half_difference(x[:, 0], np.zeros(len(x)), x[:, 1], x[:, 2])


def _cartesian(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return x[:, 3:6].copy(), x[:, 0:3].copy()


_CONVERTERS = {
    "SPHERICAL_TL_PL_TV_PV": _spherical_tl_pl_tv_pv,
    "ISOTROPIC_TL_TV_PROJ_DPHI": _isotropic_tl_tv_proj_dphi,
    "RUSIN_TH_PH_TD_PD": _rusin_th_ph_td_pd,
    "RUSIN_TH_TD_PD": _rusin_th_td_pd,
    "CARTESIAN": _cartesian,
}


# ---------------------------------------------------------------------- writing
def write_alta(samples: Samples, path: str | os.PathLike) -> None:
    """Write ``samples`` as an ALTA text data file, atomically.

    Header: ``#DIM 4 C``, ``#PARAM_IN SPHERICAL_TL_PL_TV_PV`` (``θl, φl, θv, φv`` in radians),
    ``#PARAM_OUT`` ``XYZ_COLOR`` for channels ``x, y, z``, ``RGB_COLOR`` for any other 3 channels,
    else ``INV_STERADIAN`` (the values are BRDF in 1/sr; ALTA has no name for other channel
    counts, and reads the count from ``#DIM``), ``#VS 0`` and brdffit's ``#CHANNELS`` line (left
    out where a name is empty or holds white space, which the line cannot carry). Numbers have
    17 significant digits, so reading the file back gives the samples to ~1e-16. Sigma and
    weights are not written (ALTA's ``#VS`` intervals are not 1-σ uncertainties).
    """
    n_channels = samples.n_channels
    channels = tuple(samples.channels)
    if n_channels == 3 and tuple(c.lower() for c in channels) == ("x", "y", "z"):
        output = "XYZ_COLOR"
    elif n_channels == 3:
        output = "RGB_COLOR"
    else:
        output = "INV_STERADIAN"
    theta_l, phi_l = direction_to_spherical(np.asarray(samples.wi, dtype=np.float64))
    theta_v, phi_v = direction_to_spherical(np.asarray(samples.wo, dtype=np.float64))
    table = np.column_stack([theta_l, phi_l, theta_v, phi_v, np.asarray(samples.values, dtype=np.float64)])
    header = [
        f"#DIM 4 {n_channels}",
        "#PARAM_IN SPHERICAL_TL_PL_TV_PV",
        f"#PARAM_OUT {output}",
        "#VS 0",
    ]
    if all(c and not any(ch.isspace() for ch in c) for c in channels) and len(set(channels)) == len(channels):
        header.append("#CHANNELS " + " ".join(channels))
    source = " ".join(str(samples.source).split())
    header.append(f"#ORIGIN written by brdffit from {source}; angles in radians, values BRDF in 1/sr")
    write_text_atomic(path, "\n".join(header) + "\n" + format_rows(table, " "))
