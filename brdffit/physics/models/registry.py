"""The registry of models: ``MODELS``, each name's :class:`~brdffit.physics.models.model.ModelEntry`, and
:func:`get_model`, which builds a model from its name and options with one-line errors.

``MODELS[name](**options)`` builds a model; the entry also says what ``brdffit compare`` tries, what ``brdffit
models`` lists and how a fit reaches a renderer. :func:`register_model` adds a model of one's own
(``docs/adding-a-model.md``).
"""

from functools import cache
from typing import Any

from ...datadriven.model import PCA
from ...errors import Argument, BrdfInputError, not_a_choice
from ..renderers.gltf_model import GLTF
from ..renderers.principled_model import PRINCIPLED
from ..renderers.roughplastic_model import ROUGHPLASTIC
from .cook_torrance import COOK_TORRANCE
from .lafortune import LAFORTUNE
from .lambert import LAMBERT
from .model import Model, ModelEntry
from .phong import BLINN_PHONG, PHONG
from .ward import WARD, WARD_ANISO, WARD_DUER

#: The models by name, in the order ``brdffit models`` lists and ``brdffit compare`` fits them.
MODELS: dict[str, ModelEntry] = {
    "lambert": LAMBERT,
    "ward": WARD,
    "ward-aniso": WARD_ANISO,
    "ward-duer": WARD_DUER,
    "cook-torrance": COOK_TORRANCE,
    "blinn-phong": BLINN_PHONG,
    "phong": PHONG,
    "lafortune": LAFORTUNE,
    "gltf": GLTF,
    "principled": PRINCIPLED,
    "roughplastic": ROUGHPLASTIC,
    "pca": PCA,
}


def register_model(name: str, entry: ModelEntry) -> None:
    """Add a model to the registry under ``name`` (``--model NAME``, ``get_model(NAME)``, ``compare``'s specs):
    ``entry.build(**options)`` must build a :class:`Model` whose ``name`` is ``name``. A name is registered once;
    register before fitting (the registry is read, not locked, by fits running on other threads)."""
    if not isinstance(name, str) or not name or any(character in name for character in ":,= "):
        raise BrdfInputError(Argument.given("name", name), " must be a word without ':', ',', '=' or spaces")
    if name in MODELS:
        raise BrdfInputError(f"a model {name!r} is registered already; choose another name")
    if not isinstance(entry, ModelEntry):
        raise BrdfInputError(Argument("entry"), f" must be a ModelEntry, got {type(entry).__name__}")
    MODELS[name] = entry


@cache
def model_option_names(name: str) -> tuple[str, ...]:
    """The options (``fresnel``, ``lobes``) that model ``name`` takes (asked once per fit: kept)."""
    return tuple(MODELS[name].option_defaults)


def model_option_defaults(name: str) -> dict[str, Any]:
    """Each option of model ``name`` with its default (``{"fresnel": "schlick", …}``)."""
    return MODELS[name].option_defaults


def recorded_options() -> frozenset[str]:
    """Options a result records that a user never gives (a basis file's digest, the ridge's scale a fit measured)."""
    return frozenset().union(*(entry.recorded for entry in MODELS.values()))


def file_options() -> frozenset[str]:
    """Options that name a file: a spec (a label) shows the file's name, not its whole path."""
    return frozenset().union(*(entry.files for entry in MODELS.values()))


def chosen_options(model: Model) -> dict[str, Any]:
    """The options of ``model`` that differ from their defaults: what names a fit apart from its model's default
    (``{"fresnel": "conductor"}``; ``{}`` for Cook-Torrance with Beckmann, V-groove and Schlick). A file an option
    names (pca's basis) and what a result only records (its digest, the ridge's scale) name nothing apart."""
    defaults = model_option_defaults(model.name) if model.name in MODELS else {}
    unnamed = recorded_options() | file_options()
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
        raise not_a_choice("model", model, MODELS, "is not a model")
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
