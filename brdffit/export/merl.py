"""A fitted model as a MERL ``.binary`` table, the measured-BRDF format renderers read (Matusik et al. 2003)."""

import os

import numpy as np

from ..data.merl import CHANNELS, HORIZON, N_BINS, SCALES, bin_directions, stored_planes, write_merl_table
from ..errors import BrdfInputError
from ..physics.evaluate import evaluate
from ..physics.merl_table import bin_offset


def write_merl(
    model, params: dict, path: str | os.PathLike, *, bin_centres: bool = False, **model_options
) -> list[str]:
    """Tabulate ``model`` with ``params`` (the result file's dictionary) into a MERL ``.binary`` file; returns what
    a user must know (a one-channel model is written as grey, the same table in r, g and b).

    The model (three channels, r, g, b, or one) is evaluated with :func:`brdffit.evaluate` at every bin's
    directions (Matusik et al. 2003 table, Rusinkiewicz 1998 angles): each bin's lower edge, where MERL's
    ``BRDFRead.cpp`` looks a direction up, or its centre with ``bin_centres`` (``physics/merl_table.py``); bins with
    a direction below the horizon, which MERL never looks up, hold 0. ``model_options`` are the model's options
    (``fresnel=``).
    """
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
