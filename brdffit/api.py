"""The fits of the public API: :func:`fit` and :func:`fit_batch`, each with the uncertainty of its results on request.

They join two layers that know nothing of each other: ``brdffit/fitting`` (the fit) and
``brdffit/uncertainty`` (its error bars, which need a fit to start from). Everything else in the public
API lives in its layer and is re-exported by name in ``brdffit/__init__.py``.
"""

import os
from collections.abc import Sequence
from functools import partial
from typing import Any

from ._jax import float64
from .data.load import as_samples, check_read_options
from .data.samples import Samples
from .errors import FitWarning, warn
from .fitting.many.cluster import fit_here, fit_on_cluster
from .fitting.objective.losses import get_loss
from .fitting.options import Holding, Solving, holding_of, solving_of
from .fitting.single.fit import checked, fit_checked
from .fitting.single.result import FitResult
from .physics.models.model import Model
from .physics.models.registry import model_for
from .uncertainty.mcmc import MCMC, check_walkers
from .uncertainty.methods import check_options, with_uncertainty


@float64
def fit(
    samples: Samples | str | os.PathLike,
    model: str | Model = "ward",
    loss: str = "log",
    *,
    max_theta: float | None = None,
    start: dict[str, Any] | None = None,
    n_starts: int | None = None,
    max_steps: int | None = None,
    dtype: str | None = None,
    seed: int | None = None,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    solving: Solving | None = None,
    holding: Holding | None = None,
    uncertainty: str | None = None,
    mcmc: MCMC | None = None,
    chain: str | os.PathLike | None = None,
    progress: bool = False,
    **model_options: Any,
) -> FitResult:
    """Fit ``model`` to ``samples`` (a :class:`Samples`, or a file's path: :func:`brdffit.load_samples` reads it)
    by minimising ``loss`` (``brdffit.LOSSES``); returns a :class:`FitResult`.

    ``max_theta``: drop samples with θi or θo above this many degrees.
    ``start``: parameters (the result file's dictionary) to start from instead of
    the data-driven starts. How the fit is solved, :class:`brdffit.Solving` (``solving=``) or its fields as
    keywords, each None for its default: ``n_starts`` (3), how many of the best grid starts to
    run Levenberg-Marquardt from, the lowest cost winning; ``max_steps`` (256) per start; ``dtype``
    (``float64``): ``float32`` runs the solve with the model in single precision (sums stay float64) and
    then refines the optimum in float64 (mixed-precision iterative refinement,
    usually one or two steps), so the result is float64's; ``seed`` (0): the random part of the subset the starts
    are searched on (above 16,384 samples). What the fit holds, :class:`brdffit.Holding` (``holding=``) or its
    fields as keywords: ``fixed``, parameters held at values, by the result
    file's names (``{"eta": 1.5, "kd": 0, "lobes[1].cxy": 0.577}``; an albedo
    takes one value for every channel or a list); ``bounds``, parameters held
    within ranges (``{"m": (0.05, 0.3)}``); ``docs/holding.md``. Both are
    written to the result (``fit.fixed``, ``fit.bounds``), and the uncertainty
    covers the free parameters only. ``uncertainty``: ``"laplace"`` or ``"mcmc"`` adds the
    result's ``uncertainty``; ``mcmc`` (:class:`brdffit.MCMC`: walkers, steps,
    burn, thin, seed), ``chain`` (a ``.npz`` or ``.h5`` file for the chain) and
    ``progress`` (a progress bar) apply to ``"mcmc"``. ``model_options``:
    ``fresnel=`` for cook-torrance, ``lobes=`` for lafortune.
    """
    solving = solving_of(solving, n_starts=n_starts, max_steps=max_steps, dtype=dtype, seed=seed)
    holding = holding_of(holding, fixed=fixed, bounds=bounds)
    check_options(uncertainty, mcmc, chain)
    samples = as_samples(samples)
    if start is not None and isinstance(model, str):  # Lafortune's number of lobes may come from the start
        model, model_options = model_for(model, start, **model_options), {}
    setup = checked(samples, model, loss, max_theta, holding, **model_options)
    if uncertainty == "mcmc":  # before the fit: emcee needs two walkers per sampled coordinate
        check_walkers(mcmc or MCMC(), setup.model, setup.samples, setup.constraints)
    result = fit_checked(setup, solving, start)
    warn_about(result)
    if uncertainty is None:
        return result
    return with_uncertainty(result, setup.samples, uncertainty, mcmc=mcmc, chain=chain, progress=progress)


@float64
def fit_batch(
    samples: Sequence[Samples | str | os.PathLike],
    model: str | Model = "ward",
    loss: str = "log",
    *,
    strategy: str = "auto",
    progress: bool | None = None,
    max_theta: float | None = None,
    start: dict[str, Any] | Sequence[dict[str, Any]] | None = None,
    n_starts: int | None = None,
    max_steps: int | None = None,
    dtype: str | None = None,
    seed: int | None = None,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    solving: Solving | None = None,
    holding: Holding | None = None,
    uncertainty: str | None = None,
    mcmc: MCMC | None = None,
    client=None,
    read_options: dict[str, Any] | None = None,
    threads: int | None = None,
    **model_options: Any,
) -> list[FitResult]:
    """Fit ``model`` to each of ``samples`` (datasets, or paths read with :func:`brdffit.load_samples` and
    ``read_options``); the results come in the same order.

    The options are those of :func:`fit`, applied to every dataset; ``start``
    may also be a list with one parameter dictionary per dataset.
    ``strategy``: ``auto`` (``vmap`` on a GPU, ``loop`` otherwise), ``loop`` or
    ``vmap``. ``progress``: a progress bar on stderr (default: when stderr is a
    terminal). ``uncertainty`` (``"laplace"`` or ``"mcmc"``, with ``mcmc``
    settings) adds each result's ``uncertainty`` after the fits.
    ``client``: a ``dask.distributed.Client``; the fits are spread over its
    workers (``brdffit/fitting/many/cluster.py``), paths are read there, and the results are
    those of this process's fit. ``threads``: how many batches of datasets
    are fitted at once (default: every CPU core this process may use; on a
    cluster, 1 in each task, whose workers are the parallelism; with
    ``vmap``, always 1: its programs fill the device); the results do not
    depend on it.
    """
    solving = solving_of(solving, n_starts=n_starts, max_steps=max_steps, dtype=dtype, seed=seed)
    holding = holding_of(holding, fixed=fixed, bounds=bounds)
    check_options(uncertainty, mcmc)
    read_options = dict(read_options or {})
    check_read_options(read_options)
    options: dict[str, Any] = dict(
        strategy=strategy,
        max_theta=max_theta,
        solving=solving,
        holding=holding,
        threads=threads,
        then=None if uncertainty is None else partial(with_uncertainty, method=uncertainty, mcmc=mcmc),
    )
    if client is not None:
        first_start = start if isinstance(start, dict) or start is None else next(iter(start), None)
        built = model_for(model, first_start, **model_options) if isinstance(model, str) else model
        get_loss(loss)
        spread: dict[str, Any] = dict(read_options=read_options, start=start, progress=progress)
        results = fit_on_cluster(client, samples, built, loss, **spread, **options)
    else:
        datasets = [as_samples(one, **read_options) for one in samples]
        if uncertainty == "mcmc":  # before any fit: emcee needs two walkers per sampled coordinate
            options["on_checked"] = partial(_check_walkers, mcmc or MCMC())
        results = fit_here(datasets, model, loss, start=start, progress=progress, **options, **model_options)
    for result in results:
        warn_about(result)
    return results


def _check_walkers(settings: MCMC, setup) -> None:
    """emcee's two walkers per sampled coordinate, for one dataset as the fit checked it."""
    check_walkers(settings, setup.model, setup.samples, setup.constraints)


def warn_about(result: FitResult) -> None:
    """Each of the result's caveats as a :class:`~brdffit.FitWarning` (they are also ``result.warnings``)."""
    for caveat in result.warnings:
        warn(FitWarning(caveat))
