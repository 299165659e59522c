"""A fitted model as a MERL ``.binary`` table, the measured-BRDF format renderers read (Matusik et al. 2003)."""

import os

import numpy as np

from ..data.merl import CHANNELS, HORIZON, N_BINS, SCALES, bin_directions, stored_planes, write_merl_table
from ..errors import BrdfInputError
from ..physics.evaluate import evaluate
from ..physics.geometry import in_turned_frame, spherical_to_direction
from ..physics.merl_table import bin_offset

#: A BRDF whose values change by more than this fraction of its largest when both directions turn about the normal
#: (:func:`anisotropy`) is anisotropic: a MERL table, indexed by Rusinkiewicz's angles without the half vector's
#: azimuth, holds an isotropic BRDF only. An isotropic model's values change by rounding alone (~1e-15).
ISOTROPY_TOLERANCE = 1e-6
#: The turns about the normal (radians) at which :func:`anisotropy` compares the values.
TURNS = (np.pi / 5, np.pi / 2, 2 * np.pi / 3)
#: How many direction pairs of each kind :func:`anisotropy` looks at: uniformly spread, and near the mirror
#: direction with the half vector tilted 0.001–0.6 rad towards every azimuth (where a narrow lobe's stretch shows).
TURNED_PAIRS = 256


def write_merl(
    model, params: dict, path: str | os.PathLike, *, bin_centres: bool = False, **model_options
) -> list[str]:
    """Tabulate ``model`` with ``params`` (the result file's dictionary) into a MERL ``.binary`` file; returns what
    a user must know (a one-channel model is written as grey, the same table in r, g and b).

    The model (three channels, r, g, b, or one) is evaluated with :func:`brdffit.evaluate` at every bin's
    directions (Matusik et al. 2003 table, Rusinkiewicz 1998 angles): each bin's lower edge, where MERL's
    ``BRDFRead.cpp`` looks a direction up, or its centre with ``bin_centres`` (``physics/merl_table.py``); bins with
    a direction below the horizon, which MERL never looks up, hold 0. ``model_options`` are the model's options
    (``fresnel=``). An anisotropic BRDF (:func:`anisotropy` above :data:`ISOTROPY_TOLERANCE`) is refused: the table
    would hold one slice of it.
    """
    change, name = anisotropy(model, params, **model_options), getattr(model, "name", model)
    if not np.isfinite(change):
        raise BrdfInputError(f"{path}: {name} with these parameters gives values that are not finite numbers")
    if change > ISOTROPY_TOLERANCE:
        raise BrdfInputError(
            f"{path}: {name} with these parameters is anisotropic (turning both directions about the normal changes"
            f" its values by up to {change:.3g} of its largest); a MERL table holds an isotropic BRDF only: export"
            " it to mitsuba or gltf"
        )
    wi, wo = bin_directions(bin_centres)
    above = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    values = np.zeros((N_BINS, len(CHANNELS)))
    computed = evaluate(model, params, wi[above], wo[above], **model_options)
    notes = []
    if computed.shape[1] == 1:
        computed = np.repeat(computed, len(CHANNELS), axis=1)
        notes.append("one channel: written as grey, the same values in r, g and b")
    if computed.shape[1] != len(CHANNELS):
        name = getattr(model, "name", model)
        raise BrdfInputError(
            f"{path}: model {name!s} gives {computed.shape[1]} channels; a MERL file holds 3 (r, g, b), or grey from 1"
        )
    values[above] = computed
    write_merl_table(values, path)
    if bin_centres:
        notes.append("each bin evaluated at its centre (MERL's BRDFRead.cpp looks a direction up at its lower edge)")
    return notes


def merl_brdf(path: str | os.PathLike, bin_centres: bool = False):
    """A MERL file's BRDF as brdffit reads it back, ``brdf(wi, wo) -> (N, 3)`` in 1/sr: the table interpolated
    trilinearly in its bin coordinates (``datadriven/tabulation.py``) over the bins that hold a value (stored ≥ 0)
    with both directions above the horizon; ``bin_centres``: the table's values lie at its bins' centres."""
    from ..datadriven.tabulation import interpolation

    table = np.array(stored_planes(path)) * SCALES[:, None]  # (3, bins), 1/sr
    wi, wo = bin_directions(bin_centres)
    filled = np.all(table >= 0, axis=0) & (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)

    def brdf(wi, wo):
        index, weight = interpolation(np.asarray(wi, float), np.asarray(wo, float), filled, bin_offset(bin_centres))
        return np.einsum("nk,cnk->nc", weight, table[:, index])

    return brdf


def anisotropy(model, params: dict, **model_options) -> float:
    """How far ``model`` with ``params`` is from isotropic: the largest change of its values when both directions
    of a pair turn about the normal by each of :data:`TURNS`, over :data:`TURNED_PAIRS` seeded pairs of each kind
    (spread; near the mirror direction; those with a direction at the horizon or below left out), as a fraction of
    its largest value there (0 for a BRDF that is 0 there; NaN where a value is not a finite number)."""
    rng = np.random.default_rng(0)
    spread_i, spread_o = _directions(rng, min_cos=0.1), _directions(rng, min_cos=0.1)
    # near the mirror direction: wo is wi reflected about a half vector tilted by δ towards azimuth ψ
    half = spherical_to_direction(np.geomspace(1e-3, 0.6, TURNED_PAIRS), rng.uniform(0, 2 * np.pi, TURNED_PAIRS))
    near_i = _directions(rng, min_cos=0.5)
    near_o = 2 * np.sum(near_i * half, axis=1, keepdims=True) * half - near_i
    wi, wo = np.concatenate([spread_i, near_i]), np.concatenate([spread_o, near_o])
    kept = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    wi, wo = wi[kept], wo[kept]
    turned_i = np.concatenate([wi, *(in_turned_frame(wi, turn) for turn in TURNS)])
    turned_o = np.concatenate([wo, *(in_turned_frame(wo, turn) for turn in TURNS)])
    values = evaluate(model, params, turned_i, turned_o, **model_options).reshape(1 + len(TURNS), len(wi), -1)
    if not np.all(np.isfinite(values)):
        return float("nan")
    largest = np.max(np.abs(values[0]))
    return float(np.max(np.abs(values[1:] - values[0])) / largest) if largest > 0 else 0.0


def _directions(rng: np.random.Generator, min_cos: float) -> np.ndarray:
    """:data:`TURNED_PAIRS` directions drawn by ``rng``, ``cos θ`` uniform in ``[min_cos, 1]``, azimuth uniform."""
    return spherical_to_direction(
        np.arccos(rng.uniform(min_cos, 1.0, TURNED_PAIRS)), rng.uniform(0, 2 * np.pi, TURNED_PAIRS)
    )
