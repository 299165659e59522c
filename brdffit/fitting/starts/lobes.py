"""Several lobes, fitted one at a time: each new lobe placed on what the lobes so far leave unexplained.

A model of several lobes (Lafortune's) has many local minima: a lobe can settle where it explains nothing
and stay there, dead, while the fit reports convergence. Started from grid shapes alone, the real
retro-reflective tape's 3-lobe log-loss fit stopped at twice the cost that 30 starts find. So the fit goes
lobe by lobe:

1. the first lobe at the grid's best shapes, fitted alone (the other lobes switched off: albedo 0, which
   the solver's dead-column rule leaves alone, so every fit runs in the one compiled solver of the model);
2. each next lobe placed beside the lobes fitted so far (variable projection over the grid, ``grid.py``)
   at the best shape of every family of directions (forward, retro, normal, flatter, steeper), and the
   whole model refitted from each; the best goes on to the next lobe;
3. at the end the greedy grid starts of the whole model compete too.

The cost of each level is kept: a fit with more lobes must not end worse than one with fewer (a caveat
says so when it does, ``caveats.py``). So are the minima the last level's runs end in. Under a loss linear in the
values (l2, cosine) the brightest samples rule the cost and the default starts miss lower minima: on the real
retro-reflective tape, 2 lobes end at cost 14,974 where 30 starts find 10,174 (a narrow retro lobe of albedo
5·10⁷), and 3 of its 4 l2 cases stop above the best known; under the log loss all 4 reach it. Such a fit whose
runs ended in more than one minimum says that a lower one may exist (:meth:`LobeFit.caveats`).
"""

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from ...physics.models.model import LobeModel
from ...physics.models.params import lobe_family
from ..objective.losses import Loss
from ..objective.problem import Problem
from ..solver.compiled import Solved
from ..solver.hold import Hold
from .grid import LobeSearch, starting_points

#: Two runs whose costs differ by more than this fraction ended in different minima: the solver stops within
#: ~1e-10 of a minimum's cost (``solver/``), and a thousandth of a percent is no difference a user would see.
SAME_MINIMUM = 1e-5


class LobeFit(NamedTuple):
    """The best run of a lobe-by-lobe fit (a ``solver/compiled.Solved``), the cost with one lobe less and the costs
    the last lobe's runs ended at, on the problem searched."""

    best: Solved
    fewer_lobes_cost: float
    last_costs: tuple[float, ...] = ()
    #: Whether the levels were searched on every sample (their costs then compare with the fit's), not a subset.
    searched_all: bool = True

    def caveats(self, loss: Loss, n_starts: int) -> list[str]:
        """What a user must know when, under a loss linear in the values, the last lobe's runs ended in more than
        one minimum (module docstring)."""
        minima = distinct_minima(self.last_costs)
        if not loss.linear or len(minima) < 2:
            return []
        return [
            f"a model of several lobes has many local minima under the {loss.name} loss: the last lobe's"
            f" {len(self.last_costs)} runs ended in {len(minima)} different ones (cost {minima[0]:.6g} to"
            f" {minima[-1]:.6g}), so a lower one may exist: more starts than {n_starts} search further (--starts,"
            " n_starts in Python), or the log loss is less ruled by the brightest samples"
        ]


def distinct_minima(costs) -> list[float]:
    """The different values among ``costs``, ascending: each more than :data:`SAME_MINIMUM` (relative) above the
    last; non-finite costs (a run that failed) are left out."""
    minima: list[float] = []
    for cost in sorted(float(c) for c in costs if np.isfinite(c)):
        if not minima or cost > minima[-1] * (1 + SAME_MINIMUM) + np.finfo(float).tiny:
            minima.append(cost)
    return minima


def lobe_by_lobe(
    model: LobeModel,
    loss: Loss,
    problem: Problem,
    solve: Callable,
    n_starts: int,
    best: Callable,
    hold: Hold | None = None,
) -> LobeFit:
    """Fit ``model``'s lobes one at a time on ``problem`` with the compiled ``solve``; ``best`` picks among runs.
    Every start respects ``hold``, which ``solve`` applies (``hold.py``)."""
    search = LobeSearch(model, loss, problem, hold)
    n_channels = problem.measured.shape[1]
    level_costs = []
    fitted: Solved | None = None
    for placed in range(model.n_lobes):
        chosen = [] if fitted is None else _shapes(model, fitted.theta, n_channels, placed)
        costs, thetas = search.candidates(chosen)
        starts = _each_family(search.grid, costs, extra=n_starts if placed == 0 else 0)
        runs = [solve(thetas[index], problem) for index in starts]
        if placed == model.n_lobes - 1:
            runs += [solve(theta, problem) for theta in starting_points(model, loss, problem, n_starts, hold)]
        started = tuple(float(run.cost) for run in runs)
        if fitted is not None:
            runs.append(fitted)  # the lobes so far with the new one off: never worse than one lobe less
        fitted = best(runs)
        level_costs.append(float(fitted.cost))
    assert fitted is not None  # a model fitted lobe by lobe has lobes
    fewer = level_costs[-2] if len(level_costs) > 1 else float("nan")
    return LobeFit(fitted, fewer, started)


def _shapes(model: LobeModel, theta, n_channels: int, count: int) -> list[dict[str, float]]:
    """The shapes of the first ``count`` lobes at the unconstrained ``theta``."""
    shape = model.unconstrained.to_params(np.asarray(theta), n_channels).shape
    return [{name: float(shape[name][k]) for name in lobe_family(model).names} for k in range(count)]


def _each_family(grid: tuple[dict[str, float], ...], costs: np.ndarray, extra: int) -> list[int]:
    """Grid indices: the cheapest shape of each family (shapes alike but for their last parameter, the lobe's
    width: a Lafortune direction, a roughness's Fresnel term), then the ``extra`` cheapest others, best first."""
    order = np.argsort(costs, kind="stable")
    chosen, families = [], set()
    for index in order:
        family = tuple(list(grid[index].values())[:-1])
        if family not in families:
            families.add(family)
            chosen.append(int(index))
    chosen += [int(index) for index in order if int(index) not in chosen][:extra]
    return sorted(chosen, key=lambda index: costs[index])
