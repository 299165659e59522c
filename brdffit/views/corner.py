"""The corner plot of a fit's posterior (Foreman-Mackey 2016, the ``corner`` package)."""

import logging
import os

import numpy as np

from .._jax import float64
from ..errors import Argument, BrdfInputError, needs
from ..fitting.single.result import FitResult
from ..fitting.single.table import value_with_error
from .figures import check_figure_path, save_figure

#: Draws taken from the Laplace Gaussian when a result has no MCMC draws.
GAUSSIAN_DRAWS = 20_000


#: Most parameters a corner plot shows (a grid of this many squared panels): the first ones, in the covariance's
#: order. 48 coefficients of a data-driven model made a 36 MB image that took 78 s.
MOST_PARAMETERS = 18


def corner_plot(result: FitResult, path: str | os.PathLike | None = None, *, truths=None, seed: int = 0):
    """The corner plot of ``result``'s posterior: every pair of physical parameters, the LM optimum marked.

    Draws are the MCMC ones (``result.draws``) or, for a Laplace result, :data:`GAUSSIAN_DRAWS` seeded draws from
    its Gaussian. Parameters the data do not determine are left out, and beyond :data:`MOST_PARAMETERS` only the
    first are shown. ``truths``: a flat vector (covariance order) to mark instead of the optimum. ``path``: also
    save it (atomically).
    Returns the matplotlib figure.
    """
    if path is not None:
        path = check_figure_path(path)
    if not result.uncertainty:
        raise BrdfInputError(
            "a corner plot needs an uncertainty estimate; fit with ", Argument("uncertainty", "mcmc"), " (or laplace)"
        )
    needs("matplotlib", "plots", "corner plots")
    corner = needs("corner", "plots", "corner plots")

    names = result.uncertainty["covariance"]["names"]
    optimum = _flat_parameters(result)
    if result.draws is not None:
        draws = result.draws
    else:
        covariance = np.array(result.uncertainty["covariance"]["matrix"], dtype=float)  # None → NaN
        known = np.isfinite(np.diag(covariance))
        draws = np.full((GAUSSIAN_DRAWS, len(names)), np.nan)
        rng = np.random.default_rng(seed)
        draws[:, known] = rng.multivariate_normal(
            optimum[known], covariance[np.ix_(known, known)], GAUSSIAN_DRAWS, method="eigh"
        )
    keep = np.all(np.isfinite(draws), axis=0) & (np.ptp(draws, axis=0) > 0)  # a fixed parameter's draws are one value
    if keep.sum() < 1:
        raise BrdfInputError("no parameter has a posterior spread to plot")
    shown = int(keep.sum())
    if shown > MOST_PARAMETERS:  # the first ones (the data-driven model's leading components): a readable grid
        keep &= np.cumsum(keep) <= MOST_PARAMETERS
    marked = optimum if truths is None else np.asarray(truths, dtype=float)
    labels = [name for name, k in zip(names, keep, strict=True) if k]
    if keep.sum() == 1:  # corner draws a grid of at least 2 × 2
        figure = _histogram(draws[:, keep][:, 0], labels[0], marked[keep][0])
    else:
        root = logging.getLogger()
        level = root.level
        root.setLevel(logging.ERROR)  # corner logs "too few points to create valid contours" on the root logger
        try:
            kept = draws[:, keep]
            # Titles as the table writes values: the median ± the draws' standard deviation, to the error's digits
            # (corner's own format gives every parameter the same digits: "0.143" beside an error of 1.5e-05).
            figure = corner.corner(
                kept,
                labels=labels,
                truths=marked[keep],
                quantiles=(0.16, 0.5, 0.84),
                label_kwargs={"fontsize": 9},
            )
            diagonal = figure.axes[:: len(labels) + 1]
            for axis, name, column in zip(diagonal, labels, kept.T, strict=True):
                value = value_with_error(float(np.median(column)), float(np.std(column)))
                axis.set_title(f"{name}\n{value}", fontsize=9)
        finally:
            root.setLevel(level)
    method = result.uncertainty.get("method", "")
    what = "MCMC posterior" if result.draws is not None else f"{method} Gaussian"
    first = f"; the first {MOST_PARAMETERS} of {shown} parameters" if shown > MOST_PARAMETERS else ""
    figure.suptitle(f"{result.model}: {what} (lines: fitted optimum{first})", y=1.02)
    if path is not None:
        save_figure(figure, path, dpi=110, bbox_inches="tight")
    return figure


def _histogram(draws: np.ndarray, label: str, marked: float):
    """The one-parameter "corner plot": a histogram with the 16/50/84% quantiles and the optimum."""
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(4, 3))
    axis.hist(draws, bins=40, histtype="step", color="k")
    for q in np.quantile(draws, (0.16, 0.5, 0.84)):
        axis.axvline(q, color="k", linestyle="--", linewidth=1)
    axis.axvline(marked, color="#4682b4")
    axis.set_xlabel(label)
    axis.set_yticks([])
    return figure


@float64
def _flat_parameters(result: FitResult) -> np.ndarray:
    from ..physics.models.registry import get_model

    model = get_model(result.model, **result.model_options)
    return np.asarray(model.physical.from_params(model.dictionary.to_params(result.params)), dtype=float)
