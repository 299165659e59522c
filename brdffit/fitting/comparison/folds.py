"""K-fold splits of samples for cross-validation, grouped by light direction where the data allow.

A gonioreflectometer measures many view directions per light direction. Random folds would hold out
samples whose neighbours (same light, a degree away in view) stay in the training set, and the held-out
loss would measure interpolation between neighbours, not how well the model generalises. So when the data
have at least :data:`MIN_GROUPS` distinct light directions, every fold holds out whole light directions
(grouped K-fold, as scikit-learn's ``GroupKFold``: groups assigned largest first to the fold with the fewest
samples, ties broken by a seeded shuffle). Otherwise (one to four light directions, or random data where every
sample has its own) folds are random, of equal size, seeded.
"""

from typing import NamedTuple

import numpy as np

from ...checks import whole_number
from ...data.samples import Samples
from ...errors import BrdfInputError

#: Distinct light directions from which folds hold out whole light directions.
MIN_GROUPS = 5


class Folds(NamedTuple):
    """Which fold each sample is held out in (N,), how the folds were made, and how many groups they hold."""

    fold: np.ndarray  # (N,) in 0 … count − 1
    count: int  # type: ignore[assignment]  # a field, named as the tuple method it shadows
    kind: str  # "light-direction" or "random"
    groups: int  # distinct light directions

    def held_out(self, k: int) -> np.ndarray:
        """The mask (N,) of the samples fold ``k`` holds out."""
        return self.fold == k

    def describe(self, k: int, samples: Samples) -> str:
        """What fold ``k`` holds out, as a person reads it: ``light zeniths 39.4°, 84.4°``, or ``1/5 of the
        samples, at random``."""
        if self.kind != "light-direction":
            return f"1/{self.count} of the samples, at random"
        zeniths = np.unique(np.round(samples.theta_i[self.held_out(k)], 1))
        return "light zenith" + ("s " if zeniths.size > 1 else " ") + ", ".join(f"{z:g}°" for z in zeniths)


def make_folds(samples: Samples, folds: int = 5, seed: int = 0) -> Folds:
    """``folds`` folds of ``samples`` (module docstring), seeded by ``seed``."""
    folds = whole_number("folds", folds, 2)
    rng = np.random.default_rng(seed)
    _, group = samples.light_directions()
    n_groups = int(group.max()) + 1
    if MIN_GROUPS <= n_groups < samples.n_samples:
        if n_groups < folds:
            raise BrdfInputError(
                f"{samples.source}: {n_groups} light directions cannot fill {folds} folds that each hold out whole"
                f" light directions; give folds ≤ {n_groups}"
            )
        sizes = np.bincount(group, minlength=n_groups)
        order = rng.permutation(n_groups)
        order = order[np.argsort(-sizes[order], kind="stable")]  # largest first, equal sizes in seeded order
        fold_of_group, filled = np.empty(n_groups, np.int64), np.zeros(folds, np.int64)
        for g in order:
            k = int(np.argmin(filled))
            fold_of_group[g], filled[k] = k, filled[k] + sizes[g]
        return Folds(fold_of_group[group], folds, "light-direction", n_groups)
    if samples.n_samples < folds:
        raise BrdfInputError(f"{samples.source}: {samples.n_samples} samples cannot fill {folds} folds")
    fold = np.empty(samples.n_samples, np.int64)
    fold[rng.permutation(samples.n_samples)] = np.arange(samples.n_samples) % folds
    return Folds(fold, folds, "random", n_groups)
