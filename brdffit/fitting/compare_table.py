"""The printed ranking of a model comparison (``brdffit compare``): one row per model, best first."""

import math

#: The models whose warnings are written out under the table (the others' are counted; the JSON has them all).
WARNINGS_OF_FIRST = 3


def comparison_table(comparison) -> str:
    """The ranking of a :class:`~brdffit.fitting.compare.Comparison`: rank, mark, spec, k, cost, rmse, AIC, BIC, the
    cross-validated loss with its standard error and the count of warnings; then the key, the warnings every model
    shares (about the data) once, the other warnings of the first :data:`WARNINGS_OF_FIRST` models, and every
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
            f"  {_number(score.cv_loss):>10} ± {_number(score.cv_stderr):<9} {len(score.result.warnings):>8}{status}"
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


def _number(value: float) -> str:
    return "—" if math.isnan(value) else f"{value:.4g}"
