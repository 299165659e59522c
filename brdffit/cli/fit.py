"""``brdffit fit``: fit a model to one or more samples files, write each result, print its table.

Every check runs before any fit (options, output paths, every input read), so bad input writes nothing.
"""

import argparse
import os
import sys
from pathlib import Path

from .._files import check_not_stopped
from ..errors import Argument, BrdfInputError
from . import EXIT_BAD_INPUT, EXIT_NOT_CONVERGED, EXIT_OK
from .arguments import (
    add_holding_options,
    add_loading_options,
    add_mcmc_options,
    add_model_options,
    cluster_client,
    holding_arguments,
    json_argument,
    json_file,
    load,
    mcmc_settings,
    model_options,
    output_file,
    read_options,
)
from .files import Files, write_to_standard_output


def configure(parser: argparse.ArgumentParser) -> None:
    from ..fitting.objective.losses import LOSSES
    from ..fitting.options import MAX_STEPS, N_STARTS

    parser.add_argument("samples", metavar="SAMPLES", nargs="+", help="samples file(s): CSV, MERL, ALTA, ASTM")
    add_model_options(parser, "ward")
    parser.add_argument("--loss", default="log", metavar="NAME", help=f"one of: {', '.join(LOSSES)} (default log)")
    parser.add_argument("--max-theta", type=float, metavar="DEG", help="drop samples with θi or θo above DEG degrees")
    add_holding_options(parser)
    add_loading_options(parser)
    parser.add_argument(
        "--start",
        metavar="PARAMS",
        help="start from these parameters (JSON file, a result file, or inline JSON) instead of the data-driven starts",
    )
    parser.add_argument(
        "--starts",
        type=int,
        default=N_STARTS,
        metavar="N",
        help=f"Levenberg-Marquardt runs from the N best grid starts (default {N_STARTS})",
    )
    parser.add_argument(
        "--max-steps",
        type=int,
        default=MAX_STEPS,
        metavar="N",
        help=f"most solver steps per start (default {MAX_STEPS})",
    )
    parser.add_argument(
        "--dtype",
        default="float64",
        metavar="TYPE",
        help="float64 (default), or float32: solve in single precision, then refine in double",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="result file ('-' for standard output, the table then goes to standard error), or a folder (OUTDIR/)"
        " for several samples files (default: SAMPLES-stem.MODEL[.OPTION-VALUE].json in the current folder)",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print a JSON list, one object per samples file (its result file, model, cost, rmse, steps, converged,"
        " warnings; error for one not written), instead of the table or the summary",
    )
    parser.add_argument(
        "--threads",
        type=int,
        metavar="N",
        help="several samples files: fit N batches of them at once (default: one per CPU core this process may use;"
        " with --scheduler or --workers, 1 in each task)",
    )
    spread = parser.add_argument_group("cluster (pip install 'brdffit[cluster]')").add_mutually_exclusive_group()
    spread.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="spread the fits over the Dask cluster whose scheduler is at ADDRESS (tcp://host:8786); its workers"
        " read the samples files, at the same paths",
    )
    spread.add_argument(
        "--workers", type=int, metavar="N", help="spread the fits over a local Dask cluster of N worker processes"
    )
    errors = parser.add_argument_group("uncertainty")
    errors.add_argument(
        "--uncertainty",
        metavar="METHOD",
        help="laplace (Gauss-Newton covariance at the optimum) or mcmc (emcee posterior)",
    )
    add_mcmc_options(errors)
    errors.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the mcmc walkers, the start search's subset and --subsample (default 0)",
    )
    errors.add_argument("--chain", metavar="FILE", help="mcmc: save the whole chain (.npz, or .h5 with h5py)")
    errors.add_argument("--corner", metavar="FILE", help="corner plot of the posterior (.png, .pdf or .svg)")


def files(args: argparse.Namespace) -> Files:
    """What ``fit`` reads (the samples, ``--start``, ``--basis``) and writes (results, ``--chain``, ``--corner``)."""
    from ..physics.models.registry import get_model

    model = get_model(args.model, **model_options(args))
    return Files.of(
        inputs={"SAMPLES": args.samples, "--start": json_file(args.start), "--basis": args.basis},
        outputs={
            "-o": output_paths(args.samples, args.output, model),
            "--chain": args.chain,
            "--corner": args.corner,
        },
    )


def run(args: argparse.Namespace) -> int:
    from .._programs.cache import enable_compilation_cache
    from ..fitting.objective.losses import get_loss
    from ..fitting.options import Solving
    from ..physics.models.registry import get_model

    enable_compilation_cache()
    model = get_model(args.model, **model_options(args))
    get_loss(args.loss)
    mcmc = _uncertainty_settings(args)
    Solving(n_starts=args.starts, max_steps=args.max_steps, dtype=args.dtype, seed=args.seed)  # checked before any work
    outputs = output_paths(args.samples, args.output, model)
    start = _start(args.start)
    held = holding_arguments(args)
    _check_holding(model, held)
    if args.json and outputs is None:
        raise BrdfInputError("--json prints to standard output, where -o - sends the result: give one of them")
    for option, value in (("--workers", args.workers), ("--threads", args.threads)):
        if value is not None and value < 1:
            raise BrdfInputError(f"{option} must be 1 or more, got {value}")
    if args.chain and (args.scheduler or args.workers):
        raise BrdfInputError("--chain keeps a chain in this process: give it without --scheduler and --workers")
    if args.scheduler:  # a cluster's workers read the files, at the same paths (a worker's folder may be another)
        samples = [str(Path(path).resolve()) for path in args.samples]
    else:
        samples = [load(path, args) for path in args.samples]  # every input read and checked before any fit
    if args.scheduler or args.workers:
        with cluster_client(args.scheduler, args.workers) as client:
            results = _fit(args, model, samples, start, mcmc, held, client=client)
    else:
        results = _fit(args, model, samples, start, mcmc, held)
    # A fit that is not finite (data out of float64's range) has no result file: one fit is an error; in a batch,
    # that dataset's error line, the others written, and the exit status of bad input.
    problems = [result.non_finite() for result in results]
    if len(results) == 1 and problems[0] is not None:
        raise BrdfInputError(f"{args.samples[0]}: {problems[0]}")
    if outputs is None:  # -o -: the result file on standard output, everything else on standard error
        check_not_stopped()  # an interrupted command writes nothing, also here
        write_to_standard_output(results[0].to_json())
    else:
        outputs[0].parent.mkdir(parents=True, exist_ok=True)
        for result, output, problem in zip(results, outputs, problems, strict=True):
            if problem is None:
                result.save(output)
    if args.corner:
        from ..views.corner import corner_plot

        corner_plot(results[0], args.corner)
    _report(args, results, outputs, problems)
    if any(problem is not None for problem in problems):
        return EXIT_BAD_INPUT
    return EXIT_OK if all(result.converged for result in results) else EXIT_NOT_CONVERGED


def _fit(args: argparse.Namespace, model, samples: list, start, mcmc, held: dict, client=None) -> list:
    """Every fit, with its uncertainty when asked; their warnings are the results' own (``_report`` prints them).
    With a Dask ``client``, spread over its workers; paths in ``samples`` are read there."""
    from .. import api

    options = dict(
        max_theta=args.max_theta,
        start=start,
        n_starts=args.starts,
        max_steps=args.max_steps,
        dtype=args.dtype,
        seed=args.seed,
        uncertainty=args.uncertainty,
        mcmc=mcmc,
        **held,
    )
    progress = False if args.quiet else None  # None: a bar where standard error is a terminal
    if client is not None:
        return api.fit_batch(
            samples,
            model,
            args.loss,
            client=client,
            read_options=read_options(args),
            threads=args.threads,
            progress=progress,
            **options,
        )
    if len(samples) == 1:
        progress = sys.stderr.isatty() and not args.quiet
        return [api.fit(samples[0], model, args.loss, chain=args.chain, progress=progress, **options)]
    return api.fit_batch(samples, model, args.loss, threads=args.threads, progress=progress, **options)


def _report(args: argparse.Namespace, results: list, outputs: list[Path] | None, problems: list[str | None]) -> None:
    """The table (one input) or a line per input, then a warning line for each thing a user must know, and an error
    line for each input whose fit is not finite (``problems``: none written).

    On standard output, unless the result file went there (``-o -``): then on standard error. ``-q``: the warnings
    and errors alone. A fit's caveats are in its table; they are said again on standard error only where the table
    did not reach the same screen (standard output a file or a pipe): on a terminal each was printed twice.
    """
    stream = sys.stderr if outputs is None else sys.stdout
    caveats_seen = False
    each: list[Path | None] = list(outputs) if outputs else [None]
    written = [None if problem else output for output, problem in zip(each, problems, strict=True)]
    if args.quiet:  # no table nor summary, wherever it would go (-q -o -: the result alone on standard output)
        pass
    elif args.json:
        from ..fitting.single.result import json_text

        print(json_text(summary_rows(args.samples, results, written, problems)), file=stream)
    elif len(results) == 1:
        print(results[0].table(source=args.samples[0]), file=stream)
        caveats_seen = stream is sys.stderr or (sys.stdout.isatty() and sys.stderr.isatty())
        files: list[str | Path | None] = ["-"] if outputs is None else [*outputs]  # None: -o -
        files += [args.chain, args.corner]
        if any(files):
            print(f"wrote {', '.join(str(path) for path in files if path)}", file=stream)
    else:
        print(summary(args.samples, results, written), file=stream)
    for path, result, problem in zip(args.samples, results, problems, strict=True):
        if problem is not None:
            print(f"brdffit: error: {path}: {problem}; not written", file=sys.stderr)
            continue
        caveats = [] if caveats_seen else result.warnings
        for message in [*caveats, *(result.uncertainty["warnings"] if result.uncertainty else [])]:
            print(f"brdffit: warning: {path}: {message}", file=sys.stderr)
        if not result.converged:
            print(
                f"brdffit: warning: {path}: the fit did not converge ({result.message}); written with converged: false",
                file=sys.stderr,
            )


def _check_holding(model, held: dict) -> None:
    """The names, values and bounds of ``--fix`` and ``--bounds`` checked against the model before any file is read
    (the channel count is checked with the samples)."""
    from ..fitting.single.constraints import check_names

    check_names(model, **held)


def _start(value: str | None):
    """The ``--start`` parameters: a parameter dictionary, or a result file's ``params``."""
    if not value:
        return None
    start = json_argument(value, "--start")
    return start["params"] if isinstance(start, dict) and "params" in start else start


def _uncertainty_settings(args: argparse.Namespace):
    """The MCMC settings (None unless ``--uncertainty mcmc``), after every check of the uncertainty options."""
    from ..uncertainty.methods import check_options
    from ..views.figures import check_figure_path

    check_options(args.uncertainty, chain=args.chain if args.uncertainty == "mcmc" else None)
    method = args.uncertainty
    settings = mcmc_settings(args, also=("chain",))
    if args.corner and not method:
        raise BrdfInputError(Argument("corner"), " needs ", Argument("uncertainty", "mcmc"), " (or laplace)")
    if args.corner:  # before the work: the plot's libraries
        from ..errors import needs

        needs("matplotlib", "plots", "corner plots")
        needs("corner", "plots", "corner plots")
    if (args.chain or args.corner) and len(args.samples) > 1:
        raise BrdfInputError(f"--chain and --corner take one samples file; got {len(args.samples)}")
    if args.chain:
        args.chain = str(output_file(args.chain, "--chain"))
    if args.corner:
        check_figure_path(args.corner, argument="corner")
        args.corner = str(output_file(args.corner, "--corner"))
        os.environ.setdefault("MPLBACKEND", "Agg")  # files only: no window, no display needed
    return settings


def output_paths(inputs: list[str], output: str | None, model) -> list[Path] | None:
    """The result file of each input (None: ``-o -``, standard output), checked before any work.

    One input: ``-o FILE``, by default ``<stem>.<model>[.<option>-<value>].json`` here (the options that change
    the result are in the name, so fits of one file with other options do not overwrite each other). ``-o``
    ending in ``/``, or several inputs: a folder, created (after every check) if missing, holding one such
    file per input. An existing folder without the ``/`` is refused: it would be ambiguous. That no output is
    an input is checked with every other file of the command (:func:`files`).
    """
    if output == "-":
        if len(inputs) > 1:
            raise BrdfInputError(f"-o -: standard output takes one result; got {len(inputs)} samples files")
        return None
    as_folder = len(inputs) > 1 or (output is not None and output.endswith(("/", os.sep)))
    if not as_folder:
        if output is not None and Path(output).is_dir():
            raise BrdfInputError(
                f"-o {output}: is a folder; give a file name, or {output.rstrip(os.sep)}/ to write"
                f" {default_name(inputs[0], model)} into it"
            )
        return [output_file(output or default_name(inputs[0], model), "-o")]
    folder = Path(output) if output else Path(".")
    if folder.exists() and not folder.is_dir():
        raise BrdfInputError(f"-o {output}: is a file; with several samples files give a folder (OUTDIR/)")
    json_named = folder.suffix.lower() == ".json" and output is not None and not output.endswith(("/", os.sep))
    if not folder.exists() and json_named:
        raise BrdfInputError(f"-o {output}: looks like a file; with several samples files give a folder (OUTDIR/)")
    existing = next((parent for parent in (folder, *folder.parents) if parent.exists()), Path("."))
    if not os.access(existing, os.W_OK):
        raise BrdfInputError(f"-o {folder}: folder {existing} is not writable")
    outputs = [folder / default_name(path, model) for path in inputs]
    seen: dict[Path, str] = {}
    for path, out in zip(inputs, outputs, strict=True):
        if out in seen:
            raise BrdfInputError(f"{seen[out]} and {path} would both write {out}; give them different names")
        seen[out] = path
    return [output_file(out, "-o") if out.parent.exists() else out for out in outputs]


def default_name(path: str, model) -> str:
    """``<stem>.<model>[.<option>-<value>…].json`` with the options that differ from their defaults:
    ``tape.lafortune.lobes-2.json``, ``oak.cook-torrance.fresnel-conductor.json``, ``oak.ward.json``."""
    from ..physics.models.registry import chosen_options
    from ..physics.models.specs import shown_value

    options = "".join(f".{key}-{shown_value(key, value)}" for key, value in chosen_options(model).items())
    from .files import stem

    return f"{stem(path)}.{model.name}{options}.json"


def summary_rows(inputs: list[str], results, outputs, problems: list[str | None]) -> list[dict]:
    """What :func:`summary` says of each fit, as plain data (``--json``): ``samples``, ``result`` (the file written;
    None: not written), ``model``, ``model_options``, ``cost``, ``rmse``, ``n_steps``, ``converged``, ``warnings`` and
    ``error`` (why nothing was written; None)."""
    return [
        {
            "samples": path,
            "result": None if output is None else str(output),
            "model": result.model,
            "model_options": dict(result.model_options),
            "cost": result.cost if problem is None else None,
            "rmse": result.rmse if problem is None else None,
            "n_steps": result.n_steps,
            "converged": result.converged,
            "warnings": list(result.warnings),
            "error": problem,
        }
        for path, result, output, problem in zip(inputs, results, outputs, problems, strict=True)
    ]


def summary(inputs: list[str], results, outputs) -> str:
    """One line per input: steps, cost, rmse, convergence and the file written (None: not written)."""
    width = max(len(path) for path in inputs)
    lines = [f"{'samples'.ljust(width)}  steps  {'cost':>12}  {'rmse (1/sr)':>12}  status     result"]
    for path, result, output in zip(inputs, results, outputs, strict=True):
        status = "converged" if result.converged else "NOT conv."
        output = "(not written)" if output is None else output
        lines.append(
            f"{path.ljust(width)}  {result.n_steps:5d}  {result.cost:12.6g}  {result.rmse:12.4g}  {status:9s}  {output}"
        )
    return "\n".join(lines)
