"""``brdffit basis``: a data-driven basis learned from a library of MERL tables, and the directions to measure.

``basis build LIB… -o basis.npz``: the principal components of the library's mapped tables (``datadriven/build.py``).
``basis directions basis.npz -n 20 -o directions.csv``: the pairs that best condition a fit of a new material's
coefficients (``datadriven/directions.py``). ``brdffit fit SAMPLES --model pca --basis basis.npz`` fits them.
"""

import argparse
import sys
import time
from pathlib import Path

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import output_file, quiet
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    from ..datadriven.build import DEFAULT_COMPONENTS
    from ..datadriven.directions import CANDIDATES, MAX_THETA
    from ..datadriven.mapping import MAPPINGS

    actions = parser.add_subparsers(title="actions", metavar="ACTION", required=True)
    build = actions.add_parser("build", help="learn a basis from a library of MERL tables", allow_abbrev=False)
    build.add_argument("library", nargs="+", metavar="LIB", help="MERL .binary files, or folders of them")
    quiet(build)
    build.add_argument("-o", "--output", required=True, metavar="FILE", help="basis file to write (.npz)")
    build.add_argument(
        "--components",
        type=int,
        default=DEFAULT_COMPONENTS,
        metavar="K",
        help=f"principal components to keep (default {DEFAULT_COMPONENTS})",
    )
    build.add_argument(
        "--mapping",
        default=MAPPINGS[0],
        metavar="M",
        help=f"{', '.join(MAPPINGS)} (default {MAPPINGS[0]}: ln((ρ·cos θi cos θo + ε)/(ρ_median·… + ε)))",
    )
    build.set_defaults(action=_build)
    directions = actions.add_parser(
        "directions", help="the direction pairs that best condition a coefficient fit", allow_abbrev=False
    )
    directions.add_argument("basis", metavar="BASIS", help="basis file (from brdffit basis build)")
    quiet(directions)
    directions.add_argument("-n", type=int, default=20, metavar="N", help="how many pairs (default 20)")
    directions.add_argument("-o", "--output", required=True, metavar="FILE", help="directions CSV to write")
    directions.add_argument(
        "--max-theta",
        type=float,
        default=MAX_THETA,
        metavar="DEG",
        help=f"largest zenith angle of a pair (default {MAX_THETA:g})",
    )
    directions.add_argument(
        "--candidates", type=int, default=CANDIDATES, metavar="N", help=f"bins scored (default {CANDIDATES})"
    )
    directions.add_argument("--seed", type=int, default=0, help="seed of the candidates' subset (default 0)")
    directions.set_defaults(action=_directions)


def files(args: argparse.Namespace) -> Files:
    """What ``basis build`` reads (the library's tables) and writes (``-o``); what ``basis directions`` reads (the
    basis) and writes (``-o``)."""
    if args.action is _build:
        output = None if args.output == "-" else args.output
        return Files.of(inputs={"LIB": library_files(args.library)}, outputs={"-o": output})
    return Files.of(inputs={"BASIS": args.basis}, outputs={"-o": args.output})


def run(args: argparse.Namespace) -> int:
    return args.action(args)


def library_files(entries: list[str]) -> list[Path]:
    """The MERL files of ``LIB…``: files as given, folders as their ``*.binary`` files, sorted."""
    files: list[Path] = []
    for entry in entries:
        path = Path(entry)
        if path.is_dir():
            found = sorted(path.glob("*.binary"))
            if not found:
                raise BrdfInputError(f"{entry}: folder holds no .binary (MERL) file")
            files += found
        else:
            files.append(path)
    return files


def _build(args: argparse.Namespace) -> int:
    from .._progress import progress_bar
    from ..data.merl import N_BINS
    from ..datadriven.basis import save_basis
    from ..datadriven.build import build_basis

    files = library_files(args.library)
    if args.output == "-":
        raise BrdfInputError("-o -: a basis is a binary file; give a file name (basis.npz)")
    output = output_file(args.output, "-o")
    started = time.perf_counter()
    with progress_bar(2 * N_BINS, "bin", False if args.quiet else None, unit_scale=True) as bar:
        basis = build_basis(files, components=args.components, mapping=args.mapping, progress=bar.update)
    save_basis(basis, output)
    print(f"wrote {output}: {describe_basis(basis)} ({time.perf_counter() - started:.1f} s)")
    return EXIT_OK


def _directions(args: argparse.Namespace) -> int:
    from ..datadriven.basis import load_basis
    from ..datadriven.directions import choose_directions, write_directions

    output = output_file(args.output, "-o")
    basis = load_basis(args.basis)
    from .._progress import progress_bar

    with progress_bar(args.n, "pair", False if args.quiet else None) as bar:
        options = dict(max_theta=args.max_theta, candidates=args.candidates, seed=args.seed, progress=bar.update)
        chosen = choose_directions(basis, args.n, **options)
    write_directions(chosen.angles, output)
    pairs = "pair" if args.n == 1 else "pairs"
    print(
        f"wrote {output}: {args.n} direction {pairs}; condition number of the {basis.n_components} components'"
        f" rows there {chosen.condition:.3g}"
    )
    if chosen.poorly_conditioned:
        print(
            "brdffit: warning: these pairs barely determine the coefficients (condition number"
            f" {chosen.condition:.3g}): a fit would rest on the ridge; allow a larger --max-theta or more --candidates",
            file=sys.stderr,
        )
    return EXIT_OK


def describe_basis(basis) -> str:
    """One line: components, library, mapping, explained variance."""
    import numpy as np

    cumulative = np.cumsum(basis.explained)
    shares = ", ".join(f"{100 * share:.1f}%" for share in basis.explained)
    return (
        f"{basis.n_components} components of {len(basis.materials)} tables ({basis.mapping} mapping);"
        f" variance explained {shares} (together {100 * cumulative[-1]:.2f}%)"
    )
