"""``brdffit info``: what a samples file holds, read as a fit would read it."""

import argparse

from . import EXIT_OK
from .arguments import add_loading_options, load
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="FILE", help="samples file (any format), or a basis file (.npz)")
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")
    parser.add_argument(
        "--json",
        action="store_true",
        help="print what info says as one JSON object (docs/command-line.md lists its fields) instead of lines",
    )


def files(args: argparse.Namespace) -> Files:
    """What ``info`` reads (``FILE``); it writes nothing."""
    return Files.of(inputs={"FILE": args.input})


def run(args: argparse.Namespace) -> int:
    from ..data.summary import summary, summary_text
    from ..fitting.single.result import json_text

    if is_basis_file(args.input):
        from ..datadriven.basis import load_basis
        from .basis import describe_basis

        basis = load_basis(args.input)
        if args.json:
            print(json_text(_basis_summary(args.input, basis)))
            return EXIT_OK
        print(f"{args.input}: basis, {describe_basis(basis)}")
        print(f"  library: {', '.join(basis.materials[:6])}{', …' if len(basis.materials) > 6 else ''}")
        print(f"  bins holding a value: {int(basis.filled.sum()):,} of {basis.filled.size:,}; sha256 {basis.digest}")
        return EXIT_OK
    found = summary(load(args.input, args))
    print(json_text(found) if args.json else summary_text(found))
    return EXIT_OK


def _basis_summary(path: str, basis) -> dict:
    """What ``info`` says of a basis file, as plain data (``--json``)."""
    return {
        "source": str(path),
        "format": "basis",
        "components": int(basis.n_components),
        "mapping": basis.mapping,
        "explained": [float(share) for share in basis.explained],
        "materials": list(basis.materials),
        "bins_filled": int(basis.filled.sum()),
        "bins": int(basis.filled.size),
        "sha256": basis.digest,
    }


def is_basis_file(path: str) -> bool:
    """Whether ``path`` is a zip archive (an ``.npz``) holding a basis's ``kind``: sniffed, whatever its name."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            return "kind.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False
