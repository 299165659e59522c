"""``brdffit svbrdf``: a capture of a spatially varying material fitted texel by texel into maps, and relit.

``svbrdf fit CAPTURE --model M -o maps/``: one fit per texel (``svbrdf/texel_fits.py``), the maps written into the
folder (``params.npz``, ``maps.json``, ``textures/``; ``svbrdf/maps.py``). ``svbrdf render maps/ --light X,Y,Z
--camera X,Y,Z -o image.exr``: the image those maps predict (``svbrdf/relight.py``).
"""

import argparse
import contextlib
import sys
from pathlib import Path

from ..errors import BrdfInputError
from . import EXIT_NOT_CONVERGED, EXIT_OK
from .arguments import (
    add_holding_options,
    add_model_options,
    cluster_client,
    holding_arguments,
    model_files,
    model_options,
    output_file,
    quiet,
)
from .files import Files

#: The images ``svbrdf render`` writes, by suffix.
RENDER_SUFFIXES = (".exr", ".png", ".npy")


def configure(parser: argparse.ArgumentParser) -> None:
    from ..fitting.objective.losses import LOSSES
    from ..fitting.options import MAX_STEPS, N_STARTS

    actions = parser.add_subparsers(title="actions", metavar="ACTION", required=True)
    fit = actions.add_parser(
        "fit", help="fit a model to every texel of a capture; write its parameter maps", allow_abbrev=False
    )
    fit.add_argument("capture", metavar="CAPTURE", help="capture folder, or its capture.json")
    quiet(fit)
    add_model_options(fit, "ward")
    fit.add_argument(
        "--loss",
        default="relative",
        metavar="NAME",
        help=f"one of: {', '.join(LOSSES)} (default relative: a photograph's noise grows with its signal)",
    )
    add_holding_options(fit)
    fit.add_argument(
        "--starts", type=int, default=N_STARTS, metavar="N", help=f"runs per texel from the N best grid starts"
        f" (default {N_STARTS})",
    )  # fmt: skip
    fit.add_argument(
        "--max-steps",
        type=int,
        default=MAX_STEPS,
        metavar="N",
        help=f"most solver steps per start (default {MAX_STEPS})",
    )
    fit.add_argument("--seed", type=int, default=0, help="seed of the start search's subset (default 0)")
    fit.add_argument(
        "--uncertainty", metavar="METHOD", help="laplace: a standard-error map per parameter (<name>_stderr)"
    )
    fit.add_argument(
        "--smoothness",
        type=float,
        metavar="TAU",
        help="draw neighbouring texels' shape parameters together: TAU is how far one typically differs from a"
        " neighbour's, in its fit coordinate (0.1 on a roughness's logarithm: 10%%); default: each texel its own",
    )
    fit.add_argument(
        "--threads", type=int, metavar="N", help="fit N batches of texels at once (default: one per CPU core)"
    )
    fit.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted fit into the same -o folder: the tiles it finished are kept",
    )
    fit.add_argument("--no-textures", action="store_true", help="write params.npz and maps.json alone")
    spread = fit.add_argument_group("cluster (pip install 'brdffit[cluster]')").add_mutually_exclusive_group()
    spread.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="fit the tiles on the Dask cluster whose scheduler is at ADDRESS (its workers read the photographs)",
    )
    spread.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="fit the tiles on a local Dask cluster of N worker processes (each reads the photographs)",
    )
    fit.add_argument("-o", "--output", required=True, metavar="MAPS", help="folder to write the maps into")
    fit.set_defaults(action=_fit)
    render = actions.add_parser(
        "render", help="the image fitted maps predict for a light and a camera", allow_abbrev=False
    )
    render.add_argument("maps", metavar="MAPS", help="maps folder (from brdffit svbrdf fit)")
    quiet(render)
    render.add_argument("--light", required=True, metavar="X,Y,Z", help="the point light's position in mm")
    render.add_argument("--camera", required=True, metavar="X,Y,Z", help="the camera's position in mm")
    render.add_argument(
        "--intensity",
        default="1",
        metavar="I[,I…]",
        help="the light's radiant intensity, or one per channel (default 1)",
    )
    render.add_argument(
        "--exposure",
        type=float,
        metavar="E",
        help="a .png's factor on radiance before sRGB encoding (default π·d²/I, d the light's distance from the"
        " sample's centre: a white diffuse surface facing the light renders white; it depends on the light alone,"
        " so two maps' renders compare; .exr and .npy hold the radiance itself)",
    )
    render.add_argument("-o", "--output", required=True, metavar="IMAGE", help="image to write: .exr, .png or .npy")
    render.set_defaults(action=_render)


def files(args: argparse.Namespace) -> Files:
    """What ``svbrdf fit`` reads (``capture.json`` and every image it names) and writes (the maps' files in ``-o``);
    what ``svbrdf render`` reads (the maps) and writes (``-o``)."""
    if args.action is _render:
        maps = _maps_folder(args.maps)  # every file in it: a render never replaces a map's own texture
        inside = [path for path in maps.rglob("*") if path.is_file()] if maps.is_dir() else []
        return Files.of(inputs={"MAPS": [args.maps, maps / "maps.json", *inside]}, outputs={"-o": args.output})
    from ..svbrdf.capture import capture_file, read_capture

    capture = read_capture(args.capture)
    images = [shot.file for shot in capture.shots] + [capture.mask, capture.normal_map]
    folder = Path(args.output)
    written = [args.output, folder / "params.npz", folder / "maps.json"]
    file = capture_file(args.capture)  # the capture's folder too: the maps are not written among the photographs
    return Files.of(
        inputs={"CAPTURE": [file.parent, file, *images], "--basis": model_files(model_options(args))},
        outputs={"-o": written},
    )


def run(args: argparse.Namespace) -> int:
    return args.action(args)


def _fit(args: argparse.Namespace) -> int:
    from .._programs.cache import enable_compilation_cache
    from ..physics.models.registry import get_model
    from ..svbrdf import fit, read_capture

    enable_compilation_cache()
    options = {name: value for name, value in model_options(args).items() if value is not None}
    get_model(args.model, **options)
    output = _output_folder(args.output)
    capture = read_capture(args.capture)
    held = holding_arguments(args)
    for option, value in (("--workers", args.workers), ("--threads", args.threads)):
        if value is not None and value < 1:
            raise BrdfInputError(f"{option} must be 1 or more, got {value}")
    with contextlib.ExitStack() as stack:
        client = None
        if args.scheduler or args.workers:
            client = stack.enter_context(cluster_client(args.scheduler, args.workers))
        maps = fit(
            capture,
            args.model,
            args.loss,
            output=output,
            resume=args.resume,
            progress=False if args.quiet else None,
            threads=args.threads,
            n_starts=args.starts,
            max_steps=args.max_steps,
            seed=args.seed,
            uncertainty=args.uncertainty,
            smoothness=args.smoothness,
            textures=not args.no_textures,
            fixed=held["fixed"],
            bounds=held["bounds"],
            client=client,
            **options,
        )
    summary = maps.summary()
    rows, columns = maps.shape
    median = summary["median_rmse"]
    print(
        f"wrote {output}/: {maps.model} maps of {rows} × {columns} texels from {len(capture.shots)} images"
        f" ({summary['fitted']:,} fitted, {summary['converged']:,} converged"
        + (f"; median rmse {median:.3g}, in the {maps.loss} loss's units" if median is not None else "")
        + ")"
    )
    print(_table(maps))
    if maps.smoothing:
        said = maps.smoothing
        print(
            f"  smoothness prior τ = {said['tau']:g} (λ = {said['lambda']:.3g}): {said['passes']} pass(es), the last"
            f" moving a shape coordinate by at most {said['largest_change']:.2g}"
        )
    glb, mitsuba = maps.exports.get("glb") or {}, maps.exports.get("mitsuba") or {}
    if glb.get("file"):
        print(f"  {glb['file']}: the maps on a quad for glTF viewers" + "".join(f"; {n}" for n in glb["notes"]))
    if mitsuba.get("folder"):
        print(
            f"  {mitsuba['folder']}/: bsdf.xml with {len(mitsuba['textured'])} bitmap texture(s), scene.xml"
            + "".join(f"; {note}" for note in mitsuba.get("notes", []))
        )
    for what, said in (("material.glb", glb), ("Mitsuba scene", mitsuba)):
        if said.get("not_written"):
            print(f"brdffit: note: no {what}: {said['not_written']}", file=sys.stderr)
    for note in [*maps.notes, *([maps.caveats()] if maps.caveats() else [])]:
        print(f"brdffit: warning: {note}", file=sys.stderr)
    return EXIT_OK if summary["converged"] == summary["fitted"] else EXIT_NOT_CONVERGED


def _table(maps) -> str:
    """Each parameter's median and 5th–95th percentiles over the fitted texels, per channel."""
    import numpy as np

    fitted = maps.fitted
    lines = [f"{'parameter':<22} {'median':>10} {'5%':>10} {'95%':>10}"]
    for name, array in maps.params.items():
        values = array[fitted]
        columns = [values] if values.ndim == 1 else [values[:, c] for c in range(values.shape[1])]
        for channel, column in zip(maps.channels if values.ndim > 1 else [""], columns, strict=False):
            label = f"{name}[{channel}]" if channel else name
            low, middle, high = np.percentile(column, [5, 50, 95]) if column.size else (np.nan,) * 3
            lines.append(f"{label:<22} {middle:>10.4g} {low:>10.4g} {high:>10.4g}")
    return "\n".join(lines)


def _output_folder(value: str) -> Path:
    """The maps folder ``-o`` names: an existing folder, or one to make in an existing, writable folder."""
    import os

    path = Path(value)
    if value == "-":
        raise BrdfInputError("-o -: maps are a folder of files; give a folder name (maps/)")
    if path.exists() and not path.is_dir():
        raise BrdfInputError(f"-o {value}: is a file; give a folder to write the maps into")
    parent = path if path.is_dir() else path.parent
    if not parent.is_dir():
        raise BrdfInputError(f"-o {value}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise BrdfInputError(f"-o {value}: folder {parent} is not writable")
    return path


def _maps_folder(value: str) -> Path:
    """The maps folder ``MAPS`` names: the folder, or its ``maps.json``."""
    path = Path(value)
    return path.parent if path.name == "maps.json" and path.is_file() else path


def _render(args: argparse.Namespace) -> int:
    import numpy as np

    from ..svbrdf import read_maps, render
    from ..svbrdf.images import srgb_encoded, write_exr, write_png

    output = output_file(args.output, "-o", ".png")  # -: a PNG on standard output, as render and plot write
    suffix = output.suffix.lower()
    if suffix not in RENDER_SUFFIXES:
        raise BrdfInputError(f"-o {args.output}: write {', '.join(RENDER_SUFFIXES)}")
    light, camera = (_point(flag, value) for flag, value in (("--light", args.light), ("--camera", args.camera)))
    intensity = _numbers("--intensity", args.intensity)
    if not all(intensity > 0):
        raise BrdfInputError(f"--intensity {args.intensity}: every value must be > 0")
    if args.exposure is not None and not args.exposure > 0:
        raise BrdfInputError(f"--exposure {args.exposure:g}: must be > 0")
    if args.exposure is not None and suffix != ".png":
        raise BrdfInputError(f"--exposure exposes a .png; {suffix} holds the radiance itself")
    maps = read_maps(_maps_folder(args.maps))
    if len(intensity) not in (1, len(maps.channels)):
        raise BrdfInputError(
            f"--intensity: {len(intensity)} values for {len(maps.channels)} channels; give 1 or {len(maps.channels)}"
        )
    image = render(maps, light, camera, intensity)
    image = image[..., 0] if image.shape[-1] == 1 else image
    if suffix == ".exr":
        write_exr(output, image)
    elif suffix == ".png":
        exposure = args.exposure or np.pi * float(np.sum(light**2)) / float(np.max(intensity))
        write_png(output, srgb_encoded(image * exposure))
    else:
        from .._files import atomic_path

        with atomic_path(output) as temporary, open(temporary, "wb") as stream:
            np.save(stream, image)
    rows, columns = maps.shape
    print(
        f"wrote {args.output}: {rows} × {columns} image of {args.maps} lit from {light.tolist()} mm, seen from"
        f" {camera.tolist()} mm"
    )
    return EXIT_OK


def _point(flag: str, value: str):
    from ..svbrdf.relight import point_above

    numbers = _numbers(flag, value)
    if len(numbers) != 3:
        raise BrdfInputError(f"{flag} {value}: give X,Y,Z, three numbers in mm")
    return point_above(flag, numbers)


def _numbers(flag: str, value: str):
    import numpy as np

    try:
        numbers = np.array([float(part) for part in value.split(",")])
    except ValueError:
        raise BrdfInputError(f"{flag} {value}: give comma-separated numbers") from None
    if not np.all(np.isfinite(numbers)):
        raise BrdfInputError(f"{flag} {value}: give finite numbers")
    return numbers
