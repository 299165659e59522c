"""The reflectance models and the registry that maps ``--model`` names to them.

``MODELS[name](**options)`` builds a :class:`Model`; :func:`get_model` does the
same with one-line errors for unknown names and options.
"""

import inspect
from typing import Any

from ...errors import BrdfInputError
from .base import Lobe as Lobe
from .base import Model as Model
from .base import Params as Params
from .cook_torrance import cook_torrance
from .lafortune import lafortune
from .lambert import lambert
from .phong import blinn_phong, phong
from .ward import ward, ward_aniso, ward_duer

MODELS = {
    "lambert": lambert,
    "ward": ward,
    "ward-aniso": ward_aniso,
    "ward-duer": ward_duer,
    "cook-torrance": cook_torrance,
    "blinn-phong": blinn_phong,
    "phong": phong,
    "lafortune": lafortune,
}


def model_option_names(name: str) -> tuple[str, ...]:
    """The options (``fresnel``, ``lobes``) that model ``name`` takes."""
    return tuple(inspect.signature(MODELS[name]).parameters)


def get_model(model: "str | Model", **options: Any) -> Model:
    """The model called ``model`` built with ``options``; options given as ``None`` take their default.

    A :class:`Model` is returned as it is (then no options may be given).
    """
    options = {key: value for key, value in options.items() if value is not None}
    if isinstance(model, Model):
        if options:
            raise BrdfInputError(f"options {', '.join(options)} cannot be applied to an already built model")
        return model
    if model not in MODELS:
        raise BrdfInputError(f"{model!r} is not a model; choose one of: {', '.join(MODELS)}")
    accepted = model_option_names(model)
    for key in options:
        if key not in accepted:
            takes = f"it takes --{', --'.join(accepted)}" if accepted else "it takes no options"
            raise BrdfInputError(f"--{key} does not apply to model {model}; {takes}")
    return MODELS[model](**options)
