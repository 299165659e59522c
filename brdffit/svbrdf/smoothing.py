"""A smoothness prior across texels: where a texel's photographs leave its shape under-determined, its neighbours'
shapes decide it.

With ``smoothness`` τ the maps minimise, over every texel's parameters at once::

    Σ_texels rᵀr  +  λ · Σ_neighbouring pairs |S(θ_i − θ_j)|²,      λ = σ² / τ²

``rᵀr`` is a texel's cost (its fit's residuals, as without the prior), ``θ`` its solver vector (``Model.unconstrained``:
a roughness or an exponent as its logarithm, an index above 1 as the logarithm of its excess), ``S`` picks the shape
parameters every channel shares (not the albedos, not a per-channel index, not an azimuth, which wraps round) of a
model with albedos and one lobe (a renderer's own model has weights as logits beside its roughness, on which one τ
means nothing alike; Lafortune's several lobes have no order a neighbour's could be matched in), ``σ²`` is the
residuals' variance (the median over the texels of ``rᵀr / (values − parameters)`` of their own fits) and τ how far
a shape coordinate typically differs between two neighbouring texels: the prior's standard deviation of that
difference, in the coordinate's units (τ = 0.1 on a logarithm: a roughness 10% from its neighbour's). It is the most
probable maps under the texels' likelihoods and a Gaussian Markov random field prior on their shapes over the four
neighbours (Besag 1974; Rue & Held, *Gaussian Markov Random Fields*, 2005, §3.3).

It is found by block coordinate descent over a checkerboard: no texel of one colour has a neighbour of its colour, so
each is fitted, from its current parameters, with the prior ``λ · n_i · |S(θ_i − μ_i)|²`` (``μ_i`` the mean of its
``n_i`` fitted neighbours' ``θ``; ``solver/hold.py``), which is exactly how the whole objective depends on it; then the
other colour. Each half-pass solves its texels' parts to the solver's tolerance, so the objective falls but for what a
result rounds (a start moved inside a bound). Up to :data:`PASSES` passes, until no shape coordinate moves by more than
:data:`TOLERANCE` in a pass; the maps say how many passes ran and how far the last one moved. Texels are refitted a
chunk at a time (the capture's tile size), and their Laplace errors, where asked for, once the descent has ended.
"""

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import BrdfInputError
from ..fitting.single.fit import start_vector
from ..physics.domains import AxisAzimuth
from ..physics.models.model import LobeModel, Model
from ..physics.models.params import albedo_size
from .capture import Capture
from .maps import column_params

#: Most passes over the checkerboard (each fits every texel once).
PASSES = 20
#: A pass that moves no shape coordinate by more than this (in its units: 1e-4 of a logarithm) ends the descent.
TOLERANCE = 1e-4
#: ``refit(texels, starts, priors, uncertainty) -> arrays``: the texels fitted from ``starts`` under ``priors``.
Refit = Callable[[np.ndarray, list[dict[str, Any]], list[tuple[np.ndarray, np.ndarray]], bool], dict]


def shape_mask(model: Model, n_channels: int) -> np.ndarray:
    """Which entries (k,) of ``model``'s solver vector the prior draws together: the shape parameters its channels
    share, but an azimuth (module docstring); a one-line error for a model the prior does not apply to."""
    if not isinstance(model, LobeModel) or model.n_lobes != 1 or model.whole:
        raise BrdfInputError(
            "a smoothness prior draws together the shape of a model with albedos and one lobe (ward, ward-aniso,"
            f" cook-torrance, blinn-phong, phong, one-lobe lafortune), not a {model.name} fit's"
        )
    first = albedo_size(model, n_channels)
    mask = np.zeros(model.unconstrained.size(n_channels), dtype=bool)
    mask[first : first + len(model.unconstrained.shared.names)] = True
    # The sampling vector has the solver's layout (the physical one spells a Lafortune direction with one entry more).
    mask &= ~np.array([isinstance(domain, AxisAzimuth) for domain in model.sampling.domains(n_channels)])
    if not mask.any():
        raise BrdfInputError(f"a {model.name} fit has no shape parameters for a smoothness prior to draw together")
    return mask


def smoothed(
    columns: dict[str, np.ndarray],
    capture: Capture,
    model: Model,
    tau: float,
    refit: Refit,
    chunk: int,
    uncertainty: bool = False,
) -> dict[str, Any]:
    """The texels of ``columns`` (the capture's flat arrays, updated) fitted again under the smoothness prior of
    standard deviation ``tau`` (module docstring) by ``refit``, at most ``chunk`` texels at a time, with their
    Laplace errors once at the end where ``uncertainty``; what the maps say of it: ``tau``, ``lambda``, the
    ``passes`` run, the ``largest_change`` of a shape coordinate in the last one and whether that was below
    :data:`TOLERANCE` (``converged``)."""
    rows, width = capture.shape
    n_channels = len(capture.channels)
    mask = shape_mask(model, n_channels)
    fitted = np.flatnonzero(columns["n_samples"] > 0)
    thetas = np.full((rows * width, mask.size), np.nan)

    def read_thetas(texels: np.ndarray) -> None:
        for texel in texels:
            try:
                thetas[texel] = start_vector(model, column_params(columns, texel), n_channels)
            except BrdfInputError:  # a shape run off to where no fit moves (an index of 10⁸): left as it is
                thetas[texel] = np.nan

    read_thetas(fitted)
    n_values = columns["n_samples"][fitted] * n_channels
    enough = n_values > mask.size
    if not enough.any():
        raise BrdfInputError("no texel has more values than parameters: the residuals' variance is unknown")
    variance = float(np.median(columns["cost"][fitted][enough] / (n_values[enough] - mask.size)))
    weight = variance / tau**2
    grid = np.arange(rows * width).reshape(rows, width)
    colour = ((grid // width + grid % width) % 2).ravel()

    def fit_again(texels: np.ndarray, with_errors: bool = False) -> None:
        """``texels`` fitted under their priors, given their neighbours now, a chunk at a time."""
        means, counts = _neighbour_means(thetas, rows, width)
        texels = texels[(counts[texels] > 0) & np.isfinite(thetas[texels, 0])]
        for first in range(0, len(texels), chunk):
            some = texels[first : first + chunk]
            priors = []
            for texel in some:
                mean = thetas[texel].copy()
                mean[mask] = means[texel, mask]
                priors.append((mean, np.where(mask, weight * counts[texel], 0.0)))
            tile = refit(some, [column_params(columns, texel) for texel in some], priors, with_errors)
            for name, values in tile.items():
                if name in columns:
                    columns[name][some] = values
            read_thetas(some)

    passes, largest = 0, np.inf
    while passes < PASSES and largest > TOLERANCE:
        before = thetas[:, mask].copy()
        for shade in (0, 1):
            fit_again(fitted[colour[fitted] == shade])
        passes += 1
        change = np.abs(thetas[:, mask] - before)
        largest = float(np.max(change[np.isfinite(change)], initial=0.0))
    if uncertainty:  # at the optimum each texel's part is solved already: its Laplace errors there
        for shade in (0, 1):
            fit_again(fitted[colour[fitted] == shade], with_errors=True)
    converged = largest <= TOLERANCE
    return {"tau": tau, "lambda": weight, "passes": passes, "largest_change": largest, "converged": converged}


def _neighbour_means(thetas: np.ndarray, rows: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The mean (H·W, k) of each texel's fitted four neighbours' ``thetas`` (NaN rows: not fitted) and how many
    there are (H·W,); NaN where none."""
    grid = thetas.reshape(rows, width, -1)
    total = np.zeros_like(grid)
    count = np.zeros((rows, width))
    for axis in (0, 1):
        for shift in (1, -1):
            moved = np.roll(grid, shift, axis=axis)
            edge = [slice(None)] * 2
            edge[axis] = slice(0, 1) if shift == 1 else slice(-1, None)
            present = np.isfinite(moved[..., 0])
            present[tuple(edge)] = False  # np.roll wraps round: the far edge is no neighbour
            total += np.where(present[..., None], moved, 0.0)
            count += present
    with np.errstate(invalid="ignore", divide="ignore"):
        means = total / count[..., None]
    return means.reshape(rows * width, -1), count.ravel()
