"""The fit's options as objects, each checked once: how to solve (:class:`Solving`) and what to hold (:class:`Holding`).

``brdffit.fit``, ``fit_batch``, ``compare`` and ``report`` take them (``solving=brdffit.Solving(n_starts=5)``,
``holding=brdffit.Holding(fixed={"eta": 1.5})``) or, as before, their fields as keywords (``n_starts=5``,
``fixed={"eta": 1.5}``): :func:`solving_of` and :func:`holding_of` turn either form into the object, with one-line
errors, once per call; the fit's layers pass the objects on. ``brdffit.MCMC`` is the third such object (the
sampler's settings, ``uncertainty/mcmc.py``). No JAX here: the command line's help shows the defaults.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..checks import choice, whole_number
from ..errors import Argument, BrdfInputError

#: Levenberg-Marquardt runs from the best grid starts; the lowest cost wins.
N_STARTS = 3
#: Most solver steps per start.
MAX_STEPS = 256
#: The largest ``max_steps`` allowed: far beyond any fit's need (a few hundred), and within the solver's int32 step
#: counter (``--max-steps 1e12`` overflowed it).
MAX_STEPS_ALLOWED = 1_000_000
#: The precisions a fit's model is evaluated in (its sums, and its result, are float64's either way).
DTYPES = ("float64", "float32")


@dataclass(frozen=True)
class Solving:
    """How a fit is solved: from the ``n_starts`` best grid starts (the lowest cost wins), at most ``max_steps``
    Levenberg-Marquardt steps each, the model evaluated in ``dtype`` (``float32`` refines the optimum in float64, so
    the result is float64's), ``seed`` drawing the random part of the subset the starts are searched on (above
    16,384 samples). Checked when made: a one-line error names the argument."""

    n_starts: int = N_STARTS
    max_steps: int = MAX_STEPS
    dtype: str = "float64"
    seed: int = 0

    def __post_init__(self):
        object.__setattr__(self, "n_starts", whole_number("n_starts", self.n_starts))
        object.__setattr__(self, "max_steps", whole_number("max_steps", self.max_steps, 1, MAX_STEPS_ALLOWED))
        choice("dtype", self.dtype, DTYPES)
        object.__setattr__(self, "seed", whole_number("seed", self.seed, 0))


@dataclass(frozen=True)
class Holding:
    """What a fit holds, by the result file's parameter names: ``fixed`` values (``{"eta": 1.5, "kd": 0}``; an albedo
    takes one value for every channel or a list of one per channel) and ``bounds`` (``{"m": (0.05, 0.3)}``), checked
    against a model and the samples' channels when a fit starts (``single/constraints.py``, ``docs/holding.md``)."""

    fixed: Mapping[str, Any] = field(default_factory=dict)
    bounds: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "fixed", parameter_mapping(self.fixed, "fixed"))
        object.__setattr__(self, "bounds", parameter_mapping(self.bounds, "bounds"))

    def __bool__(self) -> bool:
        return bool(self.fixed or self.bounds)


def parameter_mapping(value: Any, argument: str) -> dict[str, Any]:
    """``value`` (``fixed=`` or ``bounds=``) as a dict of parameter names; None is empty."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise BrdfInputError(
            Argument(argument), f" must be a dictionary of parameter names (as in the result file), got {value!r}"
        )
    return dict(value)


def solving_of(solving: Solving | None = None, **keywords: Any) -> Solving:
    """The :class:`Solving` a call asks for: ``solving``, or its fields given as keywords (those given as None take
    their default); not both."""
    return _options_of(Solving, "solving", solving, keywords)


def holding_of(holding: Holding | None = None, **keywords: Any) -> Holding:
    """The :class:`Holding` a call asks for: ``holding``, or ``fixed=`` and ``bounds=``; not both."""
    return _options_of(Holding, "holding", holding, keywords)


def _options_of(kind: type, argument: str, given, keywords: dict[str, Any]):
    keywords = {key: value for key, value in keywords.items() if value is not None}
    if given is None:
        return kind(**keywords)
    if not isinstance(given, kind):
        raise BrdfInputError(Argument(argument), f" must be brdffit.{kind.__name__}(...), got {type(given).__name__}")
    if keywords:
        raise BrdfInputError(
            Argument(next(iter(keywords))), " and ", Argument(argument), " are both given; give the options in one"
        )
    return given


#: The defaults, as the objects the fit's layers pass on.
SOLVING = Solving()
HOLDING_NOTHING = Holding()
