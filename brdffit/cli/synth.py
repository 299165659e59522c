"""``brdffit synth``: synthetic samples of a model on a measurement geometry, with noise (``data_synth``); ``brdffit
synth capture OUT/``: a synthetic capture of a spatially varying material (``data_synth/capture.py``)."""

import argparse
import inspect
from pathlib import Path

from ..errors import BrdfInputError
from . import EXIT_OK
from .arguments import add_model_options, json_argument, json_file, model_files, model_options, output_file, quiet
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    from brdffit.data_synth import GEOMETRIES, NOISE_KINDS

    add_model_options(parser, None)
    parser.add_argument(
        "--params", metavar="PARAMS", help="parameters: JSON file (a result file works) or inline JSON (required)"
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
    parser.add_argument("-o", "--output", metavar="FILE", help="samples file to write (required)")
    actions = parser.add_subparsers(title="actions", metavar="[capture]", dest="action")
    capture = actions.add_parser(
        "capture",
        help="a capture of a spatially varying material made from known maps (brdffit svbrdf fit reads it)",
        allow_abbrev=False,
    )
    capture.add_argument("folder", metavar="OUT", help="folder to write capture.json, the images and truth.npz into")
    quiet(capture)
    add_model_options(capture, "ward")
    capture.add_argument(
        "--params",
        action="append",
        metavar="PARAMS",
        help="the two materials the maps blend, given twice (JSON files or inline JSON; default: the model's built-in"
        " pair, for lambert, ward and cook-torrance)",
    )
    capture.add_argument("--texels", default="32,32", metavar="ROWS,COLUMNS", help="the texel grid (default 32,32)")
    capture.add_argument(
        "--size", type=float, default=100.0, metavar="MM", help="the square sample's side (default 100)"
    )
    capture.add_argument("--images", type=int, default=32, metavar="N", help="photographs, one light each (default 32)")
    capture.add_argument("--noise", type=float, default=0.01, metavar="LEVEL", help="multiplicative (default 0.01)")
    capture.add_argument("--seed", type=int, default=0, help="seed of the noise (default 0)")
    capture.add_argument("--format", default="exr", metavar="FORMAT", help="the images' format: exr (default) or npy")


def files(args: argparse.Namespace) -> Files:
    """What ``synth`` reads (``--params``, ``--directions``, the basis the model names) and writes (``-o``); what
    ``synth capture`` reads (``--params``) and writes (``capture.json`` and ``truth.npz`` in OUT)."""
    if args.action == "capture":
        folder = Path(args.folder)
        return Files.of(
            inputs={
                "--params": [json_file(value) for value in args.params or []],
                "--basis": model_files(model_options(args)),
            },
            outputs={"OUT": [args.folder, folder / "capture.json", folder / "truth.npz"]},
        )
    if args.params is None or args.output is None:
        raise BrdfInputError(
            f"{'--params' if args.params is None else '-o'} is required (or: brdffit synth capture OUT)"
        )
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
    if args.action == "capture":
        return _capture(args)
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


def _capture(args: argparse.Namespace) -> int:
    from brdffit.data_synth.capture import FORMATS, synth_capture

    from .._programs.cache import enable_compilation_cache

    enable_compilation_cache()
    try:
        shape = tuple(int(part) for part in args.texels.split(","))
    except ValueError:
        shape = ()
    if len(shape) != 2 or min(shape) < 1:
        raise BrdfInputError(f"--texels {args.texels}: give ROWS,COLUMNS, two whole numbers ≥ 1")
    if args.format not in FORMATS:
        raise BrdfInputError(f"--format {args.format}: use {' or '.join(FORMATS)}")
    if args.images < 1 or not args.size > 0 or not args.noise >= 0:
        raise BrdfInputError("--images must be ≥ 1, --size > 0 and --noise ≥ 0")
    given = args.params or []
    if len(given) not in (0, 2):
        raise BrdfInputError(f"--params given {len(given)} time(s): give the two materials the maps blend, or none")
    materials = [json_argument(value, "--params") for value in given] or [None, None]
    folder = Path(args.folder)
    if folder.exists() and not folder.is_dir():
        raise BrdfInputError(f"OUT {args.folder}: is a file; give a folder")
    if folder.is_dir() and any(folder.iterdir()):
        raise BrdfInputError(
            f"OUT {args.folder}: is not empty; give a new or empty folder (a capture's files would mix)"
        )
    options = {name: value for name, value in model_options(args).items() if value is not None}
    synth_capture(
        folder, args.model, *materials, shape=shape, size_mm=args.size, n_images=args.images, noise=args.noise,
        seed=args.seed, image_format=args.format, **options,
    )  # fmt: skip
    print(f"wrote {args.folder}/: a capture of {shape[0]} × {shape[1]} texels, {args.images} {args.format} images"
          f" of {args.model} maps, and their truth (truth.npz)")  # fmt: skip
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
