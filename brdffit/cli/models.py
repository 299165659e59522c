"""``brdffit models``: each model with its formula, options, parameters and their domains."""

import argparse

from . import EXIT_OK
from .arguments import flag
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def files(args: argparse.Namespace) -> Files:
    """``models`` reads and writes no file."""
    return Files()


def run(args: argparse.Namespace) -> int:
    from ..physics.models.registry import MODELS, recorded_options

    for name, entry in MODELS.items():
        options = [option for option in entry.option_defaults if option not in recorded_options()]
        if entry.listing:  # a model that needs a file to be built: described by its entry
            summary, *details = entry.listing
            print(f"{name}\n  {summary}")
            if options:
                print(f"  options: {', '.join(flag(option) for option in options)}")
            for line in details:
                print(f"  {line}")
            continue
        model = entry()
        summary = model.summary + (f": {model.lobe.summary}" if model.lobe else "")
        print(f"{name}\n  {summary}")
        if options:
            print(f"  options: {', '.join(flag(option) for option in options)}")
        shaping = [option for option in entry.choices if _changes_parameters(entry, option)]
        for option, values in entry.choices.items():
            if option not in shaping:
                listed = ", ".join(f"{value} ({what})" for value, what in values.items())
                print(f"  {flag(option)}: {listed}")
        for option in shaping:
            for value, what in entry.choices[option].items():
                lines = describe_parameters(entry(**{option: value}))
                print(f"  {flag(option)} {value}: {'; '.join(lines)} ({what})")
        if not shaping:
            print("  parameters: " + "; ".join(describe_parameters(model)))
    return EXIT_OK


def _changes_parameters(entry, option: str) -> bool:
    """Whether the values of ``option`` give models of different parameters (Cook-Torrance's Fresnel term)."""
    return len({tuple(describe_parameters(entry(**{option: value}))) for value in entry.choices[option]}) > 1


def describe_parameters(model) -> list[str]:
    """One line per parameter: its name, shape ([C] for one value per channel) and domain."""
    held = dict(getattr(model, "held", ()))
    held_text = lambda name: f" (held at {held[name]:g} unless freed)" if name in held else ""
    lines = [] if model.whole else [f"{model.diffuse_name}: [C] {model.diffuse.albedo_domain.text}"]
    if model.n_lobes:
        if not model.whole:
            albedo = model.lobe.albedo_domain.text
            lines.append(f"{model.specular_name}: [C] {albedo}{held_text(model.specular_name)}")
        per_channel = lambda name: "[C] " if name in model.lobe.channel_names else ""
        lines += [
            f"{name}: {per_channel(name)}{domain.text}{held_text(name)}" for name, domain in model.lobe.parameters
        ]
    return lines
