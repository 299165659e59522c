"""A solve as a :class:`FitResult`: its parameters moved onto their domains and into their canonical form, its caveats,
how it ended.

Every fit ends here, whichever way it was solved: one dataset or a batch of many (``stacked.py``), a model of several
lobes (``fit.py``), the data-driven model's own solve (``datadriven/fit.py``).
"""

import functools
from collections.abc import Sequence

import numpy as np

from ..._jax import jax
from ...data.reciprocity import ReciprocityAhead
from ...data.samples import Samples
from ...physics.models.model import LobeModel, Model
from ...physics.models.params import Params
from ..objective.losses import Loss
from ..solver.compiled import Solved, failure_message
from .caveats import EDGE, Screened, caveats
from .constraints import Constraints
from .criteria import fitted_values
from .result import FitResult


def final_params(model: Model, solved: Solved, n_channels: int) -> Params:
    """A solve's parameters (numpy), each moved onto its domain where the solver's coordinates reached its edge
    only in the limit."""
    physical = np.asarray(model.physical.from_params(jax.tree.map(np.asarray, solved.params)))
    low, high = _domain_bounds(model, n_channels)
    if not np.all(np.isfinite(physical) & (physical > low) & (physical < high)):  # else every domain holds it
        domains = model.physical.domains(n_channels)
        physical = np.array([domain.nearest_inside(value) for value, domain in zip(physical, domains, strict=True)])
    params = model.physical.to_params(physical, n_channels)
    return _onto_meaningful_ends(model, params)


@functools.lru_cache(maxsize=64)
def _domain_bounds(model: Model, n_channels: int) -> tuple[np.ndarray, np.ndarray]:
    """The lower and upper bounds of each entry of ``model``'s physical vector, made once: a fit per texel asks
    thousands of times."""
    low, high = np.array([domain.bounds for domain in model.physical.domains(n_channels)], float).T
    return low, high


def _onto_meaningful_ends(model: Model, params: Params) -> Params:
    """``params`` with each parameter whose domain's ends are values of their own (``Lobe.meaningful_ends``: glTF's
    metallic) put onto the end it lies within :data:`~brdffit.fitting.single.caveats.EDGE` of: the solver's logistic
    map reaches an end only in the limit, and a user reads ``metallic 0``, not ``7e-09``."""
    if not isinstance(model, LobeModel) or model.lobe is None or not model.lobe.meaningful_ends:
        return params
    shape = dict(params.shape)
    for name in model.lobe.meaningful_ends:
        low, high = dict(model.lobe.parameters)[name].bounds
        value = np.asarray(shape[name], float)
        shape[name] = np.where(value - low < EDGE, low, np.where(high - value < EDGE, high, value))
    return Params(params.diffuse, params.specular, shape)


def canonical_params(model: Model, params: Params, constraints: Constraints | None = None) -> Params:
    """``params`` (numpy) with each lobe's shape in its family's canonical form (``Lobe.canonical``: an anisotropic
    lobe's ``alpha_u ≤ alpha_v``), unless that would move a shape parameter ``constraints`` hold: the user's naming
    wins."""
    if not isinstance(model, LobeModel) or model.lobe is None:
        return params
    shape = model.lobe.canonical({name: np.asarray(value) for name, value in params.shape.items()})
    held = set() if constraints is None else constraints.held_shapes
    if any(not np.array_equal(shape[name], params.shape[name]) for name in held):
        return params
    return Params(params.diffuse, params.specular, shape)


def result_of(
    model: Model,
    loss: Loss,
    samples: Samples,
    solved: Solved,
    max_steps: int,
    dtype: str,
    fewer_lobes_cost: float | None = None,
    max_theta: float | None = None,
    screened: Screened | None = None,
    more_caveats: Sequence[str] = (),
    constraints: Constraints | None = None,
    params: Params | None = None,
    with_caveats: bool = True,
    reciprocal: ReciprocityAhead | None = None,
) -> FitResult:
    """The :class:`FitResult` of a solve, with its caveats (``caveats.py``) and ``more_caveats`` (the model's own);
    ``samples`` are those fitted, selected by ``max_theta``. ``screened``: what the caveats' screens found for this fit,
    when the caller screened many fits at once (``caveats.screen_bucket``). ``constraints``: what the fit
    held; its fixed values are written exactly, and a parameter that ended on a bound is said. ``params``: the
    solve's :func:`final_params`, when the caller has them. ``with_caveats=False``: only what the constraints say
    (``fit.fit_checked``). ``reciprocal``: the samples' reciprocity, when the caller started its check earlier
    (``reciprocity.ReciprocityAhead``)."""
    converged = bool(solved.converged)
    params = final_params(model, solved, samples.n_channels) if params is None else params
    params = canonical_params(model, params, constraints)
    if constraints is not None:
        params = constraints.within_bounds(constraints.with_fixed(params))
        more_caveats = [*constraints.bound_warnings(solved.theta), *more_caveats]
    found = []
    if with_caveats:
        held = frozenset(() if constraints is None else constraints.fixed)
        found = caveats(
            model,
            samples,
            params,
            float(solved.cost),
            fewer_lobes_cost,
            screened=screened,
            held=held,
            reciprocal=reciprocal,
        )
    return FitResult(
        model=model.name,
        model_options=model.model_options,
        channels=samples.channels,
        params=model.dictionary.from_params(params),
        loss=loss.name,
        cost=float(solved.cost),
        rmse=float(solved.rmse),
        n_samples=samples.n_samples,
        n_values=fitted_values(samples.n_samples, samples.n_channels, samples.weight),
        sigma=samples.sigma is not None,
        n_steps=int(solved.n_steps),
        converged=converged,
        message="" if converged else failure_message(int(solved.result), max_steps),
        dtype=dtype,
        warnings=[*found, *more_caveats],
        quantity=samples.provenance.quantity if samples.provenance else None,
        max_theta=max_theta,
        reading=dict(samples.provenance.reading) if samples.provenance else {},
        fixed={} if constraints is None else dict(constraints.fixed),
        bounds={} if constraints is None else dict(constraints.bounds),
    )
