"""``brdffit compare``: fit several models to one samples file and rank them by cross-validated loss."""

import argparse
import sys

from .._files import check_not_stopped
from . import EXIT_OK
from .arguments import add_comparison_options, comparison_arguments, load, output_file
from .files import Files, write_to_standard_output


def configure(parser: argparse.ArgumentParser) -> None:
    add_comparison_options(parser)
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="also write the comparison as JSON ('-' for standard output; the table then goes to standard error)",
    )


def files(args: argparse.Namespace) -> Files:
    """What ``compare`` reads (the samples, ``--basis``) and writes (``-o``, unless standard output)."""
    return Files.of(
        inputs={"SAMPLES": args.samples, "--basis": args.basis},
        outputs={"-o": None if args.output == "-" else args.output},
    )


def run(args: argparse.Namespace) -> int:
    from .._programs.cache import enable_compilation_cache
    from ..fitting.comparison.compare import compare

    enable_compilation_cache()
    arguments = comparison_arguments(args)
    output = None if args.output in (None, "-") else output_file(args.output, "-o")
    comparison = compare(load(args.samples, args), **arguments, progress=False if args.quiet else None)
    stream = sys.stderr if args.output == "-" else sys.stdout
    print(comparison.table(), file=stream)
    if args.output == "-":
        check_not_stopped()  # an interrupted command writes nothing, also here
        write_to_standard_output(comparison.to_json())
    elif output is not None:
        comparison.save(output)
        print(f"wrote {output}", file=stream)
    return EXIT_OK
