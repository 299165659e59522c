"""What a user holds: fixed parameters and bounded ones, by the names of the result file.

``fixed={"eta": 1.5, "kd": 0, "lobes[1].cxy": 0.577}`` and ``bounds={"m": (0.05, 0.3)}``. Names are those of the
result file's ``params``: an albedo (``kd``, ``rho_d``, ``lobes[0].rho_s``) and a shape parameter with one value per
channel (a conductor's ``eta``, ``k``) take one value for every channel or a list of one per channel, a lobe's other
shape parameters (``m``, a dielectric's ``eta``, ``alpha_x``, ``lobes[1].n``) one number. A bound is a range
``[lo, hi]`` inside the parameter's domain; an albedo's and a per-channel parameter's applies to each channel.

A model may hold parameters by default (``LobeModel.held``: a conductor's ``ks`` at 1, its Fresnel term being the
reflectance); a user frees one with ``fixed={"ks": None}`` (``--free ks``), or fixes or bounds it otherwise.

:class:`Constraints` checks them against a model (one-line errors) and turns them into what each part of brdffit needs:
the solver's :class:`~brdffit.fitting.solver.hold.Hold` over the unconstrained vector, the mask of the coordinates the
MCMC walkers move and their bounds, the number of free parameters (``compare``'s ``k``), and the result's parameters
with the fixed ones at exactly their values. Every coordinate system has the same entries (``coordinates.py``), so one
mask serves all; a Lafortune lobe's ``cxy`` and ``cz`` are both its angle ``ψ`` (``Lobe.coordinate_index``), and ``cxy``
alone holds it with ``cz ≥ 0`` (``Lobe.shape_holding``).
"""

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import Argument, BrdfInputError
from ...physics.domains import Domain
from ...physics.models.model import LobeModel, Model
from ...physics.models.params import Params, albedo_size, lobe_family
from ..options import parameter_mapping
from ..solver.hold import Hold, on_bound

_LOBE_NAME = re.compile(r"^lobes\[(\d+)\]\.(\w+)$")
#: The value every albedo that is not held takes while the vectors of the held ones are computed (any would do).
_ANY_ALBEDO = 0.5


@dataclass(frozen=True)
class Target:
    """One parameter a user names: which lobe (0 for a model's only lobe), what kind, and its dictionary name."""

    name: str  # as the user wrote it: "kd", "eta", "lobes[1].cxy"
    kind: str  # "diffuse", "specular" or "shape"
    lobe: int
    parameter: str  # the name within the lobe: "ks", "m", "cxy"
    domain: Domain


@dataclass(frozen=True)
class Constraints:
    """Fixed values and bounds of ``model``'s parameters for ``n_channels`` channels, checked (:func:`constraints_for`).

    ``fixed``: name → a number, or a list of one per channel for an albedo. ``bounds``: name → ``[lo, hi]``. Both are
    written to the result file (``fit.fixed``, ``fit.bounds``) as they are here.
    """

    model: LobeModel
    n_channels: int
    fixed: dict[str, Any] = field(default_factory=dict)
    bounds: dict[str, list[float]] = field(default_factory=dict)

    # ------------------------------------------------------------------ which entries
    def _entries(self, name: str) -> list[int]:
        return _entries(self.model, _target(self.model, name), self.n_channels)

    @property
    def free(self) -> np.ndarray:
        """(k,) bool: the entries of the unconstrained (and sampling) vector that move."""
        free = np.ones(self.model.unconstrained.size(self.n_channels), bool)
        for name in self.fixed:
            free[self._entries(name)] = False
        return free

    @property
    def n_free(self) -> int:
        """How many parameters the fit determines: the unconstrained vector's entries less the fixed ones."""
        return int(self.free.sum())

    @property
    def held_shapes(self) -> set[str]:
        """The lobe-shape parameters (by their names within a lobe: ``m``, ``alpha_u``) fixed or bounded."""
        targets = (_target(self.model, name) for name in (*self.fixed, *self.bounds))
        return {target.parameter for target in targets if target.kind == "shape"}

    # ------------------------------------------------------------------ the solver's and the walkers' forms
    def hold(self) -> Hold:
        """The solver's :class:`Hold` (numpy float64 arrays (k,)) over the unconstrained vector."""
        coordinates = self.model.unconstrained
        k = coordinates.size(self.n_channels)
        free, bounded, value, low, high = self.free.astype(float), np.zeros(k), np.zeros(k), np.zeros(k), np.zeros(k)
        value_vector = coordinates.from_params(self._placed(self.fixed))
        for name in self.fixed:
            value[self._entries(name)] = value_vector[self._entries(name)]
        low_vector, high_vector = self._bound_vectors(coordinates)
        for name in self.bounds:
            index = self._entries(name)
            bounded[index], low[index], high[index] = 1.0, low_vector[index], high_vector[index]
        return Hold(free, bounded, value, low, high)

    def sampling_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (k,) of the sampling vector (the walkers' coordinates): the user's bounds, ±inf
        where none is given (the domain's prior still applies)."""
        k = self.model.sampling.size(self.n_channels)
        low, high = np.full(k, -np.inf), np.full(k, np.inf)
        low_vector, high_vector = self._bound_vectors(self.model.sampling)
        for name in self.bounds:
            index = self._entries(name)
            low[index], high[index] = low_vector[index], high_vector[index]
        return low, high

    def _bound_vectors(self, coordinates) -> tuple[np.ndarray, np.ndarray]:
        """The vectors (in ``coordinates``) of every bounded parameter at its low ends, and at its high ends."""
        ends = ({name: bound[end] for name, bound in self.bounds.items()} for end in (0, 1))
        low, high = (np.asarray(coordinates.from_params(self._placed(values))) for values in ends)
        return low, high

    def _placed(self, values: Mapping[str, Any]) -> Params:
        """Parameters (numpy) with ``values`` at their names, any valid value elsewhere."""
        model, c = self.model, self.n_channels
        diffuse = np.full(c, _ANY_ALBEDO)
        specular = np.full((model.n_lobes, c), _ANY_ALBEDO)
        given: list[dict[str, Any]] = [{} for _ in range(model.n_lobes)]  # numbers, or (C,) per channel
        for name, value in values.items():
            target = _target(model, name)
            if target.kind == "diffuse":
                diffuse = np.broadcast_to(np.asarray(value, float), (c,)).copy()
            elif target.kind == "specular":
                specular[target.lobe] = np.broadcast_to(np.asarray(value, float), (c,))
            elif target.parameter in _per_channel(model):
                given[target.lobe][target.parameter] = np.broadcast_to(np.asarray(value, float), (c,)).copy()
            else:
                given[target.lobe][target.parameter] = float(value)
        shapes = [lobe_family(model).shape_holding(one, _prefix(model, k)) for k, one in enumerate(given)]
        names = model.lobe.names if model.lobe else ()
        one = lambda name, value: np.broadcast_to(value, (c,)) if name in _per_channel(model) else value
        shape = {name: np.array([one(name, lobe[name]) for lobe in shapes]) for name in names}
        return Params(diffuse, specular, shape)

    # ------------------------------------------------------------------ a result
    def with_fixed(self, params: Params) -> Params:
        """``params`` with every fixed parameter at exactly its value (the solver holds ``θ``, whose map back may
        differ in the last digit, and holds an albedo of 0 at ``exp(ln 10⁻¹²)``)."""
        placed = self._placed(self.fixed)
        diffuse, specular = np.array(params.diffuse, float), np.array(params.specular, float)
        shape = {name: np.array(value, float) for name, value in params.shape.items()}
        for name in self.fixed:
            target = _target(self.model, name)
            if target.kind == "diffuse":
                diffuse = np.asarray(placed.diffuse)
            elif target.kind == "specular":
                specular[target.lobe] = placed.specular[target.lobe]
            else:
                index = _coordinate(self.model, target)
                family = lobe_family(self.model)
                for tied in family.names:
                    if family.coordinate_index(tied) == index:
                        shape[tied][target.lobe] = placed.shape[tied][target.lobe]
        return Params(diffuse, specular, shape)

    def within_bounds(self, params: Params) -> Params:
        """``params`` with every bounded parameter clipped into its bound: the solver's scaled logit reaches an end to
        within rounding, and ``m = 0.10000000000000002`` for a bound ``[0.01, 0.1]`` is outside what the user
        allowed."""
        diffuse, specular = np.array(params.diffuse, float), np.array(params.specular, float)
        shape = {name: np.array(value, float) for name, value in params.shape.items()}
        for name, (low, high) in self.bounds.items():
            target = _target(self.model, name)
            if target.kind == "diffuse":
                diffuse = np.clip(diffuse, low, high)
            elif target.kind == "specular":
                specular[target.lobe] = np.clip(specular[target.lobe], low, high)
            else:
                shape[target.parameter][target.lobe] = np.clip(shape[target.parameter][target.lobe], low, high)
        return Params(diffuse, specular, shape)

    def bound_warnings(self, theta) -> list[str]:
        """One line per bounded parameter whose solve ``theta`` (unconstrained) ended on a bound."""
        side = on_bound(theta, self.hold())
        lines = []
        for name, (low, high) in self.bounds.items():
            index = self._entries(name)
            for which, value, ended in (("lower", low, -1), ("upper", high, 1)):
                if np.any(side[index] == ended):
                    lines.append(
                        f"{name} ended on its {which} bound {value:g} (bounds {low:g} to {high:g}): the data pull it"
                        " beyond; widen the bound if that is physical, or the model may not suit these samples"
                    )
        return lines


def constraints_for(
    model: Model,
    n_channels: int,
    fixed: Mapping[str, Any] | None = None,
    bounds: Mapping[str, Any] | None = None,
    *,
    defaults: bool = True,
) -> Constraints | None:
    """The :class:`Constraints` of ``fixed`` and ``bounds`` for ``model`` with ``n_channels`` channels, every name
    and value checked; None when neither holds anything (the fit then runs as it always has).

    ``defaults``: the model's default holds (``LobeModel.held``) apply but where ``fixed`` frees one (a value None)
    or fixes or bounds it; False for what a result file recorded (``fit.fixed``: every hold the fit had)."""
    fixed, bounds = parameter_mapping(fixed, "fixed"), parameter_mapping(bounds, "bounds")
    if defaults:
        fixed = _with_default_holds(model, fixed, bounds)
    if not fixed and not bounds:
        return None
    if not isinstance(model, LobeModel):  # the data-driven kind: every coefficient under its prior
        raise BrdfInputError(
            Argument("fixed" if fixed else "bounds"),
            f": model {model.name} fits every coefficient, under its prior (ridge); it takes no fixed or bounded"
            " parameters",
        )
    checked_fixed = {name: _fixed_value(model, name, value, n_channels) for name, value in fixed.items()}
    checked_bounds = {name: _bound(model, name, value) for name, value in bounds.items()}
    _check_overlaps(model, checked_fixed, checked_bounds)
    constraints = Constraints(model, n_channels, checked_fixed, checked_bounds)
    # Every value placed in a whole shape: a Lafortune direction's cz alone, or a cxy beyond 1/√2, is refused here.
    lows, highs = ({name: bound[end] for name, bound in checked_bounds.items()} for end in (0, 1))
    for argument, values in (("fixed", checked_fixed), ("bounds", lows), ("bounds", highs)):
        try:
            constraints._placed(values)
        except BrdfInputError as error:
            raise _error(argument, str(error)) from None
    hold = constraints.hold()
    if np.any((hold.bounded > 0) & ~(hold.high - hold.low > 1e-9 * np.maximum(1.0, np.abs(hold.high)))):
        raise _error("bounds", "a range too narrow to search in (its ends are one value to the fit); fix the parameter")
    # A fixed direction is written as held: cxy and cz both given are put exactly onto 2·cxy² + cz² = 1.
    placed = constraints._placed(checked_fixed)
    for name in checked_fixed:
        target = _target(model, name)
        if target.kind == "shape" and target.parameter not in _per_channel(model):
            checked_fixed[name] = float(placed.shape[target.parameter][target.lobe])
    if constraints.n_free == 0:
        raise BrdfInputError(Argument("fixed"), f": every parameter of {model.name} is fixed; nothing is left to fit")
    return constraints


def _with_default_holds(model: Model, fixed: dict[str, Any], bounds: dict[str, Any]) -> dict[str, Any]:
    """``fixed`` with ``model``'s default holds (``LobeModel.held``) added, but those the user names: a None frees
    one (and is nothing for a parameter that is free anyway: ``compare`` passes one holding to every model), a value
    fixes it there, a bound bounds it instead."""
    held = dict(getattr(model, "held", ()))
    for name, value in fixed.items():
        if value is None:  # freed: a parameter of the model's (free already unless held by default)
            _target(model, name, "fixed")
    defaults = {name: value for name, value in held.items() if name not in fixed and name not in bounds}
    return defaults | {name: value for name, value in fixed.items() if value is not None}


def _per_channel(model: Model) -> tuple[str, ...]:
    """The names of ``model``'s shape parameters with one value per channel (``Lobe.channel_names``)."""
    return model.lobe.channel_names if isinstance(model, LobeModel) and model.lobe is not None else ()


def parameter_names(model: Model) -> list[str]:
    """The names :func:`constraints_for` takes for ``model``: ``kd, ks, m, f0``; ``rho_d, lobes[0].rho_s, …``."""
    if not isinstance(model, LobeModel):  # the data-driven kind: every coefficient under its prior
        return []
    if model.whole:  # a renderer's own model: its lobe's shape alone
        return list(lobe_family(model).names)
    names = [model.diffuse_name]
    for k in range(model.n_lobes):
        prefix = _prefix(model, k)
        names += [prefix + model.specular_name] + [prefix + name for name in lobe_family(model).names]
    return names


def _prefix(model: LobeModel, k: int) -> str:
    return f"lobes[{k}]." if model.lobes_as_list else ""


def _target(model: Model, name: str, argument: str = "fixed") -> Target:
    """The parameter ``name`` names in ``model``, or a one-line error listing the names it has."""
    known = parameter_names(model)  # none but a lobe model's
    if isinstance(model, LobeModel) and isinstance(name, str) and name in known:
        if model.lobes_as_list and (match := _LOBE_NAME.match(name)):
            lobe, parameter = int(match.group(1)), match.group(2)
        else:
            lobe, parameter = 0, name
        if parameter == model.diffuse_name and name == model.diffuse_name:
            return Target(name, "diffuse", 0, parameter, model.diffuse.albedo_domain)
        if parameter == model.specular_name:
            return Target(name, "specular", lobe, parameter, lobe_family(model).albedo_domain)
        return Target(name, "shape", lobe, parameter, dict(lobe_family(model).parameters)[parameter])
    raise _error(argument, f"{model.name} has no parameter {name!r}; its parameters are {', '.join(known)}")


def _coordinate(model: LobeModel, target: Target) -> int:
    return lobe_family(model).coordinate_index(target.parameter)


def _entries(model: LobeModel, target: Target, n_channels: int) -> list[int]:
    """The indices of ``target``'s entries in the flat vectors (``coordinates.py``: diffuse, specular, shapes)."""
    c, k, a = n_channels, model.n_lobes, albedo_size(model, n_channels)
    if target.kind == "diffuse":
        return list(range(c))
    if target.kind == "specular":
        return list(range(c + target.lobe * c, c + (target.lobe + 1) * c))
    s, per_channel = len(model.unconstrained.shared.names), model.unconstrained.per_channel
    if per_channel is not None and target.parameter in _per_channel(model):  # after every lobe's shared ones
        names = per_channel.names  # lobe, parameter, channel
        first = a + k * s + (target.lobe * len(names) + names.index(target.parameter)) * c
        return list(range(first, first + c))
    return [a + target.lobe * s + _coordinate(model, target)]


def _number(value: Any, argument: str, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise _error(argument, f"{name} takes numbers, got {value!r}")
    return float(value)


def _error(argument: str, text: str) -> BrdfInputError:
    """``fixed: eta = 0.5 is outside …`` (``--fix: …`` on the command line)."""
    return BrdfInputError(Argument(argument), f": {text}")


def _fixed_value(model: LobeModel, name: str, value: Any, n_channels: int):
    """The fixed value checked: a list of ``n_channels`` values of an albedo or a per-channel shape parameter, or one
    number, inside the parameter's domain."""
    target = _target(model, name, "fixed")
    if target.kind == "shape" and target.parameter not in _per_channel(model):
        number = _number(value, "fixed", name)
        if not target.domain.contains(number):
            raise _error("fixed", f"{name} = {number:g} is outside its domain {target.domain.text}")
        return number
    values = value if isinstance(value, list | tuple | np.ndarray) else [value]
    numbers = [_number(one, "fixed", name) for one in values]
    if len(numbers) == 1:
        numbers = numbers * n_channels
    if len(numbers) != n_channels:
        raise _error(
            "fixed",
            f"{name} has {len(numbers)} values but the samples have {n_channels} channel(s); give one value,"
            " or one per channel",
        )
    if not target.domain.contains(numbers):
        raise _error("fixed", f"{name} = {value!r} is outside its domain {target.domain.text}")
    return numbers


def _bound(model: LobeModel, name: str, value: Any) -> list[float]:
    """The bound checked: two finite numbers ``lo < hi`` inside the parameter's domain."""
    target = _target(model, name, "bounds")
    if not isinstance(value, list | tuple | np.ndarray) or len(value) != 2:
        raise _error("bounds", f"{name} takes two numbers, low and high, got {value!r}")
    low, high = (_number(one, "bounds", name) for one in value)
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise _error("bounds", f"{name} needs finite bounds with low < high, got {low:g} to {high:g}")
    if not target.domain.contains([low, high]):
        raise _error("bounds", f"{name} from {low:g} to {high:g} reaches outside its domain {target.domain.text}")
    return [low, high]


def _check_overlaps(model: LobeModel, fixed: dict[str, Any], bounds: dict[str, Any]) -> None:
    """A parameter is fixed or bounded, not both; a Lafortune direction is held by one of ``cxy`` and ``cz``."""
    held: dict[tuple[str, int, int], tuple[str, str]] = {}
    for how, name in [*(("fixed", name) for name in fixed), *(("bounds", name) for name in bounds)]:
        target = _target(model, name)
        key = (target.kind, target.lobe, _coordinate(model, target) if target.kind == "shape" else 0)
        if key in held and not (how == "fixed" and held[key][0] == "fixed"):
            other = held[key][1]
            both = f"{name} is" if other == name else f"{other} and {name} (one direction) are"
            raise BrdfInputError(Argument("bounds"), f": {both} also fixed; fix a parameter or bound it, not both")
        held[key] = (how, name)


def check_names(model: Model, fixed: Mapping[str, Any] | None = None, bounds: Mapping[str, Any] | None = None) -> None:
    """Check ``fixed`` and ``bounds`` against ``model`` before the samples are known (the command line's check before
    any file is read): names, domains, ranges; an albedo's list is taken to have one value per channel."""
    lengths = [len(value) for value in (fixed or {}).values() if isinstance(value, list | tuple)]
    constraints_for(model, max(lengths, default=1), fixed, bounds)
