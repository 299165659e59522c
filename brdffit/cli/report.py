"""``brdffit report``: compare models on one samples file and write one self-contained HTML page about it; or, given
the folder of fitted maps (``brdffit svbrdf fit``), the page of those maps (``svbrdf/report.py``)."""

import argparse
from pathlib import Path

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import add_comparison_options, add_mcmc_options, comparison_arguments, load, mcmc_settings, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    add_comparison_options(parser)
    errors = parser.add_argument_group("uncertainty")
    errors.add_argument(
        "--uncertainty",
        metavar="METHOD",
        help="laplace or mcmc: error bars on the parameters of the two best models (default none)",
    )
    add_mcmc_options(errors)
    parser.add_argument(
        "-o", "--output", metavar="FILE", help="the report (.html); default SAMPLES-stem.report.html here"
    )
    parser.add_argument(
        "--held-back",
        metavar="CAPTURE",
        help="a maps folder's report: a capture of photographs the fit did not see, to set beside the maps relit",
    )


def files(args: argparse.Namespace) -> Files:
    """What ``report`` reads (the samples, ``--basis``, ``--held-back``) and writes (the page)."""
    return Files.of(
        inputs={"SAMPLES": args.samples, "--basis": args.basis, "--held-back": args.held_back},
        outputs={"-o": _output(args)},
    )


def _is_maps(path: str) -> bool:
    """Whether ``path`` is a folder of fitted maps (it holds ``maps.json``)."""
    return (Path(path) / "maps.json").is_file()


def _output(args: argparse.Namespace) -> str:
    """The page: ``-o``, by default ``SAMPLES-stem.report.html`` here."""
    from .files import stem

    return args.output or f"{stem(args.samples)}.report.html"


def run(args: argparse.Namespace) -> int:
    from .._programs.cache import enable_compilation_cache
    from ..uncertainty.methods import check_options
    from ..views.report import check_report_path, report

    enable_compilation_cache()
    if _is_maps(args.samples):
        return _maps_report(args)
    if args.held_back is not None:
        raise BrdfInputError("--held-back applies to a maps folder's report (brdffit report MAPS/)")
    arguments = comparison_arguments(args)
    check_options(args.uncertainty)
    mcmc = mcmc_settings(args)
    output = _output(args)
    path = output_file(output, "-o", ".html")
    check_report_path(path if output == "-" else output, argument="output")
    report(
        load(args.samples, args),
        **arguments,
        uncertainty=args.uncertainty,
        mcmc=mcmc,
        path=path,
        progress=False if args.quiet else None,
    )
    print(f"wrote {output}")  # on standard error when the page went to standard output (-o -)
    return EXIT_OK


def _maps_report(args: argparse.Namespace) -> int:
    from ..svbrdf.report import maps_report
    from ..views.report import check_report_path

    output = _output(args)
    if output == "-":
        raise BrdfInputError("-o -: a maps report is written to a file; give its name (maps.html)")
    path = output_file(output, "-o", ".html")
    check_report_path(path, argument="output")
    maps_report(args.samples, path, held_back=args.held_back)
    print(f"wrote {output}")
    return EXIT_OK
