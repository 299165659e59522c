"""The ``brdffit`` command line (SPEC section 7).

Exit status: 0 success; 1 a fit did not converge (its result is still
written, with ``converged: false``); 2 bad input or usage, reported in one
line on stderr, with nothing written.
"""

import argparse
import inspect
import json
import os
import sys
from pathlib import Path
from typing import Any

from .._version import __version__
from ..errors import BrdfInputError

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_BAD_INPUT = 0, 1, 2


class _UsageError(Exception):
    """An argparse usage error, reported like any other bad input."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        raise _UsageError(f"{message} (see {self.prog} --help)")


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``) and return the exit status."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command in (_fit, _synth, _convert):
            from ..cache import enable_compilation_cache

            enable_compilation_cache()
        return args.command(args)
    except (BrdfInputError, _UsageError) as error:
        print(f"brdffit: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemExit as exit_:  # --help and --version
        return exit_.code if isinstance(exit_.code, int) else EXIT_OK


def run() -> None:
    """Console-script entry point."""
    try:
        status = main()
        sys.stdout.flush()
    except BrokenPipeError:
        # The reader went away (`brdffit fit … | head`): files are already written; say nothing more.
        # Python docs, "Note on SIGPIPE": point stdout at devnull so the final flush cannot fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = EXIT_OK
    sys.exit(status)


# ------------------------------------------------------------------ the parser
def _build_parser() -> argparse.ArgumentParser:
    from ..data.samples import ANGLE_UNITS, QUANTITIES
    from ..fitting.losses import LOSSES
    from ..physics.models import MODELS

    parser = _Parser(
        prog="brdffit",
        description="Fit analytic BRDF models to measured reflectance samples.",
        allow_abbrev=False,
    )
    parser.add_argument("--version", action="version", version=f"brdffit {__version__}")
    commands = parser.add_subparsers(title="commands", metavar="COMMAND", required=True)

    def model_options(command: argparse.ArgumentParser, default: str | None) -> None:
        default_text = (
            f" (default {default})" if default else " (default: the model of a result file given as --params)"
        )
        command.add_argument(
            "--model", default=default, metavar="NAME", help=f"one of: {', '.join(MODELS)}{default_text}"
        )
        command.add_argument(
            "--fresnel", metavar="KIND", help="cook-torrance: schlick (default), dielectric, conductor, none"
        )
        command.add_argument("--lobes", type=int, metavar="K", help="lafortune: number of lobes (default 1)")

    def loading_options(command: argparse.ArgumentParser) -> None:
        reading = command.add_argument_group("reading the samples")
        reading.add_argument(
            "--format", metavar="NAME", help="csv, merl, alta or astm (default: from the extension and first lines)"
        )
        reading.add_argument(
            "--quantity",
            default="brdf",
            metavar="Q",
            help=f"what the values are: {', '.join(QUANTITIES)} (default brdf)",
        )
        reading.add_argument(
            "--angles",
            default="degrees",
            metavar="UNIT",
            help=f"CSV angle columns in {' or '.join(ANGLE_UNITS)} (default degrees)",
        )
        reading.add_argument(
            "--spectral-to",
            default="keep",
            metavar="T",
            help="value columns named by wavelength (nm): xyz, rgb (linear sRGB) or keep every band (default keep)",
        )
        reading.add_argument("--illuminant", default="D65", metavar="NAME", help="for --spectral-to (default D65)")
        reading.add_argument(
            "--observer",
            default="CIE 1931 2 Degree Standard Observer",
            metavar="NAME",
            help="colour-matching functions for --spectral-to (default: CIE 1931 2 Degree Standard Observer)",
        )
        reading.add_argument("--subsample", type=int, metavar="N", help="MERL: keep N samples")
        reading.add_argument(
            "--subsample-method", default="random", metavar="M", help="MERL: random (default) or stratified (over θh)"
        )

    fit = commands.add_parser("fit", help="fit a model to a samples file", allow_abbrev=False)
    fit.add_argument(
        "samples", metavar="SAMPLES", nargs="+", help="samples file(s): CSV (SPEC section 4), MERL, ALTA, ASTM"
    )
    model_options(fit, "ward")
    fit.add_argument("--loss", default="log", metavar="NAME", help=f"one of: {', '.join(LOSSES)} (default log)")
    fit.add_argument("--max-theta", type=float, metavar="DEG", help="drop samples with θi or θo above DEG degrees")
    loading_options(fit)
    fit.add_argument(
        "--start",
        metavar="PARAMS",
        help="start from these parameters (JSON file or inline JSON) instead of the data-driven starts",
    )
    fit.add_argument(
        "--starts",
        type=int,
        default=3,
        metavar="N",
        help="Levenberg-Marquardt runs from the N best grid starts (default 3)",
    )
    fit.add_argument(
        "--max-steps", type=int, default=256, metavar="N", help="most solver steps per start (default 256)"
    )
    fit.add_argument(
        "--dtype",
        default="float64",
        metavar="TYPE",
        help="float64 (default), or float32: solve in single precision, then refine in double",
    )
    fit.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="result file, or a folder (OUTDIR/) for several samples files"
        " (default: SAMPLES-stem.MODEL.json in the current folder)",
    )
    errors = fit.add_argument_group("uncertainty")
    errors.add_argument(
        "--uncertainty",
        metavar="METHOD",
        help="laplace (Gauss-Newton covariance at the optimum) or mcmc (emcee posterior)",
    )
    errors.add_argument("--walkers", type=int, metavar="N", help="mcmc: walkers (default 32)")
    errors.add_argument("--steps", type=int, metavar="N", help="mcmc: steps per walker (default 2000)")
    errors.add_argument("--burn", type=int, metavar="N", help="mcmc: steps discarded as burn-in (default 500)")
    errors.add_argument("--thin", type=int, metavar="N", help="mcmc: keep every N-th step (default 1)")
    errors.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the mcmc walkers, the start search's subset and --subsample (default 0)",
    )
    errors.add_argument("--chain", metavar="FILE", help="mcmc: save the whole chain (.npz, or .h5 with h5py)")
    errors.add_argument("--corner", metavar="FILE", help="corner plot of the posterior (.png, .pdf or .svg)")
    fit.set_defaults(command=_fit)

    synth = commands.add_parser("synth", help="write synthetic samples of a model", allow_abbrev=False)
    model_options(synth, None)
    synth.add_argument(
        "--params", required=True, metavar="PARAMS", help="parameters: JSON file (a result file works) or inline JSON"
    )
    synth.add_argument(
        "--geometry", default="hemisphere", metavar="NAME", help="hemisphere (default), in-plane, random, near-specular"
    )
    synth.add_argument(
        "--n-incident",
        type=int,
        metavar="N",
        help="light zenith angles (hemisphere, in-plane, near-specular; default 8)",
    )
    synth.add_argument("--n-theta", type=int, metavar="N", help="viewer zenith angles (hemisphere 36, in-plane 90)")
    synth.add_argument("--n-phi", type=int, metavar="N", help="viewer azimuths (hemisphere; default 36)")
    synth.add_argument("--n-samples", type=int, metavar="N", help="sample count (random, near-specular; default 10000)")
    synth.add_argument(
        "--spread", type=float, metavar="DEG", help="near-specular: widest angle from the mirror direction (default 10)"
    )
    synth.add_argument(
        "--noise",
        type=float,
        default=0.0,
        metavar="LEVEL",
        help="noise level: 0.01 is 1%% for multiplicative noise (default 0)",
    )
    synth.add_argument(
        "--noise-kind",
        default="multiplicative",
        metavar="KIND",
        help="multiplicative (default) or additive (LEVEL in 1/sr)",
    )
    synth.add_argument("--sigma-column", action="store_true", help="write the noise's 1-σ as sigma columns")
    synth.add_argument("--seed", type=int, default=0, help="seed of the noise and of random geometries (default 0)")
    synth.add_argument("-o", "--output", required=True, metavar="FILE", help="samples file to write")
    synth.set_defaults(command=_synth)

    models = commands.add_parser("models", help="list the models, their parameters and domains", allow_abbrev=False)
    models.set_defaults(command=_models)

    convert = commands.add_parser(
        "convert", help="convert samples between formats, or tabulate a fit result as a MERL file", allow_abbrev=False
    )
    convert.add_argument("input", metavar="IN", help="samples file (any format), or a result file (.json) for .binary")
    convert.add_argument(
        "output", metavar="OUT", help="the format from the extension: .csv, .dat (ALTA), .astm, .binary"
    )
    loading_options(convert)
    convert.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")
    convert.set_defaults(command=_convert)

    info = commands.add_parser("info", help="what a samples file holds: count, channels, angular coverage")
    info.add_argument("input", metavar="FILE", help="samples file (any format)")
    loading_options(info)
    info.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")
    info.set_defaults(command=_info)
    return parser


# ------------------------------------------------------------------ commands
def _fit(args: argparse.Namespace) -> int:
    from ..fitting.batch import fit_batch
    from ..fitting.losses import get_loss
    from ..physics.models import get_model

    model = get_model(args.model, fresnel=args.fresnel, lobes=args.lobes)
    get_loss(args.loss)
    mcmc = _uncertainty_options(args)
    outputs = _fit_outputs(args.samples, args.output, model.name)
    start = _json_argument(args.start, "--start") if args.start else None
    if isinstance(start, dict) and "params" in start:  # a result file
        start = start["params"]
    # Every input is read and checked before any fit runs or any file is written.
    samples = [_load(path, args) for path in args.samples]
    if mcmc is not None:
        from ..uncertainty.mcmc import check_walkers

        for one in samples:
            check_walkers(mcmc, model, one)
    results = fit_batch(
        samples,
        model,
        args.loss,
        max_theta=args.max_theta,
        start=start,
        n_starts=args.starts,
        max_steps=args.max_steps,
        dtype=args.dtype,
        seed=args.seed,
    )
    if args.uncertainty:
        results = [
            _with_uncertainty(args, result, one.within(args.max_theta), path, mcmc)
            for result, one, path in zip(results, samples, args.samples, strict=True)
        ]
    outputs[0].parent.mkdir(parents=True, exist_ok=True)
    for result, output in zip(results, outputs, strict=True):
        result.save(output)
    if args.corner:
        from ..views.corner import corner_plot

        corner_plot(results[0], args.corner)
    if len(results) == 1:
        print(results[0].table(source=args.samples[0]))
        print(f"wrote {', '.join(str(p) for p in (outputs[0], args.chain, args.corner) if p)}")
    else:
        print(_summary(args.samples, results, outputs))
    failed = [(path, result) for path, result in zip(args.samples, results, strict=True) if not result.converged]
    for path, result in failed:
        print(
            f"brdffit: warning: {path}: the fit did not converge ({result.message}); written with converged: false",
            file=sys.stderr,
        )
    return EXIT_NOT_CONVERGED if failed else EXIT_OK


def _uncertainty_options(args: argparse.Namespace):
    """The MCMC settings (None unless ``--uncertainty mcmc``), after every check of the uncertainty options."""
    from ..uncertainty.mcmc import MCMC, check_chain_path
    from ..uncertainty.methods import check_method
    from ..views.corner import check_figure_path

    method = check_method(args.uncertainty)
    given = {
        name: getattr(args, name) for name in ("walkers", "steps", "burn", "thin") if getattr(args, name) is not None
    }
    if method != "mcmc":
        for option in [*given, *(name for name in ("chain",) if getattr(args, name))]:
            raise BrdfInputError(f"--{option} applies only to --uncertainty mcmc")
    if args.corner and not method:
        raise BrdfInputError("--corner needs --uncertainty mcmc (or laplace)")
    if (args.chain or args.corner) and len(args.samples) > 1:
        raise BrdfInputError(f"--chain and --corner take one samples file; got {len(args.samples)}")
    if args.chain:
        check_chain_path(args.chain)
    if args.corner:
        check_figure_path(args.corner)
        _check_output(Path(args.corner), "--corner")
        os.environ.setdefault("MPLBACKEND", "Agg")  # files only: no window, no display needed
    return MCMC(**given, seed=args.seed) if method == "mcmc" else None


def _with_uncertainty(args: argparse.Namespace, result, samples, path: str, mcmc):
    """``result`` with its uncertainty block; the estimate's warnings printed on stderr, naming ``path``."""
    import warnings

    from ..uncertainty.methods import with_uncertainty

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = with_uncertainty(
            result, samples, args.uncertainty, mcmc=mcmc, chain=args.chain, progress=sys.stderr.isatty()
        )
    for warning in caught:
        print(f"brdffit: warning: {path}: {warning.message}", file=sys.stderr)
    return result


def _fit_outputs(inputs: list[str], output: str | None, model_name: str) -> list[Path]:
    """The result file of each input: ``-o FILE`` for one input, else ``OUTDIR/<stem>.<model>.json``.

    ``-o`` is a folder when several inputs are given, when it ends with ``/`` or
    when it is an existing folder; it is created (after every check) if missing.
    """
    as_folder = len(inputs) > 1 or (output is not None and (output.endswith(("/", os.sep)) or Path(output).is_dir()))
    if not as_folder:
        path = Path(output) if output else Path(f"{Path(inputs[0]).stem}.{model_name}.json")
        _check_output(path, "-o")
        return [path]
    folder = Path(output) if output else Path(".")
    if folder.exists() and not folder.is_dir():
        raise BrdfInputError(f"-o {output}: is a file; with several samples files give a folder (OUTDIR/)")
    if not folder.exists() and folder.suffix.lower() == ".json" and not output.endswith(("/", os.sep)):
        raise BrdfInputError(f"-o {output}: looks like a file; with several samples files give a folder (OUTDIR/)")
    existing = next((parent for parent in (folder, *folder.parents) if parent.exists()), Path("."))
    if not os.access(existing, os.W_OK):
        raise BrdfInputError(f"-o {folder}: folder {existing} is not writable")
    outputs = [folder / f"{Path(path).stem}.{model_name}.json" for path in inputs]
    seen: dict[Path, str] = {}
    for path, out in zip(inputs, outputs, strict=True):
        if out in seen:
            raise BrdfInputError(f"{seen[out]} and {path} would both write {out}; give them different names")
        seen[out] = path
    return outputs


def _summary(inputs: list[str], results, outputs) -> str:
    """One line per input: steps, cost, rmse, convergence and the file written."""
    width = max(len(path) for path in inputs)
    lines = [f"{'samples'.ljust(width)}  steps  {'cost':>12}  {'rmse (1/sr)':>12}  status     result"]
    for path, result, output in zip(inputs, results, outputs, strict=True):
        status = "converged" if result.converged else "NOT conv."
        lines.append(
            f"{path.ljust(width)}  {result.n_steps:5d}  {result.cost:12.6g}  {result.rmse:12.4g}  {status:9s}  {output}"
        )
    return "\n".join(lines)


def _synth(args: argparse.Namespace) -> int:
    from data_synth import GEOMETRIES, synthesize

    from ..data.samples import save_samples
    from ..physics.models import get_model

    params = _json_argument(args.params, "--params")
    model_name, options = args.model, {"fresnel": args.fresnel, "lobes": args.lobes}
    if isinstance(params, dict) and "params" in params and "model" in params:  # a result file
        if args.model not in (None, params["model"]):
            raise BrdfInputError(f"--params {args.params} holds a {params['model']} result, not --model {args.model}")
        model_name = params["model"]
        options = {**params.get("model_options", {}), **{k: v for k, v in options.items() if v is not None}}
        params = params["params"]
    if model_name is None:
        raise BrdfInputError("--model is required unless --params is a result file")
    model = get_model(model_name, **options)
    if args.geometry not in GEOMETRIES:
        raise BrdfInputError(f"--geometry {args.geometry!r} is not known; choose one of: {', '.join(GEOMETRIES)}")
    make_geometry = GEOMETRIES[args.geometry]
    accepted = inspect.signature(make_geometry).parameters
    given = {
        name: getattr(args, name)
        for name in ("n_incident", "n_theta", "n_phi", "n_samples", "spread")
        if getattr(args, name) is not None
    }
    for name in given:
        if name not in accepted:
            raise BrdfInputError(f"--{name.replace('_', '-')} does not apply to --geometry {args.geometry}")
    if "seed" in accepted:
        given["seed"] = args.seed
    output = Path(args.output)
    _check_output(output, "-o")
    wi, wo = make_geometry(**given)
    samples = synthesize(
        model.name,
        params,
        wi,
        wo,
        noise=args.noise,
        noise_kind=args.noise_kind,
        seed=args.seed,
        with_sigma=args.sigma_column,
        **model.model_options,
    )
    save_samples(samples, output)
    print(f"wrote {samples.n_samples} samples × {samples.n_channels} channel(s) of {model.name} to {output}")
    return EXIT_OK


def _models(args: argparse.Namespace) -> int:
    from ..physics.models import MODELS, get_model, model_option_names

    for name in MODELS:
        model = get_model(name)
        summary = model.summary + (f": {model.lobe.summary}" if model.lobe else "")
        print(f"{name}\n  {summary}")
        options = model_option_names(name)
        if options:
            print(f"  options: {', '.join('--' + option for option in options)}")
        if name == "cook-torrance":
            from ..physics.models.cook_torrance import FRESNEL_PARAMETERS

            for fresnel in FRESNEL_PARAMETERS:
                lines = get_model(name, fresnel=fresnel).describe_parameters()
                print(f"  --fresnel {fresnel}: " + "; ".join(lines))
        else:
            print("  parameters: " + "; ".join(model.describe_parameters()))
    return EXIT_OK


def _convert(args: argparse.Namespace) -> int:
    from ..data.load import WRITABLE

    output = Path(args.output)
    kind = WRITABLE.get(output.suffix.lower())
    if kind is None:
        choices = ", ".join(f"{suffix} ({name})" for suffix, name in WRITABLE.items())
        raise BrdfInputError(f"{output}: unknown output format; give one of: {choices}")
    _check_output(output, "OUT")
    if kind == "merl":
        if Path(args.input).suffix.lower() != ".json":
            raise BrdfInputError(
                f"{output}: a MERL file tabulates a whole BRDF; convert a fit result (.json) to .binary, e.g."
                " brdffit convert fit.json out.binary"
            )
        from ..data.merl import write_merl
        from ..fitting.results import load_result

        result = load_result(args.input)
        write_merl(output, result.model, result.params, **result.model_options)
        print(f"wrote {output}: {result.model} tabulated on MERL's 90 × 90 × 180 grid")
        return EXIT_OK
    if Path(args.input).suffix.lower() == ".json":
        raise BrdfInputError(f"{args.input}: a result file converts only to a MERL file (.binary), not to {kind}")
    samples = _load(args.input, args)
    if kind != "csv" and (samples.sigma is not None or samples.weight is not None):
        print(
            f"brdffit: warning: {output}: {kind} files hold no sigma or weight columns; they are not written",
            file=sys.stderr,
        )
    if kind == "csv":
        from ..data.samples import save_samples

        save_samples(samples, output)
    elif kind == "alta":
        from ..data.alta import write_alta

        write_alta(samples, output)
    else:
        from ..data.astm import write_astm

        write_astm(samples, output)
    print(f"wrote {samples.n_samples} samples × {samples.n_channels} channel(s) to {output} ({kind})")
    return EXIT_OK


def _info(args: argparse.Namespace) -> int:
    from ..data.load import detect_format
    from ..data.summary import describe

    samples = _load(args.input, args)
    print(describe(samples, detect_format(Path(args.input), args.format)))
    return EXIT_OK


def _load(path: str, args: argparse.Namespace):
    """``path`` read with the loading options of ``args``."""
    from ..data.samples import load_samples

    return load_samples(
        path,
        format=args.format,
        angles=args.angles,
        quantity=args.quantity,
        spectral_to=args.spectral_to,
        illuminant=args.illuminant,
        observer=args.observer,
        subsample=args.subsample,
        subsample_method=args.subsample_method,
        seed=args.seed,
    )


# ------------------------------------------------------------------ helpers
def _json_argument(value: str, option: str) -> Any:
    """Inline JSON (starting with ``{``) or the content of the JSON file ``value``."""
    if value.lstrip().startswith("{"):
        text, where = value, f"{option} (inline JSON)"
    else:
        where = f"{option} {value}"
        try:
            text = Path(value).read_text(encoding="utf-8")
        except FileNotFoundError:
            raise BrdfInputError(f"{where}: no such file") from None
        except (OSError, UnicodeDecodeError) as error:
            raise BrdfInputError(f"{where}: cannot be read ({error})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise BrdfInputError(f"{where}: not valid JSON ({error})") from None


def _check_output(path: Path, option: str) -> None:
    """Fail before any work if ``path`` cannot be written."""
    folder = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise BrdfInputError(f"{option} {path}: is a folder; give a file name")
    if not folder.is_dir():
        raise BrdfInputError(f"{option} {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise BrdfInputError(f"{option} {path}: folder {folder} is not writable")
