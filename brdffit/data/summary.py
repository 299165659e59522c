"""``brdffit info``: what a samples file holds — count, channels, value ranges and angular coverage."""

from typing import Any

import numpy as np

from ..physics.geometry import direction_to_spherical, to_half_difference
from .reciprocity import MIN_PAIRS, header_contradiction, reciprocity
from .samples import Provenance, Samples

#: Cell size of the coverage count, degrees, over Rusinkiewicz's (θh, θd) (each 0–90°).
CELL = 10


def half_difference_angles(samples: Samples) -> tuple[np.ndarray, np.ndarray]:
    """θh (half vector from the normal) and θd (light from the half vector), degrees (Rusinkiewicz 1998)."""
    theta_h, _, theta_d, _ = to_half_difference(samples.wi, samples.wo)
    return np.degrees(theta_h), np.degrees(theta_d)


def describe(samples: Samples, format_name: str | None = None) -> str:
    """What ``brdffit info`` prints: a few lines a person reads to judge whether the samples can determine a model,
    and were read right (:func:`summary`, as text). ``format_name``: how to name the format (default: the one they
    were read from)."""
    return summary_text(summary(samples, format_name))


def summary(samples: Samples, format_name: str | None = None) -> dict[str, Any]:
    """What :func:`describe` says, as plain data (``brdffit info --json``): ``source``, ``format``, ``n_samples``,
    ``channels``; the ranges ``[min, max]`` in degrees of ``theta_i``, ``theta_o``, ``delta_phi`` (``|φo − φi|``),
    ``theta_h`` and ``theta_d`` (Rusinkiewicz's); ``coverage`` (how many of the 10° × 10° (θh, θd) cells hold
    samples), ``light_directions``, ``grazing`` (the fraction with θi or θo above 70°); ``values`` per channel
    (``min``, ``median``, ``max`` in 1/sr); ``sigma`` (``"none"``, ``"given"`` or where it came from) and ``weight``
    (given or not); for a file, ``rows`` (``read``, ``kept``, ``dropped``: ``[why, count]`` pairs) and ``quantity``
    (``read_as``, ``origin``, ``header``, ``divided_by``); ``reciprocity``: None (too few pairs) or what the reciprocal
    pairs say (``pairs``, ``kind``, ``tolerance_degrees``, ``ratios`` by reading, ``as_read``, ``reciprocal``,
    ``best``, ``header_contradicted`` and its ``warning``)."""
    if format_name is None:
        format_name = samples.provenance.format if samples.provenance else "arrays"
    azimuth_i, azimuth_o = direction_to_spherical(samples.wi)[1], direction_to_spherical(samples.wo)[1]
    delta_phi = np.degrees(np.abs(np.angle(np.exp(1j * (azimuth_o - azimuth_i)))))
    theta_h, theta_d = half_difference_angles(samples)
    cells = np.unique((np.minimum(theta_h, 89.999) // CELL) * 100 + np.minimum(theta_d, 89.999) // CELL)
    provenance = samples.provenance
    sigma = (
        "none"
        if samples.sigma is None
        else (provenance.sigma_from if provenance and provenance.sigma_from else "given")
    )
    found = reciprocity(samples)
    return {
        "source": str(samples.source),
        "format": format_name,
        "n_samples": samples.n_samples,
        "channels": [str(name) for name in samples.channels],
        **{
            name: [float(values.min()), float(values.max())]
            for name, values in (
                ("theta_i", samples.theta_i),
                ("theta_o", samples.theta_o),
                ("delta_phi", delta_phi),
                ("theta_h", theta_h),
                ("theta_d", theta_d),
            )
        },
        "coverage": {"cells": len(cells), "of": (90 // CELL) ** 2, "cell_degrees": CELL},
        "light_directions": len(samples.light_directions()[0]),
        "grazing": float(np.mean(np.maximum(samples.theta_i, samples.theta_o) > GRAZING)),
        "values": {
            str(name): {"min": float(column.min()), "median": float(np.median(column)), "max": float(column.max())}
            for name, column in zip(samples.channels, samples.values.T, strict=True)
        },
        "sigma": sigma,
        "weight": samples.weight is not None,
        **({} if provenance is None else _provenance(provenance)),
        "reciprocity": None if found is None else _reciprocity(found),
    }


#: A sample is grazing when its light or its viewer lies farther than this from the normal (degrees).
GRAZING = 70


def summary_text(summary: dict[str, Any]) -> str:
    """The lines :func:`describe` prints from a :func:`summary` (six channels at most, named)."""
    channels = summary["channels"]
    c = len(channels)
    shown = ", ".join(channels[:6]) + (f", … ({c} in all)" if c > 6 else "")
    coverage = summary["coverage"]
    cell = coverage["cell_degrees"]
    lines = [
        f"{summary['source']}: {summary['format']}, {summary['n_samples']} samples × {c} channel(s): {shown}",
        f"  θi {_range(summary['theta_i'])}°, θo {_range(summary['theta_o'])}°, |φo − φi|"
        f" {_range(summary['delta_phi'])}°",
        f"  θh {_range(summary['theta_h'])}°, θd {_range(summary['theta_d'])}°; {coverage['cells']} of {coverage['of']}"
        f" {cell}°×{cell}° (θh, θd) cells hold samples; {summary['light_directions']} distinct light directions",
        f"  grazing: {summary['grazing']:.0%} of samples have θi or θo > {GRAZING}°",
    ]
    for name in channels[:6]:
        values = summary["values"][name]
        lines.append(f"  {name}: {values['min']:.4g} … {values['max']:.4g} 1/sr, median {values['median']:.4g}")
    lines.append(f"  sigma: {summary['sigma']} · weight: {'given' if summary['weight'] else 'none'}")
    if "rows" in summary:
        rows, quantity = summary["rows"], summary["quantity"]
        lines.append(f"  rows: {rows['read']} read, {rows['kept']} kept")
        lines += [f"  dropped: {count} {why}" for why, count in rows["dropped"]]
        header = (
            f" (the header says {quantity['header']})"
            if quantity["header"] and quantity["origin"] == "as given"
            else ""
        )
        lines.append(f"  values read as {quantity['read_as']} ({quantity['origin']}{header}): {quantity['divided_by']}")
    lines += _reciprocity_lines(summary["reciprocity"])
    return "\n".join(lines)


#: What each quantity divides the file's values by.
_DIVIDED_BY = {
    "brdf": "taken as they are",
    "reflectance-factor": "divided by π",
    "cosine-weighted-in": "divided by cos θi (the light's cosine)",
    "cosine-weighted-out": "divided by cos θo (the view's cosine)",
}


def _provenance(provenance: Provenance) -> dict[str, Any]:
    """How the file was read: its rows, those left out and why, and what its values were taken as."""
    kept = provenance.rows - sum(count for _, count in provenance.dropped)
    origin = (
        "as given"
        if provenance.quantity_given
        else ("as the header says" if provenance.header_quantity else "by default")
    )
    return {
        "rows": {"read": provenance.rows, "kept": kept, "dropped": [[why, count] for why, count in provenance.dropped]},
        "quantity": {
            "read_as": provenance.quantity,
            "origin": origin,
            "header": provenance.header_quantity,
            "divided_by": _DIVIDED_BY[provenance.quantity],
        },
    }


def _reciprocity(found) -> dict[str, Any]:
    """What the reciprocal pairs say (``reciprocity.Reciprocity``), as plain data."""
    return {
        "pairs": found.pairs,
        "kind": found.kind,
        "tolerance_degrees": found.tolerance_degrees,
        "ratios": dict(found.ratios),
        "as_read": found.as_read,
        "reciprocal": bool(found.reciprocal),
        "best": found.best,
        "header_contradicted": bool(found.header_contradicted),
        "warning": header_contradiction(found) if found.header_contradicted else None,
    }


def _reciprocity_lines(found: dict[str, Any] | None) -> list[str]:
    """The median ratio of reciprocal pairs under each reading of the values, the reading that fits, and whether
    the file's header contradicts the data."""
    if found is None:
        return [f"  reciprocity: fewer than {MIN_PAIRS} reciprocal pairs, not checked"]
    readings = ", ".join(f"{ratio:.3g} as {reading}" for reading, ratio in found["ratios"].items())
    lines = [
        f"  reciprocity: {found['pairs']} {found['kind']} pairs (directions matched within"
        f" {found['tolerance_degrees']:.2g}°); median f(a→b)/f(b→a), θa < θb: {readings}"
    ]
    if found["reciprocal"]:
        lines.append(f"  the values as read are reciprocal (median {found['as_read']:.3g})")
    else:
        lines.append(
            f"  the values as read are NOT reciprocal (median {found['as_read']:.3g}); they are as {found['best']}:"
            f" read them with --quantity {found['best']}"
        )
    if found["header_contradicted"]:
        lines.append(f"  warning: {found['warning']}")
    return lines


def _range(limits: list[float]) -> str:
    return f"{limits[0]:.1f}–{limits[1]:.1f}"
