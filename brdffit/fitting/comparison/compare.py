"""Which model suits these samples: every candidate fitted, scored by information criteria and cross-validation.

For each model spec (``specs.py``: ``ward``, ``lafortune:lobes=2``) :func:`compare` fits all the samples (the
fit of :func:`brdffit.fit`: its starts, its warnings) and scores it:

* **AIC and BIC** from the Gaussian likelihood of the loss's residuals. Without ``sigma`` the noise scale is
  estimated (its maximum-likelihood value ``Σr²/n``): ``−2 ln L = n ln(Σr²/n)`` up to a constant shared by
  every model, so ``AIC = n ln(Σr²/n) + 2k`` and ``BIC = n ln(Σr²/n) + k ln n`` (Akaike 1974; Schwarz 1978).
  With ``sigma`` the residuals are in units of σ and ``−2 ln L = χ² = Σr²``: ``AIC = χ² + 2k``,
  ``BIC = χ² + k ln n``. ``n`` counts the fitted values (samples × channels with a nonzero weight), ``k`` the
  model's parameters.
* **K-fold cross-validation** (``folds.py``): each fold's samples are held out, the model is refitted on the
  rest, and the held-out loss per residual ``Σr²/n_held`` is measured; ``cv_loss`` is its mean over the folds,
  ``cv_stderr`` the standard error of that mean (standard deviation over folds / √K). A model with more
  parameters always lowers the cost on the data it was fitted to, not always the held-out loss: that is the
  criterion models are ranked by. The best and every model within one standard error of it (``cv_loss ≤
  best + its cv_stderr``, the one-standard-error rule of Hastie, Tibshirani & Friedman 2009, §7.10) are marked.

Each fold's fit starts from the optimum of the fit to all the samples, and every fit of one model runs in one
compiled solver: a fold is the whole problem with its held-out rows switched off (as padding is), so the
folds cost a few Levenberg-Marquardt steps each and no compilation.
"""

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from ..._files import write_text_atomic
from ..._jax import float64
from ..._programs import built_once, jit
from ..._version import __version__
from ...data.load import as_samples
from ...data.samples import Samples
from ...datadriven.model import PcaModel
from ...errors import Argument, BrdfInputError
from ...physics.models.model import Model
from ...physics.models.registry import MODELS, get_model
from ...physics.models.specs import model_of_spec, spec_of
from ..objective.losses import Loss, get_loss
from ..objective.problem import Problem, build_problem, cost, residuals, sample_residuals
from ..options import Holding, Solving, holding_of, solving_of
from ..single.constraints import constraints_for, parameter_names
from ..single.fit import checked, fit_checked, fit_one
from ..single.result import FitResult, json_text, read_json_object, reading_of
from ..solver.compiled import compiled_solver
from .folds import Folds, make_folds

#: The criterion models are ranked by.
CRITERION = "cv_loss"
#: A fold whose held-out loss exceeds this many times the median of the others' is said (one fold dominates the mean).
DOMINANT_FOLD = 100.0


def default_specs() -> list[str]:
    """The specs every registered model says ``compare`` should try (its registry entry's ``compare``): each model,
    Lafortune with 1 to 3 lobes, Cook-Torrance with each Fresnel term."""
    return [spec for entry in MODELS.values() for spec in entry.compare]


@dataclass(frozen=True)
class ModelScore:
    """One candidate's fit and scores (module docstring); ``result`` is its full :class:`FitResult`."""

    spec: str
    k: int
    aic: float
    bic: float
    cv_loss: float
    cv_stderr: float
    fold_losses: list[float]
    result: FitResult = field(repr=False)
    fold_converged: list[bool] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        result = self.result
        return {
            "spec": self.spec,
            "model": result.model,
            "model_options": dict(result.model_options),
            "k": self.k,
            "cost": result.cost,
            "rmse": result.rmse,
            "aic": self.aic,
            "bic": self.bic,
            "cv_loss": self.cv_loss,
            "cv_stderr": self.cv_stderr,
            "fold_losses": list(self.fold_losses),
            "fold_converged": list(self.fold_converged),
            "notes": list(self.notes),
            "converged": result.converged,
            "n_steps": result.n_steps,
            "message": result.message,
            "warnings": list(result.warnings),
            "params": result.params,
            "fixed": dict(result.fixed),
            "bounds": dict(result.bounds),
        }

    @classmethod
    def from_dict(cls, entry: dict[str, Any], comparison: dict[str, Any]) -> "ModelScore":
        """One entry of a comparison file's ``models``; ``comparison`` is the whole file (its loss, channels)."""
        if not isinstance(entry, dict):
            raise TypeError("models must be a JSON list of objects")
        for name, kind in (("model", str), ("model_options", dict), ("params", dict)):
            if not isinstance(entry[name], kind):
                raise TypeError(f"models[].{name} must be a JSON {'string' if kind is str else 'object'}")
        result = FitResult(
            model=entry["model"],
            model_options=dict(entry["model_options"]),
            channels=tuple(comparison["channels"]),
            params=entry["params"],
            loss=comparison["loss"],
            cost=float(entry["cost"]),
            rmse=float(entry["rmse"]),
            n_samples=int(comparison["n_samples"]),
            n_steps=int(entry.get("n_steps", 0)),
            converged=bool(entry["converged"]),
            message=str(entry.get("message", "")),
            warnings=list(entry["warnings"]),
            fixed=dict(entry.get("fixed", {})),
            bounds=dict(entry.get("bounds", {})),
            quantity=None if comparison.get("quantity") is None else str(comparison["quantity"]),
            max_theta=None if comparison.get("max_theta") is None else float(comparison["max_theta"]),
            reading=reading_of(comparison.get("reading", {})),
        )
        aic, bic, cv_loss, cv_stderr = (_number(entry[key]) for key in ("aic", "bic", "cv_loss", "cv_stderr"))
        return cls(
            entry["spec"],
            int(entry["k"]),
            aic,
            bic,
            cv_loss,
            cv_stderr,
            [_number(value) for value in entry["fold_losses"]],
            result,
            [bool(value) for value in entry.get("fold_converged", [])],
            [str(line) for line in entry.get("notes", [])],
        )


@dataclass(frozen=True)
class Comparison:
    """Models compared on one set of samples, best first (by :data:`CRITERION`): ``models`` (also the comparison's
    items, ``comparison[0]`` the best) are :class:`ModelScore` objects, each with its fit as ``result``."""

    source: str
    n_samples: int
    channels: tuple[str, ...]
    loss: str
    folds: int
    fold_kind: str  # "light-direction" or "random"
    seed: int
    models: list[ModelScore]

    @property
    def best(self) -> ModelScore:
        return self.models[0]

    def within_one_stderr(self, score: ModelScore) -> bool:
        """Whether ``score``'s held-out loss is within one standard error of the best's."""
        return score.cv_loss <= self.best.cv_loss + self.best.cv_stderr

    def best_results(self, limit: int = 4) -> list[FitResult]:
        """The fits worth a look: the best and every model within one standard error of it, at most ``limit``."""
        chosen = [score for score in self.models if self.within_one_stderr(score)] or self.models[:1]
        return [score.result for score in chosen[:limit]]

    def __getitem__(self, index: int) -> ModelScore:
        return self.models[index]

    def __iter__(self):
        return iter(self.models)

    def __len__(self) -> int:
        return len(self.models)

    def to_dict(self) -> dict[str, Any]:
        return {
            "brdffit_version": __version__,
            "samples": self.source,
            "n_samples": self.n_samples,
            "channels": list(self.channels),
            "quantity": self.best.result.quantity,
            "max_theta": self.best.result.max_theta,
            "reading": dict(self.best.result.reading),
            "loss": self.loss,
            "folds": self.folds,
            "fold_kind": self.fold_kind,
            "seed": self.seed,
            "criterion": CRITERION,
            "best": self.best.spec,
            "models": [score.to_dict() | {"within_one_stderr": self.within_one_stderr(score)} for score in self.models],
        }

    def to_json(self) -> str:
        # Strict JSON: a fold without held-out values has no loss, written as null.
        return json_text(_nulls(self.to_dict())) + "\n"

    @classmethod
    def from_dict(cls, content: dict[str, Any], source: str = "comparison") -> "Comparison":
        """A comparison file's content, checked: a one-line error for anything else."""
        try:
            comparison = cls(
                str(content["samples"]),
                int(content["n_samples"]),
                tuple(content["channels"]),
                str(content["loss"]),
                int(content["folds"]),
                str(content["fold_kind"]),
                int(content["seed"]),
                [ModelScore.from_dict(entry, content) for entry in content["models"]],
            )
        except (KeyError, TypeError, ValueError, OverflowError) as error:
            raise BrdfInputError(f"{source}: not a brdffit comparison file (missing or bad {error})") from None
        if not comparison.models:  # compare writes one model at least; every reader asks for the best
            raise BrdfInputError(f"{source}: a comparison file of no models; brdffit compare writes one at least")
        return comparison

    def save(self, path: str | os.PathLike) -> None:
        """Write the comparison's JSON atomically."""
        write_text_atomic(path, self.to_json())

    def table(self) -> str:
        """The ranking as a person reads it (``brdffit compare`` prints it)."""
        return comparison_table(self)

    def __str__(self) -> str:
        return self.table()

    def _repr_html_(self) -> str:
        """What a notebook shows for a bare comparison: the ranking as printed, in a ``<pre>`` block (its columns
        line up)."""
        import html

        return f"<pre>{html.escape(self.table())}</pre>"


@float64
def compare(
    samples: Samples | str | os.PathLike,
    models: Sequence[str | Model] | None = None,
    loss: str = "log",
    *,
    folds: int = 5,
    seed: int = 0,
    max_theta: float | None = None,
    n_starts: int | None = None,
    max_steps: int | None = None,
    fixed: dict[str, Any] | None = None,
    bounds: dict[str, Any] | None = None,
    solving: Solving | None = None,
    holding: Holding | None = None,
    progress: bool | None = False,
) -> Comparison:
    """Fit every model of ``models`` (specs such as ``"lafortune:lobes=2"``, or :class:`Model` objects; default
    :func:`default_specs`) to ``samples`` by ``loss`` and rank them by their ``folds``-fold cross-validated loss.

    ``seed`` makes the folds (and, unless ``solving`` is given, the start search's subset); ``max_theta``,
    ``n_starts``, ``max_steps`` and ``solving`` are those of :func:`brdffit.fit` (every fit is float64's). ``fixed``
    and ``bounds`` (or ``holding``: those of :func:`brdffit.fit`) apply to each model that has the parameter named
    (``eta`` to Cook-Torrance's dielectric Fresnel only); a name no model has is refused.
    A fixed parameter is not counted in ``k``. ``progress``: a progress bar on stderr (None: when stderr is a
    terminal). Returns a :class:`Comparison`, best first.
    """
    solving = solving_of(solving, n_starts=n_starts, max_steps=max_steps, seed=None if solving else seed)
    if solving.dtype != "float64":
        raise BrdfInputError(Argument("solving"), ": compare fits in float64; give dtype='float64'")
    holding = holding_of(holding, fixed=fixed, bounds=bounds)
    samples = as_samples(samples).within(max_theta)
    loss_kind = get_loss(loss)
    chosen = [_model(one) for one in (default_specs() if models is None else models)]
    if not chosen:
        raise BrdfInputError(Argument("models"), ": give at least one model to compare")
    _check_every_name_used(chosen, holding)
    # Every model's values and bounds, checked before any fit.
    setups = [checked(samples, model, loss, max_theta, _held_by(model, holding)) for model in chosen]
    split = make_folds(samples, folds, seed)
    problem = build_problem(samples)
    from ..._progress import progress_bar

    bar = progress_bar(len(chosen), "model", progress)
    scores = []
    try:
        for model, setup in zip(chosen, setups, strict=True):
            bar.set_description(spec_of(model.name, model.model_options))
            result = fit_checked(setup, solving)
            fold_losses, fold_converged = _cross_validated(model, loss_kind, result, samples, problem, split, solving)
            score = _score(model, result, fold_losses)
            notes = _fold_notes(fold_losses, fold_converged, split, samples)
            scores.append(replace(score, fold_converged=fold_converged, notes=notes))
            bar.update(1)
    finally:
        bar.close()
    ranked = sorted(scores, key=lambda score: (math.isnan(score.cv_loss), score.cv_loss))
    return Comparison(samples.source, samples.n_samples, samples.channels, loss, split.count, split.kind, seed, ranked)


def load_comparison(path: str | os.PathLike) -> Comparison:
    """Read a comparison file written by :meth:`Comparison.save` or ``brdffit compare -o``."""
    return Comparison.from_dict(read_json_object(path, "brdffit comparison file"), str(path))


def _number(value: Any) -> float:
    """A JSON number, or null read as NaN."""
    return math.nan if value is None else float(value)


def _nulls(value: Any) -> Any:
    """``value`` with every NaN float replaced by None (JSON null)."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {key: _nulls(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_nulls(item) for item in value]
    return value


def _held_by(model: Model, holding: Holding) -> Holding:
    """The part of ``holding`` that names parameters of ``model``."""
    names = set(parameter_names(model))
    return Holding(
        {name: value for name, value in holding.fixed.items() if name in names},
        {name: value for name, value in holding.bounds.items() if name in names},
    )


def _check_every_name_used(models: list[Model], holding: Holding) -> None:
    """A held name that no compared model has is a mistake (a misspelt name would otherwise hold nothing)."""
    names = {name for model in models for name in parameter_names(model)}
    for argument, given in (("fixed", holding.fixed), ("bounds", holding.bounds)):
        for name in given:
            if name not in names:
                raise BrdfInputError(
                    Argument(argument),
                    f": no compared model has a parameter {name!r}; they have {', '.join(sorted(names))}",
                )


def _model(one: str | Model) -> Model:
    if isinstance(one, Model):
        return one
    if not isinstance(one, str):
        raise BrdfInputError(
            Argument("models"), f": each must be a model spec (a string) or a Model, got {type(one).__name__}"
        )
    return model_of_spec(one)


def _cross_validated(
    model: Model, loss: Loss, result: FitResult, samples: Samples, problem: Problem, split: Folds, solving: Solving
) -> tuple[list[float], list[bool]]:
    """The held-out loss per residual of each fold, each fold refitted from the optimum on all the samples, and
    whether each refit converged."""
    counted = np.ones(samples.n_samples, bool) if samples.weight is None else samples.weight > 0
    if isinstance(model, PcaModel):  # the data-driven kind refits by its own solve, with the fit's prior
        refit_model = get_model(result.model, **result.model_options)
        held_out_cost = None
    else:
        solve = compiled_solver(model, loss, solving.max_steps, "float64")  # the one fit_one compiled
        held_out_cost = _held_out_cost(model, loss)
        theta0 = model.unconstrained.from_params(model.dictionary.to_params(result.params))
        constraints = constraints_for(model, samples.n_channels, result.fixed, result.bounds, defaults=False)
        hold = None if constraints is None else constraints.hold()
    losses, converged = [], []
    for k in range(split.count):
        held = split.held_out(k)
        n_held = int(np.sum(held & counted)) * samples.n_channels
        if held_out_cost is None:
            refit = fit_one(samples.select(~held), refit_model, loss, start=result.params, solving=solving)  # no hold
            params = refit_model.dictionary.to_params(refit.params)
            total = np.sum(sample_residuals(refit_model, loss, params, samples.select(held))[counted[held]] ** 2)
            fold_converged = refit.converged
        else:
            fitted = solve(theta0, problem._replace(real=_rows(~held, problem)), hold)
            total = held_out_cost(fitted.theta, problem._replace(real=_rows(held, problem)))
            fold_converged = bool(fitted.converged)
        losses.append(float(total) / n_held if n_held else math.nan)
        converged.append(fold_converged)
    return losses, converged


def _fold_notes(losses: list[float], converged: list[bool], split: Folds, samples: Samples) -> list[str]:
    """What a reader of the ranking must know about a model's folds: refits that did not converge, and a fold whose
    held-out loss dominates the mean (the model predicts those samples far worse than the rest)."""
    notes = [
        f"the refit of fold {k + 1} ({split.describe(k, samples)} held out) did not converge"
        for k, done in enumerate(converged)
        if not done
    ]
    for k, value in enumerate(losses):
        others = [other for j, other in enumerate(losses) if j != k and not math.isnan(other)]
        typical = float(np.median(others)) if others else math.nan
        if others and typical > 0 and value > DOMINANT_FOLD * typical:
            notes.append(
                f"fold {k + 1} ({split.describe(k, samples)} held out) has a held-out loss of {value:.3g},"
                f" {value / typical:.0f}× the median of the others: the model predicts those samples far worse"
            )
    return notes


def _rows(mask: np.ndarray, problem: Problem) -> np.ndarray:
    """``mask`` (N,) over the samples as the problem's row mask: padding rows stay off."""
    rows = np.zeros(problem.real.shape[0], bool)
    rows[: mask.size] = mask
    return rows


@built_once
def _held_out_cost(model: Model, loss: Loss):
    """:func:`held_out_sum` of ``model`` and ``loss``, compiled once per model and loss, and stored (a later process
    neither traces nor lowers it: traced in every process, it cost the warm default comparison ~1.5 s)."""
    return jit(partial(held_out_sum, model, loss))


def held_out_sum(model: Model, loss: Loss, theta, problem: Problem):
    """``Σr²`` of ``model`` at ``theta`` under ``loss`` over the problem's rows that are on (JAX, to be traced)."""
    return cost(partial(residuals, model, loss), theta, problem)


def _score(model: Model, result: FitResult, fold_losses: list[float]) -> ModelScore:
    """AIC, BIC (the result's own, ``fitting/single/criteria.py``) and the cross-validated loss of one fit (module
    docstring); ``k`` counts its free parameters."""
    figures = result.criteria
    held = np.array([value for value in fold_losses if not math.isnan(value)])
    cv_loss = float(np.mean(held)) if held.size else math.nan
    cv_stderr = float(np.std(held, ddof=1) / math.sqrt(held.size)) if held.size > 1 else math.nan
    return ModelScore(
        spec_of(model.name, model.model_options),
        figures.nvarys,
        figures.aic,
        figures.bic,
        cv_loss,
        cv_stderr,
        fold_losses,
        result,
    )


# ---------------------------------------------------------------------- the printed ranking
#: The models whose warnings are written out under the table (the others' are counted; the JSON has them all).
WARNINGS_OF_FIRST = 3


def comparison_table(comparison) -> str:
    """The ranking of a :class:`~brdffit.fitting.comparison.compare.Comparison`: rank, mark, spec, k, cost, rmse, AIC,
    BIC, the cross-validated loss with its standard error and the count of warnings; then the key, the warnings every
    model shares (about the data) once, the other warnings of the first :data:`WARNINGS_OF_FIRST` models, and every
    model's notes on its folds."""
    how = (
        "each holding out whole light directions"
        if comparison.fold_kind == "light-direction"
        else "of samples drawn at random"
    )
    lines = [
        f"models compared on {comparison.source}: {comparison.n_samples} samples × {len(comparison.channels)}"
        f" channel(s), loss {comparison.loss}",
        f"  ranked by the loss per residual on held-out samples: {comparison.folds} folds {how},"
        f" seed {comparison.seed}",
    ]
    width = max(len("model"), *(len(score.spec) for score in comparison.models))
    lines.append(
        f"  rank    {'model'.ljust(width)}   k  {'cost':>11}  {'rmse (1/sr)':>11}  {'AIC':>11}  {'BIC':>11}"
        f"  {'CV loss':>10} ± {'s.e.':<9} warnings"
    )
    for rank, score in enumerate(comparison.models, 1):
        mark = "*" if rank == 1 else "=" if comparison.within_one_stderr(score) else " "
        status = "" if score.result.converged else "  NOT converged"
        lines.append(
            f"  {rank:>4} {mark}  {score.spec.ljust(width)} {score.k:>3}  {score.result.cost:11.5g}"
            f"  {score.result.rmse:11.4g}  {score.aic:11.5g}  {score.bic:11.5g}"
            f"  {_figure(score.cv_loss):>10} ± {_figure(score.cv_stderr):<9} {len(score.result.warnings):>8}{status}"
        )
    lines.append("  * best   = within one standard error of the best")
    for score in comparison.models:
        held = [f"{name} = {_shown(value)}" for name, value in score.result.fixed.items()]
        held += [f"{name} in [{low:g}, {high:g}]" for name, (low, high) in score.result.bounds.items()]
        if held:
            lines.append(f"  {score.spec}: held: {', '.join(held)} (k counts the free parameters)")
    shared = [line for line in comparison.models[0].result.warnings if _in_every(comparison, line)]
    lines += [f"  every model: warning: {line}" for line in shared]
    for score in comparison.models[:WARNINGS_OF_FIRST]:
        lines += [f"  {score.spec}: warning: {line}" for line in score.result.warnings if line not in shared]
    for score in comparison.models:
        lines += [f"  {score.spec}: note: {line}" for line in score.notes]
    return "\n".join(lines)


def _in_every(comparison, line: str) -> bool:
    """Whether every model's fit has the warning ``line`` (one about the data, such as non-reciprocal values)."""
    return all(line in score.result.warnings for score in comparison.models)


def _shown(value) -> str:
    """A fixed value: one number, or an albedo's per channel (one number when they are all equal)."""
    values = value if isinstance(value, list) else [value]
    return f"{values[0]:.10g}" if len(set(values)) == 1 else "[" + ", ".join(f"{one:.10g}" for one in values) + "]"


def _figure(value: float) -> str:
    """A held-out loss as the ranking shows it: 4 digits, or — where a fold held nothing out."""
    return "—" if math.isnan(value) else f"{value:.4g}"
