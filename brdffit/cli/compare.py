"""``brdffit compare``: fit several models to one samples file and rank them by cross-validated loss."""

import argparse
import sys

from . import EXIT_OK
from .arguments import add_loading_options, load, output_file


def configure(parser: argparse.ArgumentParser) -> None:
    from ..fitting.fit import MAX_STEPS, N_STARTS
    from ..fitting.losses import LOSSES

    parser.add_argument("samples", metavar="SAMPLES", help="samples file: CSV, MERL, ALTA, ASTM")
    parser.add_argument(
        "--models",
        metavar="SPEC,…",
        help="models to compare, each NAME[:key=value,…] (cook-torrance:fresnel=conductor, lafortune:lobes=2,"
        " shorthand lafortune:2); default: every model, Lafortune with 1–3 lobes, Cook-Torrance with each Fresnel",
    )
    parser.add_argument("--loss", default="log", metavar="NAME", help=f"one of: {', '.join(LOSSES)} (default log)")
    parser.add_argument(
        "--folds", type=int, default=5, metavar="K", help="cross-validation folds (default 5, at least 2)"
    )
    parser.add_argument("--max-theta", type=float, metavar="DEG", help="drop samples with θi or θo above DEG degrees")
    parser.add_argument("--starts", type=int, default=N_STARTS, metavar="N", help=f"as for fit (default {N_STARTS})")
    parser.add_argument(
        "--max-steps", type=int, default=MAX_STEPS, metavar="N", help=f"as for fit (default {MAX_STEPS})"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the folds, the start search's subset and --subsample (default 0)"
    )
    add_loading_options(parser)
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="also write the comparison as JSON ('-' for standard output; the table then goes to standard error)",
    )


def run(args: argparse.Namespace) -> int:
    from ..cache import enable_compilation_cache
    from ..fitting.compare import compare
    from ..fitting.losses import get_loss
    from ..physics.models.specs import model_of_spec, split_specs

    enable_compilation_cache()
    models = None if args.models is None else [model_of_spec(spec) for spec in split_specs(args.models)]
    get_loss(args.loss)
    output = None if args.output in (None, "-") else output_file(args.output, "-o", [args.samples])
    samples = load(args.samples, args)
    comparison = compare(
        samples,
        models,
        args.loss,
        folds=args.folds,
        seed=args.seed,
        max_theta=args.max_theta,
        n_starts=args.starts,
        max_steps=args.max_steps,
        progress=None,
    )
    stream = sys.stderr if args.output == "-" else sys.stdout
    print(comparison.table(), file=stream)
    if args.output == "-":
        sys.stdout.write(comparison.to_json())
    elif output is not None:
        comparison.save(output)
        print(f"wrote {output}", file=stream)
    return EXIT_OK
