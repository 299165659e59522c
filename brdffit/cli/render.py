"""``brdffit render RESULT.json -o sphere.png``: a sphere with the fit's Mitsuba 3 BSDF, rendered by Mitsuba; ``brdffit
render BSDF.xml`` renders an exported BSDF file as it is, without fitting anything again."""

import argparse
from pathlib import Path

from . import EXIT_OK
from .arguments import fit_file_files, fit_of, output_file
from .files import Files


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "result",
        metavar="RESULT.json",
        help="a result file of brdffit fit, or a comparison file of brdffit compare -o (its best model), or a Mitsuba"
        " BSDF file (.xml, brdffit export --to mitsuba's): rendered as it is, nothing fitted again",
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
    """What ``render`` reads and writes (:func:`~brdffit.cli.arguments.fit_file_files`; a BSDF file and the image)."""
    if _is_bsdf_file(args.result):
        return Files.of(inputs={"RESULT.json": args.result, "--samples": args.samples}, outputs={"-o": _output(args)})
    return fit_file_files(args, _output(args))


def _is_bsdf_file(path: str) -> bool:
    """Whether RESULT names a Mitsuba BSDF file (by its suffix, ``export.mitsuba_render.XML_SUFFIX``)."""
    return Path(path).suffix.lower() == ".xml"


def _output(args: argparse.Namespace) -> str:
    """The image: ``-o``, by default RESULT's stem + ``.mitsuba.png``, here."""
    from .files import stem

    return args.output or f"{stem(args.result)}.mitsuba.png"


def run(args: argparse.Namespace) -> int:
    from ..checks import whole_number
    from ..errors import Argument, BrdfInputError
    from ..export.mitsuba_render import EXPOSURE, IMAGE_SUFFIXES, checked_exposure, mitsuba, render_sphere

    whole_number("size", args.size, 16, 4096)
    whole_number("spp", args.spp, 1)
    exposure = EXPOSURE if args.exposure is None else checked_exposure(args.exposure)
    output = _output(args)
    if output != "-" and Path(output).suffix.lower() not in IMAGE_SUFFIXES:  # -: a PNG on standard output
        raise BrdfInputError(Argument("output", output), ": the image must end in .png or .exr")
    if _is_bsdf_file(args.result):
        return _run_bsdf_file(args, output, exposure)
    from .files import input_path

    result = fit_of(args)
    path = output_file(output, "-o", ".png")
    mitsuba()  # before the export's fit: say at once when Mitsuba is missing
    from .._programs.cache import enable_compilation_cache

    enable_compilation_cache()  # the export's programs, compiled once per machine (as export's)
    samples = input_path(args.samples)  # None: not given
    exported = render_sphere(result, path, size=args.size, spp=args.spp, exposure=exposure, samples=samples)
    print(f"wrote {output if output == '-' else path}: Mitsuba 3 rendered a sphere of {args.result}")
    for line in exported.comment_lines()[1:]:
        print(f"  {line}")
    return EXIT_OK


def _run_bsdf_file(args: argparse.Namespace, output: str, exposure) -> int:
    """``render BSDF.xml``: the file's BSDF rendered as it is (``export.mitsuba_render.render_bsdf_file``)."""
    from ..errors import BrdfInputError
    from ..export.mitsuba_render import mitsuba, render_bsdf_file

    if args.samples is not None:
        raise BrdfInputError(
            f"--samples {args.samples}: the render beside the data needs the fit, which {args.result} does not hold;"
            " give the result file it was exported from"
        )
    if not Path(args.result).is_file():
        raise BrdfInputError(f"{args.result}: no such file")
    path = output_file(output, "-o", ".png")
    mitsuba()
    lines = render_bsdf_file(args.result, path, size=args.size, spp=args.spp, exposure=exposure)
    print(f"wrote {output if output == '-' else path}: Mitsuba 3 rendered a sphere of {args.result}, as the file is")
    for line in lines[1:]:  # the first says what made it; the rest how far it lies
        print(f"  {line}")
    return EXIT_OK
