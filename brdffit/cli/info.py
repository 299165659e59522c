"""``brdffit info``: what a samples file holds, read as a fit would read it."""

import argparse

from . import EXIT_OK
from .arguments import add_loading_options, load


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="FILE", help="samples file (any format)")
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")


def run(args: argparse.Namespace) -> int:
    from ..data.summary import describe

    print(describe(load(args.input, args)))
    return EXIT_OK
