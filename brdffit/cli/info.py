"""``brdffit info``: what a samples file holds, read as a fit would read it."""

import argparse
from pathlib import Path

from . import EXIT_OK
from .arguments import add_loading_options, load


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="FILE", help="samples file (any format)")
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")


def run(args: argparse.Namespace) -> int:
    from ..data.load import detect_format
    from ..data.summary import describe

    samples = load(args.input, args)
    print(describe(samples, detect_format(Path(args.input), args.format)))
    return EXIT_OK
