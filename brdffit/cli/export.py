"""``brdffit export RESULT.json --to mitsuba|gltf|merl``: a fit in a form a renderer reads.

Exact where the renderer has the fitted model; otherwise the renderer's model is fitted to the fitted BRDF and
the error is printed and stored in the file (``brdffit/export``).
"""

import argparse

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import BIN_CENTRES_HELP, fit_file_files, fit_of, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    from ..export.targets import TARGETS

    parser.add_argument(
        "result",
        metavar="RESULT.json",
        help="a result file of brdffit fit, or a comparison file of brdffit compare -o (its best model)",
    )
    parser.add_argument(
        "--to",
        required=True,
        metavar="TARGET",
        help="; ".join(f"{name}: {target.description}" for name, target in TARGETS.items()),
    )
    parser.add_argument(
        "--format",
        metavar="FORMAT",
        help="mitsuba: xml (default; mitsuba.load_file takes it) or dict (a Python file defining bsdf for"
        " mitsuba.load_dict); gltf: gltf (default, JSON) or glb (binary). Default: the one -o's suffix names",
    )
    parser.add_argument(
        "-o", "--output", metavar="FILE", help="the file (default: RESULT's stem with the target's suffix, here)"
    )
    parser.add_argument("--bin-centres", action="store_true", help=BIN_CENTRES_HELP)
    parser.add_argument(
        "--samples",
        metavar="DATA",
        help="the data the fit was made from (read as the fit read it): also say how far the export, evaluated as"
        " its renderer evaluates it, lies from the data at the data's own directions (stored in the file too)",
    )


def files(args: argparse.Namespace) -> Files:
    """What ``export`` reads and writes (:func:`~brdffit.cli.arguments.fit_file_files`)."""
    return fit_file_files(args, _output(args))


def _output(args: argparse.Namespace) -> str:
    """The file: ``-o``, by default RESULT's stem with the suffix of the target's format, here."""
    from ..export.targets import TARGETS, export_format
    from .files import stem

    kind = export_format(args.to, args.format, args.output)
    return args.output or stem(args.result) + TARGETS[args.to].formats[kind]


def run(args: argparse.Namespace) -> int:
    from .._programs.cache import enable_compilation_cache
    from ..export.targets import TARGETS, check_suffix, export, export_format

    kind = export_format(args.to, args.format, args.output)
    if args.output is not None:  # a default name has the format's suffix
        check_suffix(args.to, args.output, standard_output=True)
    if args.bin_centres and args.to != "merl":
        raise BrdfInputError(f"--bin-centres applies to --to merl, not to --to {args.to}")
    from .files import input_path

    result = fit_of(args)
    path = output_file(_output(args), "-o", TARGETS[args.to].formats[kind])
    enable_compilation_cache()
    samples = input_path(args.samples)  # None: not given
    lines = export(result, args.to, path, kind, samples, bin_centres=args.bin_centres)
    print(f"wrote {args.output if args.output == '-' else path}: {TARGETS[args.to].description} of {args.result}")
    for line in lines:
        print(f"  {line}")
    return EXIT_OK
