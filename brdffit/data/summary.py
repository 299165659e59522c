"""``brdffit info``: what a samples file holds — count, channels, value ranges and angular coverage."""

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
    and were read right. ``format_name``: how to name the format (default: the one they were read from)."""
    if format_name is None:
        format_name = samples.provenance.format if samples.provenance else "arrays"
    n, c = samples.n_samples, samples.n_channels
    shown = ", ".join(samples.channels[:6]) + (f", … ({c} in all)" if c > 6 else "")
    azimuth_i, azimuth_o = direction_to_spherical(samples.wi)[1], direction_to_spherical(samples.wo)[1]
    delta_phi = np.degrees(np.abs(np.angle(np.exp(1j * (azimuth_o - azimuth_i)))))
    theta_h, theta_d = half_difference_angles(samples)
    cells = np.unique((np.minimum(theta_h, 89.999) // CELL) * 100 + np.minimum(theta_d, 89.999) // CELL)
    total = (90 // CELL) ** 2
    lines = [
        f"{samples.source}: {format_name}, {n} samples × {c} channel(s): {shown}",
        f"  θi {_range(samples.theta_i)}°, θo {_range(samples.theta_o)}°, |φo − φi| {_range(delta_phi)}°",
        f"  θh {_range(theta_h)}°, θd {_range(theta_d)}°; {len(cells)} of {total} {CELL}°×{CELL}° (θh, θd) cells"
        f" hold samples; {len(samples.light_directions()[0])} distinct light directions",
        f"  grazing: {np.mean(np.maximum(samples.theta_i, samples.theta_o) > 70):.0%} of samples have θi or θo > 70°",
    ]
    for index, name in enumerate(samples.channels[:6]):
        values = samples.values[:, index]
        lines.append(f"  {name}: {values.min():.4g} … {values.max():.4g} 1/sr, median {np.median(values):.4g}")
    provenance = samples.provenance
    sigma = (
        "none"
        if samples.sigma is None
        else (provenance.sigma_from if provenance and provenance.sigma_from else "given")
    )
    lines.append(f"  sigma: {sigma} · weight: {'given' if samples.weight is not None else 'none'}")
    if provenance is not None:
        lines += _provenance_lines(provenance)
    lines += _reciprocity_lines(samples)
    return "\n".join(lines)


#: What each quantity divides the file's values by.
_DIVIDED_BY = {
    "brdf": "taken as they are",
    "reflectance-factor": "divided by π",
    "cosine-weighted-in": "divided by cos θi (the light's cosine)",
    "cosine-weighted-out": "divided by cos θo (the view's cosine)",
}


def _provenance_lines(provenance: Provenance) -> list[str]:
    """How the file was read: its rows, those left out and why, and what its values were taken as."""
    kept = provenance.rows - sum(count for _, count in provenance.dropped)
    lines = [f"  rows: {provenance.rows} read, {kept} kept"]
    lines += [f"  dropped: {count} {why}" for why, count in provenance.dropped]
    origin = (
        "as given"
        if provenance.quantity_given
        else ("as the header says" if provenance.header_quantity else "by default")
    )
    header = (
        f" (the header says {provenance.header_quantity})"
        if provenance.header_quantity and provenance.quantity_given
        else ""
    )
    lines.append(f"  values read as {provenance.quantity} ({origin}{header}): {_DIVIDED_BY[provenance.quantity]}")
    return lines


def _reciprocity_lines(samples: Samples) -> list[str]:
    """The median ratio of reciprocal pairs under each reading of the values, the reading that fits, and whether
    the file's header contradicts the data."""
    found = reciprocity(samples)
    if found is None:
        return [f"  reciprocity: fewer than {MIN_PAIRS} reciprocal pairs, not checked"]
    readings = ", ".join(f"{ratio:.3g} as {reading}" for reading, ratio in found.ratios.items())
    lines = [
        f"  reciprocity: {found.pairs} {found.kind} pairs (directions matched within {found.tolerance_degrees:.2g}°);"
        f" median f(a→b)/f(b→a), θa < θb: {readings}"
    ]
    if found.reciprocal:
        lines.append(f"  the values as read are reciprocal (median {found.as_read:.3g})")
    else:
        lines.append(
            f"  the values as read are NOT reciprocal (median {found.as_read:.3g}); they are as {found.best}:"
            f" read them with --quantity {found.best}"
        )
    if found.header_contradicted:
        lines.append(f"  warning: {header_contradiction(found)}")
    return lines


def _range(values: np.ndarray) -> str:
    return f"{values.min():.1f}–{values.max():.1f}"
