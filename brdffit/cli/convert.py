"""``brdffit convert``: samples from one format to another, or a fit result tabulated as a MERL file."""

import argparse
import sys
from pathlib import Path

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import add_loading_options, load, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    from ..data.load import FORMATS

    parser.add_argument("input", metavar="IN", help="samples file (any format), or a result file (.json) for .binary")
    parser.add_argument("output", metavar="OUT", help=f"the format from the extension: {_suffixes(FORMATS)}")
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")


def files(args: argparse.Namespace) -> Files:
    """What ``convert`` reads (``IN``) and writes (``OUT``)."""
    return Files.of(inputs={"IN": args.input}, outputs={"OUT": args.output})


def run(args: argparse.Namespace) -> int:
    from ..data.load import FORMATS, format_of_output

    output = Path(args.output)
    kind = "csv" if args.output == "-" else format_of_output(output)  # -: a samples CSV on standard output
    if kind is None:
        raise BrdfInputError(f"{output}: unknown output format; give one of: {_suffixes(FORMATS)}")
    output = output_file(args.output, "OUT", ".csv")
    if FORMATS[kind].write is None:
        return _tabulate(args, output)
    if Path(args.input).suffix.lower() == ".json":
        raise BrdfInputError(f"{args.input}: a result file converts only to a MERL file (.binary), not to {kind}")
    samples = load(args.input, args)
    if kind != "csv" and (samples.sigma is not None or samples.weight is not None):
        print(
            f"brdffit: warning: {output}: {kind} files hold no sigma or weight columns; they are not written",
            file=sys.stderr,
        )
    write = FORMATS[kind].write
    assert write is not None  # a format written from samples (else tabulated, above)
    write(samples, output)
    shown = "-" if args.output == "-" else output
    print(f"wrote {samples.n_samples} samples × {samples.n_channels} channel(s) to {shown} ({kind})")
    return EXIT_OK


def _suffixes(formats) -> str:
    """Every suffix a file can be written with, and its format: ``.csv (csv), .binary (merl), …``."""
    return ", ".join(f"{suffix} ({name})" for name, kind in formats.items() for suffix in kind.suffixes)


def _tabulate(args: argparse.Namespace, output: Path) -> int:
    """A fit result as a MERL table (the one format written from a model, not from samples)."""
    if Path(args.input).suffix.lower() != ".json":
        raise BrdfInputError(
            f"{output}: a MERL file tabulates a whole BRDF; convert a fit result (.json) to .binary, e.g."
            " brdffit convert fit.json out.binary"
        )
    from .._programs.cache import enable_compilation_cache
    from ..export.merl import write_merl
    from ..fitting.single.result import load_result

    enable_compilation_cache()
    result = load_result(args.input)
    notes = write_merl(result.model, result.params, output, bin_centres=args.bin_centres, **result.model_options)
    print(f"wrote {output}: {result.model} tabulated on MERL's 90 × 90 × 180 grid")
    for note in notes:
        print(f"note: {note}")
    return EXIT_OK
