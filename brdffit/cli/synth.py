"""``brdffit synth``: synthetic samples of a model on a measurement geometry, with noise (``data_synth``)."""

import argparse
import inspect

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import add_model_options, json_argument, json_file, model_files, model_options, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    from brdffit.data_synth import GEOMETRIES, NOISE_KINDS

    add_model_options(parser, None)
    parser.add_argument(
        "--params", required=True, metavar="PARAMS", help="parameters: JSON file (a result file works) or inline JSON"
    )
    parser.add_argument("--geometry", metavar="NAME", help=f"{', '.join(GEOMETRIES)} (default hemisphere)")
    parser.add_argument(
        "--directions",
        metavar="CSV",
        help="the pairs of a directions file (theta_i,phi_i,theta_o,phi_o in degrees; brdffit basis directions writes"
        " one) instead of --geometry",
    )
    parser.add_argument(
        "--n-incident",
        type=int,
        metavar="N",
        help="light zenith angles (hemisphere, in-plane, near-specular; default 8)",
    )
    parser.add_argument("--n-theta", type=int, metavar="N", help="viewer zenith angles (hemisphere 36, in-plane 90)")
    parser.add_argument("--n-phi", type=int, metavar="N", help="viewer azimuths (hemisphere; default 36)")
    parser.add_argument(
        "--n-samples", type=int, metavar="N", help="sample count (random, near-specular; default 10000)"
    )
    parser.add_argument(
        "--spread", type=float, metavar="DEG", help="near-specular: widest angle from the mirror direction (default 10)"
    )
    parser.add_argument(
        "--noise",
        type=float,
        default=0.0,
        metavar="LEVEL",
        help="noise level: 0.01 is 1%% for multiplicative noise (default 0)",
    )
    parser.add_argument(
        "--noise-kind",
        default=NOISE_KINDS[0],
        metavar="KIND",
        help=f"{' or '.join(NOISE_KINDS)} (LEVEL in 1/sr for additive; default {NOISE_KINDS[0]})",
    )
    parser.add_argument("--sigma-column", action="store_true", help="write the noise's 1-σ as sigma columns")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and of random geometries (default 0)")
    parser.add_argument("-o", "--output", required=True, metavar="FILE", help="samples file to write")


def files(args: argparse.Namespace) -> Files:
    """What ``synth`` reads (``--params``, ``--directions``, the basis the model names) and writes (``-o``)."""
    model, _, _ = _model_and_params(args)
    return Files.of(
        inputs={
            "--params": json_file(args.params),
            "--directions": args.directions,
            "--basis": model_files(model.model_options),
        },
        outputs={"-o": args.output},
    )


def run(args: argparse.Namespace) -> int:
    from brdffit.data_synth import GEOMETRIES, synthesize

    from .._programs.cache import enable_compilation_cache
    from ..data.load import save_samples

    enable_compilation_cache()
    model, params, channels = _model_and_params(args)
    given = {
        name: getattr(args, name)
        for name in ("n_incident", "n_theta", "n_phi", "n_samples", "spread")
        if getattr(args, name) is not None
    }
    if args.directions is not None:  # the file gives the pairs; --seed still draws the noise
        from ..datadriven.directions import read_directions

        if given or args.geometry is not None:
            what = "geometry" if args.geometry is not None else next(iter(given)).replace("_", "-")
            raise BrdfInputError(f"--{what} does not apply to --directions (the file gives the pairs)")
        output = output_file(args.output, "-o", ".csv")
        from .files import input_path

        wi, wo = read_directions(input_path(args.directions))
    else:
        geometry = "hemisphere" if args.geometry is None else args.geometry
        if geometry not in GEOMETRIES:
            raise BrdfInputError(f"--geometry {geometry!r} is not known; choose one of: {', '.join(GEOMETRIES)}")
        make_geometry = GEOMETRIES[geometry]
        accepted = inspect.signature(make_geometry).parameters
        for name in given:
            if name not in accepted:
                raise BrdfInputError(f"--{name.replace('_', '-')} does not apply to --geometry {geometry}")
        if "seed" in accepted:
            given["seed"] = args.seed
        output = output_file(args.output, "-o", ".csv")
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
        channels=channels,
        **model.model_options,
    )
    save_samples(samples, output)
    shown = "-" if args.output == "-" else output
    print(f"wrote {samples.n_samples} samples × {samples.n_channels} channel(s) of {model.name} to {shown}")
    return EXIT_OK


def _model_and_params(args: argparse.Namespace):
    """The model, its parameters and the channel names (None: named by their count), from ``--model`` and
    ``--params`` (a parameter dictionary, or a result file, whose channel names are kept)."""
    from ..physics.models.registry import model_for

    params = json_argument(args.params, "--params")
    model_name, options, channels = args.model, model_options(args), None
    if isinstance(params, dict) and "params" in params and "model" in params:  # a result file
        if args.model not in (None, params["model"]):
            raise BrdfInputError(f"--params {args.params} holds a {params['model']} result, not --model {args.model}")
        model_name = params["model"]
        options = {**params.get("model_options", {}), **{k: v for k, v in options.items() if v is not None}}
        channels = tuple(params["channels"]) if isinstance(params.get("channels"), list) else None
        params = params["params"]
    if model_name is None:
        raise BrdfInputError("--model is required unless --params is a result file")
    return model_for(model_name, params, **options), params, channels
