"""Model specs: a model and its options in one word, ``NAME[:key=value,…]``, as ``brdffit compare`` takes them.

``ward``, ``cook-torrance:fresnel=conductor``, ``lafortune:lobes=2``. A value without its key is the value of
the one option that accepts it (``lafortune:2``, ``cook-torrance:conductor``). The canonical spec of a model
(:func:`spec_of`) names, with its key, every option that differs from its default, in the model's order:
``cook-torrance`` is Beckmann, V-groove and Schlick; ``cook-torrance:distribution=ggx,shadowing=smith``;
``cook-torrance:distribution=ggx,shadowing=smith,anisotropic=true`` (a yes or no is ``true`` or ``false``).
"""

import os
from typing import Any

from ...errors import BrdfInputError
from .model import Model
from .registry import MODELS, file_options, get_model, model_option_defaults, model_option_names, recorded_options


def spec_of(name: str, options: dict[str, Any]) -> str:
    """The canonical spec of model ``name`` with ``options``: ``lafortune:lobes=2``, ``cook-torrance``."""
    defaults = model_option_defaults(name) if name in MODELS else {}
    written = ",".join(
        f"{key}={shown_value(key, value)}"
        for key, value in options.items()
        if defaults.get(key) != value and key not in recorded_options()
    )
    return f"{name}:{written}" if written else name


def shown_value(key: str, value: Any) -> Any:
    """An option's value in a spec: a file (the data-driven model's basis) by its name, as a label shows it; a yes or
    no as ``true`` or ``false``."""
    if isinstance(value, bool):
        return str(value).lower()
    return os.path.basename(str(value)) if key in file_options() else value


def model_of_spec(spec: str) -> Model:
    """The model a spec names, with one-line errors that quote the spec."""
    name, _, written = spec.strip().partition(":")
    if name not in MODELS:
        raise BrdfInputError(f"model spec {spec!r}: {name!r} is not a model; choose one of: {', '.join(MODELS)}")
    options: dict[str, Any] = {}
    try:
        for item in filter(None, (part.strip() for part in written.split(","))):
            key, equals, value = item.partition("=")
            if equals:
                options[key.strip()] = _value(value.strip())
            else:
                options[_option_accepting(name, _value(key))] = _value(item)
        return get_model(name, **options)
    except BrdfInputError as error:  # spelled key=value, as specs are written, on the command line too
        raise BrdfInputError(f"model spec {spec!r}: {error}") from None


def _value(text: str) -> Any:
    """A spec's value: a whole number as an int (``lobes=2``), anything else as the text."""
    return int(text) if text.isdigit() else text


def _option_accepting(name: str, value: Any) -> str:
    """The one option of model ``name`` that accepts ``value``, for a value written without its key."""
    accepting = []
    for option in model_option_names(name):
        try:
            get_model(name, **{option: value})
        except BrdfInputError:
            continue
        accepting.append(option)
    options = model_option_names(name)
    if not accepting and len(options) == 1:
        get_model(name, **{options[0]: value})  # the one option's own error: lobes=0 is not allowed; …
    if len(accepting) != 1:
        takes = ", ".join(options) or "no options"
        why = "no option of" if not accepting else "more than one option of"
        raise BrdfInputError(f"{why} {name} takes {value!r}; write key=value ({takes})")
    return accepting[0]


def split_specs(text: str, completed=None) -> list[str]:
    """Specs written as one comma-separated list (``ward,cook-torrance:fresnel=conductor,lafortune:lobes=2``), split
    between specs, not inside one: a ``key=value`` piece (no ``:``) continues the spec before it, if that spec has
    options; anything else starts a spec (so a misspelt model is named as it was written). ``completed`` (a
    function of a spec) adds options given elsewhere. A spec given twice is an error."""
    specs: list[str] = []
    for piece in filter(None, (part.strip() for part in text.split(","))):
        if specs and ":" in specs[-1] and ":" not in piece and "=" in piece:
            specs[-1] += "," + piece
        else:
            specs.append(piece)
    if completed is not None:  # options the command line gives apart (``--basis`` for pca)
        specs = [completed(spec) for spec in specs]
    canonical = [spec_of(model.name, model.model_options) for model in map(model_of_spec, specs)]
    repeated = next((spec for spec in canonical if canonical.count(spec) > 1), None)
    if repeated is not None:
        raise BrdfInputError(f"model spec {repeated!r} is given twice; give each model once")
    return specs
