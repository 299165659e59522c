"""``brdffit render RESULT.json -o sphere.png``: a sphere with the fit's Mitsuba 3 BSDF, rendered by Mitsuba."""

import argparse
from pathlib import Path

from . import EXIT_OK
from .arguments import fit_file, fit_file_files, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "result",
        metavar="RESULT.json",
        help="a result file of brdffit fit, or a comparison file of brdffit compare -o (its best model)",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="the image: .png, or .exr for the linear radiance (default: RESULT's stem + .mitsuba.png, here)",
    )
    parser.add_argument(
        "--samples",
        metavar="DATA",
        help="the data the fit was made from: the PNG shows the render beside the fit's sphere and the data's own, at"
        " one exposure, and how far the export lies from the data is printed",
    )
    parser.add_argument("--size", type=int, default=256, metavar="PIXELS", help="image width and height (default 256)")
    parser.add_argument("--spp", type=int, default=64, metavar="N", help="samples per pixel (default 64)")
    parser.add_argument(
        "--exposure",
        default=None,
        metavar="X",
        help="the factor radiance is multiplied by for display (default π, the same for every image, so that renders"
        " compare: a white Lambertian surface facing the light shows white), or 'auto': each image its own",
    )


def files(args: argparse.Namespace) -> Files:
    """What ``render`` reads and writes (:func:`~brdffit.cli.arguments.fit_file_files`)."""
    return fit_file_files(args, _output(args))


def _output(args: argparse.Namespace) -> str:
    """The image: ``-o``, by default RESULT's stem + ``.mitsuba.png``, here."""
    return args.output or f"{Path(args.result).stem}.mitsuba.png"


def run(args: argparse.Namespace) -> int:
    from ..checks import whole_number
    from ..errors import Argument, BrdfInputError
    from ..export.mitsuba_render import EXPOSURE, IMAGE_SUFFIXES, checked_exposure, mitsuba, render_sphere

    whole_number("size", args.size, 16, 4096)
    whole_number("spp", args.spp, 1)
    exposure = EXPOSURE if args.exposure is None else checked_exposure(args.exposure)
    output = _output(args)
    if Path(output).suffix.lower() not in IMAGE_SUFFIXES:
        raise BrdfInputError(Argument("output", output), ": the image must end in .png or .exr")
    result = fit_file(args.result)
    path = output_file(output, "-o")
    mitsuba()  # before the export's fit: say at once when Mitsuba is missing
    exported = render_sphere(result, path, size=args.size, spp=args.spp, exposure=exposure, samples=args.samples)
    print(f"wrote {path}: Mitsuba 3 rendered a sphere of {args.result}")
    for line in exported.comment_lines()[1:]:
        print(f"  {line}")
    return EXIT_OK
