"""Model specs: a model and its options in one word, ``NAME[:key=value,…]``, as ``brdffit compare`` takes them.

``ward``, ``cook-torrance:fresnel=conductor``, ``lafortune:lobes=2``. A value without its key is the value of
the one option that accepts it (``lafortune:2``, ``cook-torrance:conductor``). The canonical spec of a model
(:func:`spec_of`) names every option with its key, in the model's order.
"""

from typing import Any

from ...errors import BrdfInputError
from . import MODELS, Model, get_model, model_option_names


def spec_of(name: str, options: dict[str, Any]) -> str:
    """The canonical spec of model ``name`` with ``options``: ``lafortune:lobes=2``, or ``ward``."""
    written = ",".join(f"{key}={value}" for key, value in options.items())
    return f"{name}:{written}" if written else name


def model_of_spec(spec: str) -> Model:
    """The model a spec names, with one-line errors that quote the spec."""
    name, _, written = spec.strip().partition(":")
    if name not in MODELS:
        raise BrdfInputError(f"model spec {spec!r}: {name!r} is not a model; choose one of: {', '.join(MODELS)}")
    options: dict[str, Any] = {}
    for item in filter(None, (part.strip() for part in written.split(","))):
        key, equals, value = item.partition("=")
        if equals:
            options[key.strip()] = _value(value.strip())
        else:
            key = _option_accepting(spec, name, _value(key))
            options[key] = _value(item)
    try:
        return get_model(name, **options)
    except BrdfInputError as error:
        raise BrdfInputError(f"model spec {spec!r}: {error}") from None


def _value(text: str) -> Any:
    """A spec's value: a whole number as an int (``lobes=2``), anything else as the text."""
    return int(text) if text.isdigit() else text


def _option_accepting(spec: str, name: str, value: Any) -> str:
    """The one option of model ``name`` that accepts ``value``, for a value written without its key."""
    accepting = []
    for option in model_option_names(name):
        try:
            get_model(name, **{option: value})
        except BrdfInputError:
            continue
        accepting.append(option)
    if len(accepting) != 1:
        takes = ", ".join(model_option_names(name)) or "no options"
        why = "no option of" if not accepting else "more than one option of"
        raise BrdfInputError(f"model spec {spec!r}: {why} {name} takes {value!r}; write key=value ({takes})")
    return accepting[0]


def split_specs(text: str) -> list[str]:
    """Specs written as one comma-separated list (``ward,cook-torrance:fresnel=conductor,lafortune:lobes=2``), split
    between specs, not inside one: a piece without ``:`` that is not a model's name (``key=value``, or a bare
    value) continues the spec before it."""
    specs: list[str] = []
    for piece in filter(None, (part.strip() for part in text.split(","))):
        if specs and ":" not in piece and piece not in MODELS:
            specs[-1] += "," + piece
        else:
            specs.append(piece)
    return specs
