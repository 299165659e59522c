"""``brdffit report``: compare models on one samples file and write one self-contained HTML page about it."""

import argparse
from pathlib import Path

from . import EXIT_OK
from .arguments import add_loading_options, load, output_file


def configure(parser: argparse.ArgumentParser) -> None:
    from ..fitting.fit import MAX_STEPS, N_STARTS
    from ..fitting.losses import LOSSES

    parser.add_argument("samples", metavar="SAMPLES", help="samples file: CSV, MERL, ALTA, ASTM")
    parser.add_argument(
        "--models",
        metavar="SPEC,…",
        help="models to compare, as for brdffit compare (default: every model)",
    )
    parser.add_argument("--loss", default="log", metavar="NAME", help=f"one of: {', '.join(LOSSES)} (default log)")
    parser.add_argument("--folds", type=int, default=5, metavar="K", help="cross-validation folds (default 5)")
    parser.add_argument(
        "--uncertainty",
        metavar="METHOD",
        help="laplace or mcmc: error bars on the parameters of the two best models (default none)",
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
        "-o", "--output", metavar="FILE", help="the report (.html); default SAMPLES-stem.report.html here"
    )


def run(args: argparse.Namespace) -> int:
    from ..cache import enable_compilation_cache
    from ..fitting.losses import get_loss
    from ..physics.models.specs import model_of_spec, split_specs
    from ..uncertainty.methods import check_options
    from ..views.report import check_report_path, report

    enable_compilation_cache()
    models = None if args.models is None else [model_of_spec(spec) for spec in split_specs(args.models)]
    get_loss(args.loss)
    check_options(args.uncertainty)
    output = args.output or f"{Path(args.samples).stem}.report.html"
    path = output_file(output, "-o", [args.samples])
    check_report_path(output, argument="output")
    samples = load(args.samples, args)
    report(
        samples,
        models,
        args.loss,
        folds=args.folds,
        seed=args.seed,
        uncertainty=args.uncertainty,
        max_theta=args.max_theta,
        n_starts=args.starts,
        max_steps=args.max_steps,
        path=path,
        progress=None,
    )
    print(f"wrote {output}")
    return EXIT_OK
