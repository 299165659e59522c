"""Fit a model to one set of samples: start → solve → caveats → result (:func:`fit_one`).

A lobe model starts from its grid's best shapes (``starts/grid.py``) and is solved by Levenberg-Marquardt
(``solver/``) in the compiled programs a batch of many datasets also runs (``stacked.py``); its caveats and result
come last (``caveats.py``, ``outcome.py``). A model of several lobes (Lafortune's) is placed and fitted lobe by
lobe instead (``starts/lobes.py``); the data-driven kind fits by a solve of its own (``datadriven/fit.py``).
"""

from typing import Any, NamedTuple

import numpy as np

from ..._jax import float64, jax
from ...data.samples import Samples
from ...datadriven.fit import fit_pca
from ...datadriven.model import PcaModel
from ...errors import Argument, BrdfInputError
from ...physics.domains import START_FACTOR
from ...physics.models.model import LobeModel, Model
from ...physics.models.params import lobe_family
from ...physics.models.registry import MODELS, get_model, model_option_names, recorded_options
from ..objective.losses import Loss, get_loss
from ..objective.problem import Problem, build_problem
from ..options import HOLDING_NOTHING, SOLVING, Holding, Solving
from ..solver.compiled import best, compiled_solver
from ..solver.hold import Hold
from ..starts.grid import search_subset
from ..starts.lobes import lobe_by_lobe
from .constraints import Constraints, constraints_for
from .outcome import result_of
from .result import FitResult
from .stacked import StackedFit, compile_in_background, default_strategy, onto_bounds


class Setup(NamedTuple):
    """What a fit is given, checked once (:func:`checked`): the model, the loss, the samples kept by ``max_theta``
    and what the fit holds (``constraints.py``; None for nothing)."""

    model: Model
    loss: Loss
    samples: Samples
    constraints: Constraints | None
    max_theta: float | None


@float64
def fit_one(
    samples: Samples,
    model: str | Model = "ward",
    loss: str = "log",
    *,
    max_theta: float | None = None,
    start: dict[str, Any] | None = None,
    solving: Solving = SOLVING,
    holding: Holding = HOLDING_NOTHING,
    caveats: bool = True,
    **model_options: Any,
) -> FitResult:
    """Fit ``model`` to ``samples`` by minimising ``loss``; the arguments are those of :func:`brdffit.fit`, and
    ``caveats`` those of :func:`fit_checked`."""
    setup = checked(samples, model, loss, max_theta, holding, **model_options)
    return fit_checked(setup, solving, start, caveats=caveats)


@float64
def fit_checked(
    setup: Setup, solving: Solving, start: dict[str, Any] | None = None, *, caveats: bool = True
) -> FitResult:
    """The fit of what :func:`checked` passed, from ``start`` (a parameter dictionary) or the data's own starts.
    ``caveats=False``: the result says only what the fit held (a parameter on its bound), not what the data may hide
    (``caveats.py``): for samples that are a model's own values (an export's refit), where the caveats' screens and
    checks would cost more than the solve and say nothing."""
    model, loss, samples, constraints, max_theta = setup
    if not isinstance(model, LobeModel | PcaModel):
        raise BrdfInputError(
            f"model {model.name}: brdffit fits lobe models and the data-driven model, not {type(model).__name__}"
        )
    if isinstance(model, PcaModel):  # the data-driven kind: a ridge start and a solve of its own
        if solving.dtype != "float64":
            raise BrdfInputError(
                Argument("dtype", solving.dtype), f" does not apply to model {model.name}; it fits in float64"
            )
        return fit_pca(samples, model, loss, start=start, max_steps=solving.max_steps, max_theta=max_theta)
    hold = None if constraints is None else constraints.hold()
    if start is None and model.n_lobes > 1:  # several lobes: placed and fitted one at a time
        solved, by_lobe = _lobe_by_lobe(model, loss, samples, solving, hold)
        steps, dtype = solving.max_steps, solving.dtype
        fewer_lobes_cost = by_lobe.fewer_lobes_cost if by_lobe.searched_all else None
        return result_of(
            model,
            loss,
            samples,
            solved,
            steps,
            dtype,
            fewer_lobes_cost,
            max_theta,
            more_caveats=by_lobe.caveats(loss, solving.n_starts) if caveats else (),
            constraints=constraints,
            with_caveats=caveats,
        )
    strategy = default_strategy()
    # the start is checked before the fit sets to work (its reciprocity check, its programs' compilation)
    given = None if start is None else start_vector(model, start, samples.n_channels)[None]
    fit = StackedFit(model, loss, [samples], hold, solving=solving, strategy=strategy, caveats=caveats)  # one dataset
    thetas = fit.starts(given)  # start: the given one, or the grid's best shapes, raced
    solved = fit.solve(thetas)  # solve: Levenberg-Marquardt
    (result,) = fit.results(solved, max_theta=max_theta, constraints=constraints)  # caveats, result
    return result


def _lobe_by_lobe(model: LobeModel, loss: Loss, samples: Samples, solving: Solving, hold: Hold | None):
    """The best solve of a model of several lobes and its :class:`~brdffit.fitting.starts.lobes.LobeFit` (the cost
    with one lobe less, the minima its starts ended in), searched on the search subset when there is one and refined
    on every sample; every solve respects ``hold``."""
    n_starts, max_steps, dtype, seed = solving.n_starts, solving.max_steps, solving.dtype, solving.seed
    full = build_problem(samples, dtype)
    compiled = compiled_solver(model, loss, max_steps, dtype)
    solve = lambda theta, problem: compiled(theta, problem, hold)
    search = search_problem(samples, full, dtype, seed)
    compiling = None
    if search is not full:
        theta = jax.ShapeDtypeStruct((model.unconstrained.size(samples.n_channels),), np.float64)
        compiling = compile_in_background(compiled, theta, full, hold)
    by_lobe = lobe_by_lobe(model, loss, search, solve, n_starts, best, hold)
    solved = by_lobe.best  # solved on every sample, unless searched on a subset
    if compiling is not None:
        compiling.join()
        solved = solve(by_lobe.best.theta, full)
    if dtype == "float32":
        refined = compiled_solver(model, loss, max_steps)(solved.theta, build_problem(samples), hold)
        solved = refined._replace(n_steps=solved.n_steps + refined.n_steps)
    if hold is not None and np.any(hold.bounded):
        one = compiled_solver(model, loss, max_steps)
        full64 = full if dtype == "float64" else build_problem(samples)
        batched = lambda thetas, holds: jax.tree.map(lambda leaf: leaf[None, None], one(thetas[0], full64, _row(holds)))
        stacked = jax.tree.map(lambda leaf: np.asarray(leaf)[None], solved)
        solved = jax.tree.map(
            lambda leaf: leaf[0], onto_bounds(batched, stacked, jax.tree.map(lambda a: a[None], hold))
        )
    return solved, by_lobe._replace(searched_all=search is full)


def _row(holds: Hold) -> Hold:
    return jax.tree.map(lambda leaf: leaf[0], holds)


def search_problem(samples: Samples, full: Problem, dtype: str, seed: int) -> Problem:
    """The problem the starts are searched on: ``full``, or that of the subset ``starts/grid.search_subset`` picks."""
    subset = search_subset(samples, seed)
    return full if subset is None else build_problem(samples.select(subset), dtype)


def checked(samples, model, loss, max_theta, holding: Holding = HOLDING_NOTHING, **model_options) -> Setup:
    """What a fit of ``samples`` is given, after every check of the arguments (:class:`Setup`; the solver's options
    checked themselves when they were made, :class:`~brdffit.fitting.options.Solving`)."""
    _check_option_names(model_options)
    model = get_model(model, **model_options)
    loss = get_loss(loss)
    if not isinstance(samples, Samples):
        raise BrdfInputError(f"fit takes Samples (from brdffit.load_samples), got {type(samples).__name__}")
    samples = samples.within(max_theta)
    constraints = constraints_for(model, samples.n_channels, holding.fixed, holding.bounds)
    n_parameters = model.unconstrained.size(samples.n_channels) if constraints is None else constraints.n_free
    free = "" if constraints is None else "free "
    if samples.values.size < n_parameters and not model.prior_weight > 0:  # a prior determines what data cannot
        raise BrdfInputError(
            f"{samples.source}: {samples.n_samples} sample(s) × {samples.n_channels} channel(s) cannot determine"
            f" the {n_parameters} {free}parameters of {model.name}; give at least {n_parameters} values"
        )
    return Setup(model, loss, samples, constraints, max_theta)


def _check_option_names(options: dict[str, Any]) -> None:
    """A keyword no model takes is a misspelt argument, not a model option (``max_step`` for ``max_steps``)."""
    known = {name for each in MODELS for name in model_option_names(each)}
    for key in options:
        if key not in known:
            listed = ", ".join(sorted(known - recorded_options()))  # a result's recorded options are taken, not offered
            raise BrdfInputError(
                Argument(key), f" is not an argument of the fit, nor an option of any model ({listed})"
            )


def start_vector(model: Model, start: dict[str, Any], n_channels: int) -> np.ndarray:
    """The unconstrained vector of the parameter dictionary ``start``, checked against the samples' channels and
    each lobe-shape parameter's plausible range: beyond :data:`~brdffit.physics.domains.START_FACTOR` times its
    upper end a fit cannot move (a Phong exponent of 10⁹ is a delta function, flat to every step) and would report
    a converged fit that never moved. An albedo can start anywhere: the fit moves its logarithm."""
    assert isinstance(model, LobeModel), f"start_vector takes a lobe model, not {type(model).__name__}"
    try:
        params = model.dictionary.to_params(start)
    except BrdfInputError as error:  # the dictionary's own message, said of the start
        raise BrdfInputError(Argument("start"), ": ", *error.parts) from None
    if params.diffuse.size != n_channels:
        raise BrdfInputError(
            Argument("start"), f" parameters have {params.diffuse.size} channel(s) but the samples have {n_channels}"
        )
    if model.n_lobes:
        for k in range(model.n_lobes):
            for name, domain in lobe_family(model).parameters:
                # the largest channel's value for a per-channel parameter (a conductor's eta, k)
                value, limit = float(np.max(params.shape[name][k])), START_FACTOR * domain.plausible[1]
                if value > limit:
                    where = f"lobes[{k}].{name}" if model.lobes_as_list else name
                    raise BrdfInputError(
                        Argument("start"),
                        f": {where} = {value:g} is far beyond its plausible range"
                        f" (≤ {domain.plausible[1]:g}), where a fit cannot move; give at most {limit:g}",
                    )
    return model.unconstrained.from_params(params)
