"""``brdffit models``: each model with its formula, options, parameters and their domains."""

import argparse

from . import EXIT_OK


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def run(args: argparse.Namespace) -> int:
    from ..physics.fresnel import FRESNEL
    from ..physics.models import MODELS, get_model, model_option_names

    for name in MODELS:
        model = get_model(name)
        summary = model.summary + (f": {model.lobe.summary}" if model.lobe else "")
        print(f"{name}\n  {summary}")
        options = model_option_names(name)
        if options:
            print(f"  options: {', '.join('--' + option for option in options)}")
        if name == "cook-torrance":
            for fresnel in FRESNEL:
                lines = describe_parameters(get_model(name, fresnel=fresnel))
                print(f"  --fresnel {fresnel}: " + "; ".join(lines))
        else:
            print("  parameters: " + "; ".join(describe_parameters(model)))
    return EXIT_OK


def describe_parameters(model) -> list[str]:
    """One line per parameter: its name, shape ([C] for one value per channel) and domain."""
    from ..physics.domains import NON_NEGATIVE

    lines = [f"{model.diffuse_name}: [C] {NON_NEGATIVE.text}"]
    if model.n_lobes:
        lines.append(f"{model.specular_name}: [C] {NON_NEGATIVE.text}")
        lines += [f"{name}: {domain.text}" for name, domain in model.lobe.parameters]
    return lines
