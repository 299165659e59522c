"""``brdffit models``: each model with its formula, options, parameters and their domains."""

import argparse
import json

from . import EXIT_OK
from .arguments import flag
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the models as one JSON list (name, summary, options, parameters) instead of lines",
    )


def files(args: argparse.Namespace) -> Files:
    """``models`` reads and writes no file."""
    return Files()


def run(args: argparse.Namespace) -> int:
    from ..fitting.single.result import json_text
    from ..physics.models.registry import MODELS

    listings = [listing(name, entry) for name, entry in MODELS.items()]
    if args.json:
        print(json_text(listings))
        return EXIT_OK
    for one in listings:
        print(f"{one['name']}\n  {one['summary']}")
        if one["options"]:
            print(f"  options: {', '.join(flag(option) for option in one['options'])}")
        for line in one["details"]:
            print(f"  {line}")
        for option, values in one["choices"].items():
            if option not in one["parameters_by_option"]:
                listed = ", ".join(f"{value} ({what})" for value, what in values.items())
                print(f"  {flag(option)}: {listed}")
        for option, by_value in one["parameters_by_option"].items():
            for value, parameters in by_value.items():
                lines = "; ".join(_parameter_text(parameter) for parameter in parameters)
                print(f"  {flag(option)} {value}: {lines} ({one['choices'][option][value]})")
        if one["parameters"] is not None and not one["parameters_by_option"]:
            print("  parameters: " + "; ".join(_parameter_text(parameter) for parameter in one["parameters"]))
    return EXIT_OK


def listing(name: str, entry) -> dict:
    """A model as ``brdffit models`` lists it, as plain data: ``name``, ``summary``, ``options`` (the options a user
    gives), ``choices`` (each option's values and what they mean), ``details`` (lines of a model described by its
    entry: one built from a file), ``parameters`` (of the default model: ``name``, ``per_channel``, ``domain``,
    ``held``; None where it needs a file), and ``parameters_by_option`` (for an option whose values change the
    parameters: each value's)."""
    from ..physics.models.registry import recorded_options

    options = [option for option in entry.option_defaults if option not in recorded_options()]
    if entry.listing:  # a model that needs a file to be built: described by its entry
        summary, *details = entry.listing
        return {
            "name": name,
            "summary": summary,
            "options": options,
            "choices": {},
            "details": list(details),
            "parameters": None,
            "parameters_by_option": {},
        }
    model = entry()
    shaping = [option for option in entry.choices if _changes_parameters(entry, option)]
    return {
        "name": name,
        "summary": model.summary + (f": {model.lobe.summary}" if model.lobe else ""),
        "options": options,
        "choices": {option: dict(values) for option, values in entry.choices.items()},
        "details": [],
        "parameters": parameters_of(model),
        "parameters_by_option": {
            option: {value: parameters_of(entry(**{option: value})) for value in entry.choices[option]}
            for option in shaping
        },
    }


def _parameter_text(parameter: dict) -> str:
    held = "" if parameter["held"] is None else f" (held at {parameter['held']:g} unless freed)"
    return f"{parameter['name']}: {'[C] ' if parameter['per_channel'] else ''}{parameter['domain']}{held}"


def _changes_parameters(entry, option: str) -> bool:
    """Whether the values of ``option`` give models of different parameters (Cook-Torrance's Fresnel term)."""
    return len({json.dumps(parameters_of(entry(**{option: value}))) for value in entry.choices[option]}) > 1


def parameters_of(model) -> list[dict]:
    """Each parameter of ``model``: its ``name``, whether it has one value per channel (``per_channel``), its
    ``domain`` (as text) and the value it is ``held`` at unless freed (None: fitted)."""
    held = dict(getattr(model, "held", ()))

    def one(name: str, per_channel: bool, domain: str) -> dict:
        return {"name": name, "per_channel": per_channel, "domain": domain, "held": held.get(name)}

    parameters = [] if model.whole else [one(model.diffuse_name, True, model.diffuse.albedo_domain.text)]
    if model.n_lobes:
        if not model.whole:
            parameters.append(one(model.specular_name, True, model.lobe.albedo_domain.text))
        parameters += [
            one(name, name in model.lobe.channel_names, domain.text) for name, domain in model.lobe.parameters
        ]
    return parameters
