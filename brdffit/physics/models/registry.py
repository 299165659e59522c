"""The reflectance models, one module per lobe family, and the registry that names them.

``MODELS[name](**options)`` builds a :class:`~brdffit.physics.models.model.Model`; :func:`get_model`
does the same with one-line errors for unknown names and options. The parts every model shares:
``model.py`` (the model: diffuse plus lobes), ``lobe.py`` (a lobe family and its shape's coordinates),
``params.py``, ``dictionary.py`` and ``coordinates.py`` (the forms its parameters take), ``grids.py``
(the shapes the fit starts from).
"""

import inspect
from functools import cache
from typing import Any

from ...datadriven.model import pca
from ...errors import Argument, BrdfInputError
from .cook_torrance import cook_torrance
from .lafortune import lafortune
from .lambert import lambert
from .model import Model
from .phong import blinn_phong, phong
from .ward import ward, ward_aniso, ward_duer

#: The models by name: each builds a :class:`Model` from its options (``fresnel``, ``lobes``).
MODELS = {
    "lambert": lambert,
    "ward": ward,
    "ward-aniso": ward_aniso,
    "ward-duer": ward_duer,
    "cook-torrance": cook_torrance,
    "blinn-phong": blinn_phong,
    "phong": phong,
    "lafortune": lafortune,
    "pca": pca,
}

#: Options a result records that a user never gives: a basis file's digest, the ridge's scale a fit measured.
RECORDED_OPTIONS = frozenset({"basis_sha256", "ridge_scale"})
#: Options that name a file: a spec (a label) shows the file's name, not its whole path; a default file name, neither.
FILE_OPTIONS = frozenset({"basis"})


@cache
def model_option_names(name: str) -> tuple[str, ...]:
    """The options (``fresnel``, ``lobes``) that model ``name`` takes (asked once per fit: kept)."""
    return tuple(inspect.signature(MODELS[name]).parameters)


def model_option_defaults(name: str) -> dict[str, Any]:
    """Each option of model ``name`` with its default (``{"fresnel": "schlick", …}``)."""
    return {key: parameter.default for key, parameter in inspect.signature(MODELS[name]).parameters.items()}


def chosen_options(model: Model) -> dict[str, Any]:
    """The options of ``model`` that differ from their defaults: what names a fit apart from its model's default
    (``{"fresnel": "conductor"}``; ``{}`` for Cook-Torrance with Beckmann, V-groove and Schlick). A file an option
    names (pca's basis) and what a result only records (its digest, the ridge's scale) name nothing apart."""
    defaults = model_option_defaults(model.name)
    unnamed = RECORDED_OPTIONS | FILE_OPTIONS
    return {key: value for key, value in model.options if defaults.get(key) != value and key not in unnamed}


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
            takes = ["it takes no options"] if not accepted else ["it takes ", *_listed(accepted)]
            raise BrdfInputError(Argument(key), f" does not apply to model {model}; ", *takes)
    return MODELS[model](**options)


def model_for(model: "str | Model", params: Any, **options: Any) -> Model:
    """:func:`get_model`, with a Lafortune model's number of lobes taken from ``params`` (a parameter dictionary
    with a ``lobes`` list) when ``lobes`` is not given."""
    if (
        isinstance(model, str)
        and model in MODELS
        and options.get("lobes") is None
        and "lobes" in model_option_names(model)
        and isinstance(params, dict)
        and isinstance(params.get("lobes"), list | tuple)
        and params["lobes"]
    ):
        options = {**options, "lobes": len(params["lobes"])}
    return get_model(model, **options)


def _listed(names: tuple[str, ...]) -> list:
    """``a, b`` as message parts, each an :class:`Argument`."""
    parts: list = []
    for index, name in enumerate(names):
        parts += [", "] if index else []
        parts.append(Argument(name))
    return parts
