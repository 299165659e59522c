"""``brdffit info``: what a samples file holds, read as a fit would read it."""

import argparse

from . import EXIT_OK
from .arguments import add_loading_options, load
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="FILE", help="samples file (any format), or a basis file (.npz)")
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")


def files(args: argparse.Namespace) -> Files:
    """What ``info`` reads (``FILE``); it writes nothing."""
    return Files.of(inputs={"FILE": args.input})


def run(args: argparse.Namespace) -> int:
    from ..data.summary import describe

    if is_basis_file(args.input):
        from ..datadriven.basis import load_basis
        from .basis import describe_basis

        basis = load_basis(args.input)
        print(f"{args.input}: basis, {describe_basis(basis)}")
        print(f"  library: {', '.join(basis.materials[:6])}{', …' if len(basis.materials) > 6 else ''}")
        print(f"  bins holding a value: {int(basis.filled.sum()):,} of {basis.filled.size:,}; sha256 {basis.digest}")
        return EXIT_OK
    print(describe(load(args.input, args)))
    return EXIT_OK


def is_basis_file(path: str) -> bool:
    """Whether ``path`` is a zip archive (an ``.npz``) holding a basis's ``kind``: sniffed, whatever its name."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            return "kind.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False
