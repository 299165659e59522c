"""``brdffit models``: each model with its formula, options, parameters and their domains."""

import argparse

from . import EXIT_OK
from .arguments import flag


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def run(args: argparse.Namespace) -> int:
    from ..physics.fresnel import FRESNEL
    from ..physics.microfacet import DISTRIBUTIONS, SHADOWING
    from ..physics.models.registry import MODELS, get_model, model_option_names

    for name in MODELS:
        if name == "pca":  # its model needs a basis file: described, not built
            print(f"{name}\n  data-driven: principal components of a library of measured tables (brdffit basis build)")
            print(f"  options: {', '.join(flag(option) for option in ('basis', 'ridge'))}")
            print("  parameters: coefficients: [K][C] real, in library standard deviations (K: the basis's components)")
            continue
        model = get_model(name)
        summary = model.summary + (f": {model.lobe.summary}" if model.lobe else "")
        print(f"{name}\n  {summary}")
        options = model_option_names(name)
        if options:
            print(f"  options: {', '.join(flag(option) for option in options)}")
        if name == "cook-torrance":
            for option, kinds in (("distribution", DISTRIBUTIONS), ("shadowing", SHADOWING)):
                described = (getattr(kind, "summary", kind) for kind in kinds.values())
                listed = ", ".join(f"{value} ({what})" for value, what in zip(kinds, described, strict=True))
                print(f"  {flag(option)}: {listed}")
            for fresnel, kind in FRESNEL.items():
                lines = describe_parameters(get_model(name, fresnel=fresnel))
                print(f"  {flag('fresnel')} {fresnel}: {'; '.join(lines)} ({kind.summary})")
        else:
            print("  parameters: " + "; ".join(describe_parameters(model)))
    return EXIT_OK


def describe_parameters(model) -> list[str]:
    """One line per parameter: its name, shape ([C] for one value per channel) and domain."""
    from ..physics.domains import ALBEDO

    lines = [f"{model.diffuse_name}: [C] {ALBEDO.text}"]
    if model.n_lobes:
        lines.append(f"{model.specular_name}: [C] {ALBEDO.text}")
        lines += [f"{name}: {domain.text}" for name, domain in model.lobe.parameters]
    return lines
