"""A model's parameters as the result file writes them: a JSON object of names, numbers and lists.

``{"rho_d": [0.1, 0.2, 0.3], "rho_s": [...], "alpha": 0.12}``: per-channel albedos as lists in channel
order (a single number is one channel), lobe shapes as numbers, but a shape parameter with one value per channel
(``Lobe.channel_names``: a conductor's ``eta``, ``k``) as a list in channel order, like an albedo (read back, one
number stands for every channel: result files written before it took a list still load); models whose lobes come
as a list (Lafortune) write ``{"rho_d": [...], "lobes": [{"rho_s": [...], "cxy": -0.6, "cz": 0.55, "n": 12.0}]}``; a
whole-lobe model (a renderer's own) writes its lobe's shape alone: ``{"base_color": [...], "metallic": 0.0, …}``.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import BrdfInputError
from ..domains import ALBEDO
from .params import Layout, Params, lobe_family, whole_albedos


@dataclass(frozen=True)
class ParameterDictionary:
    """``model``'s parameters as a dictionary: checked on the way in, plain floats and lists on the way out."""

    model: Layout

    @property
    def names(self) -> tuple[str, ...]:
        """The dictionary's top-level names, in the order of the result file."""
        model = self.model
        if model.whole:
            return lobe_family(model).names
        if not model.n_lobes:
            return (model.diffuse_name,)
        if model.lobes_as_list:
            return (model.diffuse_name, "lobes")
        return (model.diffuse_name, model.specular_name, *lobe_family(model).names)

    def to_params(self, values: Mapping[str, Any]) -> Params:
        """Check a parameter dictionary and convert it to :class:`Params` (numpy arrays).

        Every per-channel entry must have the same length; errors name the model and the parameter.
        """
        model = self.model
        if not isinstance(values, Mapping):
            raise BrdfInputError(f"{model.name}: parameters must be a JSON object, got {type(values).__name__}")
        _check_keys(values, self.names, f"{model.name}: ")
        if model.whole:
            return _whole_params(model, values)
        diffuse = _albedo(values[model.diffuse_name], f"{model.name}: {model.diffuse_name}")
        if not model.n_lobes:
            return Params(diffuse, np.zeros((0, diffuse.size)), {})
        family = lobe_family(model)
        if model.lobes_as_list:
            lobes = values["lobes"]
            if not isinstance(lobes, list | tuple) or len(lobes) != model.n_lobes:
                got = len(lobes) if isinstance(lobes, list | tuple) else type(lobes).__name__
                raise BrdfInputError(f"{model.name}: 'lobes' must be a list of {model.n_lobes} lobe(s), got {got}")
            names = (model.specular_name, *family.names)
            for index, lobe in enumerate(lobes):
                if not isinstance(lobe, Mapping):
                    raise BrdfInputError(f"{model.name}: lobes[{index}] must be a JSON object")
                _check_keys(lobe, names, f"{model.name}: lobes[{index}]: ")
            prefixes = [f"{model.name}: lobes[{index}]." for index in range(model.n_lobes)]
        else:
            lobes, prefixes = [values], [f"{model.name}: "]
        specular = np.stack(
            [
                _albedo(lobe[model.specular_name], prefix + model.specular_name)
                for lobe, prefix in zip(lobes, prefixes, strict=True)
            ]
        )
        if specular.shape[1] != diffuse.size:
            raise BrdfInputError(
                f"{model.name}: {model.specular_name} has {specular.shape[1]} channel(s)"
                f" but {model.diffuse_name} has {diffuse.size}"
            )
        shapes = [
            family.checked_shape(_shape_numbers(lobe, family, diffuse.size, prefix), prefix)
            for lobe, prefix in zip(lobes, prefixes, strict=True)
        ]
        shape = {name: np.array([one[name] for one in shapes]) for name in family.names}
        return Params(diffuse, specular, shape)

    def from_params(self, params: Params) -> dict[str, Any]:
        """The dictionary (plain Python floats and lists) of ``params``."""
        model = self.model
        if model.whole:
            return _shape_written(model, params, 0)
        result: dict[str, Any] = {model.diffuse_name: _floats(params.diffuse)}
        if not model.n_lobes:
            return result
        lobes = [
            {model.specular_name: _floats(params.specular[k])} | _shape_written(model, params, k)
            for k in range(model.n_lobes)
        ]
        if model.lobes_as_list:
            result["lobes"] = lobes
        else:
            result.update(lobes[0])
        return result


def _shape_written(model: Layout, params: Params, k: int) -> dict[str, Any]:
    """Lobe ``k``'s shape as the file writes it: numbers, and lists for the lobe's per-channel parameters."""
    family = lobe_family(model)
    return {
        name: _floats(params.shape[name][k]) if name in family.channel_names else float(params.shape[name][k])
        for name in family.names
    }


def _whole_params(model: Layout, values: Mapping[str, Any]) -> Params:
    """A whole-lobe model's parameters: its lobe's shape, with as many channels as its per-channel parameters' longest
    list (one number stands for every channel)."""
    prefix, family = f"{model.name}: ", lobe_family(model)
    lengths = [len(values[name]) for name in family.channel_names if isinstance(values[name], list | tuple)]
    n_channels = max(lengths, default=1)
    shape = family.checked_shape(_shape_numbers(values, family, n_channels, prefix), prefix)
    diffuse, specular = whole_albedos(n_channels)
    return Params(diffuse, specular, {name: np.array([value]) for name, value in shape.items()})


def _check_keys(values: Mapping[str, Any], expected: tuple[str, ...], prefix: str) -> None:
    for key in values:
        if key not in expected:
            raise BrdfInputError(f"{prefix}unknown parameter {key!r}; expected {', '.join(expected)}")
    for key in expected:
        if key not in values:
            raise BrdfInputError(f"{prefix}missing parameter {key!r}; expected {', '.join(expected)}")


def _albedo(value: Any, where: str) -> np.ndarray:
    """A per-channel albedo as a float array (C,); a single number is one channel."""
    try:
        array = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        raise BrdfInputError(f"{where} must be a number or a list of numbers, got {value!r}") from None
    if array.ndim != 1 or array.size == 0:
        raise BrdfInputError(f"{where} must be a number or a flat list of numbers, got {value!r}")
    if not ALBEDO.contains(array):
        raise BrdfInputError(f"{where} = {value!r} is outside its domain {ALBEDO.text}")
    return array


def _shape_numbers(values: Mapping[str, Any], lobe, n_channels: int, where: str) -> dict[str, Any]:
    """The lobe's shape parameters: numbers, and lists of ``n_channels`` for its ``channel_names`` (one number
    broadcast to every channel)."""
    numbers: dict[str, Any] = {}
    for name in lobe.names:
        value = values[name]
        if name in lobe.channel_names:
            items = value if isinstance(value, list | tuple) else [value]
            if not all(_is_number(item) for item in items) or len(items) not in (1, n_channels):
                raise BrdfInputError(
                    f"{where}{name} takes one number per channel ({n_channels}) or one for all, got {value!r}"
                )
            numbers[name] = np.broadcast_to(np.asarray(items, float), (n_channels,)).copy()
            continue
        if not _is_number(value):
            raise BrdfInputError(f"{where}{name} must be a single number, got {value!r}")
        numbers[name] = float(value)
    return numbers


def _is_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float | np.floating | np.integer)


def _floats(array) -> list[float]:
    return [float(x) for x in np.asarray(array).ravel()]
