"""``brdffit plot``: figures of one or more fits against the samples they were fitted to.

``brdffit plot RESULT.json [RESULT.json …] SAMPLES --kind slices|polar|residuals|sphere|all [-o FILE | OUTDIR/]``.
A comparison file (``brdffit compare -o``) counts as its best models. Every output path is checked, and the
samples read, before any figure is drawn.
"""

import argparse
import os
import re
import warnings
from pathlib import Path

from ..errors import BrdfInputError, InputWarning, warn
from ..views.figures import as_list, label
from . import EXIT_OK
from .arguments import add_loading_options, load, output_file
from .files import Files
from .files import stem as stem_of


def configure(parser: argparse.ArgumentParser) -> None:
    from ..views.plots import KINDS
    from ..views.render import LIGHTS

    parser.add_argument(
        "files",
        metavar="FILE",
        nargs="+",
        help="one or more result files (or a comparison file from brdffit compare -o), then the samples file last;"
        " the samples are read as the fits read them (their quantity, the reading options below they were fitted"
        " with, and --max-theta) unless told otherwise",
    )
    parser.add_argument(
        "--kind",
        default="all",
        metavar="KIND",
        help=f"{', '.join(KINDS)} or all (default all: one file each)",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="the figure (.png, .pdf, .svg), or a folder (OUTDIR/) for several; default SAMPLES-stem.KIND.png here",
    )
    parser.add_argument(
        "--lights",
        default="both",
        metavar="L",
        help=f"sphere: {', '.join(LIGHTS)} or both (default both, one row each)",
    )
    parser.add_argument(
        "--incidences",
        metavar="DEG,…",
        help="slices and polar: the light zeniths to show (default: the data's, at most 4)",
    )
    add_loading_options(parser)
    parser.add_argument("--seed", type=int, default=0, help="seed of --subsample (default 0)")


def files(args: argparse.Namespace) -> Files:
    """What ``plot`` reads (the result files and the samples) and writes (each figure)."""
    *_, outputs = _figures(args)
    return Files.of(inputs={"FILE": args.files}, outputs={"-o": outputs})


def _figures(args: argparse.Namespace):
    """The kinds of figure asked for, the fits ``(path, result)`` the result files hold, the figures
    ``(kind, index of the fit or None)`` and the file of each, all checked."""
    from ..checks import choice
    from ..views.plots import KINDS
    from ..views.sphere import LIGHTINGS

    if len(args.files) < 2:
        raise BrdfInputError("give one or more result files, then the samples file they were fitted to")
    *result_paths, samples_path = args.files
    kinds = list(KINDS) if args.kind == "all" else [choice("kind", args.kind, [*KINDS, "all"])]
    choice("lights", args.lights, LIGHTINGS)
    _not_a_result(samples_path)
    fits = [(path, fit) for path in result_paths for fit in _results(path)]
    results = [fit for _, fit in fits]
    figures = [(kind, index) for kind in kinds for index in (range(len(results)) if kind == "residuals" else [None])]
    return kinds, fits, figures, output_paths(figures, results, args.output, samples_path)


def run(args: argparse.Namespace) -> int:
    from ..views.figures import check_figure_path
    from ..views.plots import KINDS
    from ..views.residuals import colour_limit

    incidences = _incidences(args.incidences)
    kinds, fits, figures, outputs = _figures(args)
    if _names_a_folder(args.output) is False and args.output != "-":  # -o FILE: a suffix matplotlib writes
        check_figure_path(args.output, argument="output")
    results = [fit for _, fit in fits]
    samples_path = args.files[-1]
    max_theta = _read_as_fitted(args, fits, samples_path)
    samples = load(samples_path, args).within(max_theta)
    for path, fit in fits:
        if tuple(fit.channels) != samples.channels:
            raise BrdfInputError(
                f"{path}: its fit ({label(fit)}) has channels {', '.join(fit.channels)} but {samples_path} has"
                f" {', '.join(samples.channels)}"
            )
    outputs[0].parent.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("MPLBACKEND", "Agg")  # files only: no window, no display needed
    written = []
    if "residuals" in kinds:  # several fits' maps on one colour scale, so that they compare
        limit = max(colour_limit(result, samples) for result in results)
    with warnings.catch_warnings():  # each figure's word on a fit read otherwise: _read_as_fitted said it, once
        warnings.filterwarnings("ignore", ".* was fitted to samples read ", InputWarning)
        for (kind, index), path in zip(figures, outputs, strict=True):
            if kind == "residuals":
                KINDS[kind](results[index], samples, limit=limit, path=path)
            elif kind == "sphere":
                KINDS[kind](results, samples, lights=args.lights, path=path)
            else:
                KINDS[kind](results, samples, incidences=incidences, path=path)
            written.append("-" if args.output == "-" else str(path))  # -: a temporary file, copied to standard output
    print(f"wrote {', '.join(written)}")
    return EXIT_OK


def _results(path: str) -> list:
    """The fits a file holds: a result file's one, or a comparison file's best (and those within one s.e.)."""
    from ..fitting.comparison.compare import Comparison
    from ..fitting.single.result import FitResult, is_comparison, read_json_object
    from ..physics.models.registry import get_model
    from .files import input_path

    try:
        content = read_json_object(input_path(path), "brdffit result or comparison file")
    except BrdfInputError as error:
        raise BrdfInputError(f"{error}; give the result files first and the samples file last") from None
    fits = (
        [FitResult.from_dict(content, path)]
        if not is_comparison(content)
        else as_list(Comparison.from_dict(content, path))
    )
    for fit in fits:  # its model and options name a model brdffit has, before any name or folder derives from them
        try:
            get_model(fit.model, **fit.model_options)
        except BrdfInputError as error:
            raise BrdfInputError(f"{path}: {error}") from None
    return fits


def _not_a_result(path: str) -> None:
    """Refuse a result or comparison file where the samples file belongs (the last file)."""
    from .._files import parse_json, read_json_text
    from .files import input_path

    try:
        content = parse_json(read_json_text(input_path(path)))
    except (OSError, ValueError):  # ValueError: JSON's, too large, and UnicodeDecodeError
        return  # not JSON: the samples reader says what is wrong with it
    if isinstance(content, dict) and ("params" in content or "models" in content):
        raise BrdfInputError(f"{path} is a result file, not samples; the samples file comes last")


def _read_as_fitted(args: argparse.Namespace, fits: list, samples_path: str) -> float | None:
    """Read the samples as the fits did: their quantity and the options their files were read with (``fit.reading``:
    a format given, radians, a spectral conversion, MERL's bin centres), each where the command line leaves it at its
    default and the fits agree (else a fit that read its samples otherwise is warned about), and their ``max_theta``
    when the fits agree, which is returned."""
    import inspect

    from ..data.load import READING_OPTIONS, load_samples

    defaults = {name: parameter.default for name, parameter in inspect.signature(load_samples).parameters.items()}
    for name in ["quantity", *READING_OPTIONS]:
        # What each fit read with: a quantity not recorded is unknown; a reading option not recorded, its default.
        used = [
            (path, fit.quantity if name == "quantity" else fit.reading.get(name, defaults[name]))
            for path, fit in fits
            if name != "quantity" or fit.quantity is not None
        ]
        values = {repr(value) for _, value in used}
        if getattr(args, name) == defaults[name] and len(values) == 1:
            setattr(args, name, used[0][1])
            continue
        given = "brdf" if name == "quantity" and args.quantity is None else getattr(args, name)
        for path, value in used:
            if value != given:
                warn(
                    InputWarning(
                        f"{path} was fitted to samples read {_read_with(name, value)}; {samples_path} is read"
                        f" {_read_with(name, given)}"
                    )
                )
    limits = {fit.max_theta for _, fit in fits}
    return limits.pop() if len(limits) == 1 else None


def _read_with(name: str, value) -> str:
    """How a reading option's value reads in a warning: ``as brdf`` (the quantity), ``with --angles radians``,
    ``without --format``."""
    option = "--" + name.replace("_", "-")
    if name == "quantity":
        return f"as {value}"
    if value is None or value is False:
        return f"without {option}"
    return f"with {option}" if value is True else f"with {option} {value}"


def _incidences(text: str | None):
    if text is None:
        return None
    try:
        angles = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        angles = []
    if not angles or not all(0 <= angle < 90 for angle in angles):
        raise BrdfInputError(
            f"--incidences {text}: give light zeniths in degrees, each in [0, 90), separated by commas"
        )
    return angles


def _names_a_folder(output: str | None) -> bool | None:
    """Whether ``-o`` names a folder (a trailing ``/``, or an existing folder); None when not given."""
    return None if output is None else output.endswith(("/", os.sep)) or Path(output).is_dir()


#: The characters a fit's label keeps in a figure's file name; any other (a ``/``, a ``\\``, a space) becomes ``-``.
NAME_CHARACTERS = re.compile(r"[^A-Za-z0-9_.,=+-]")


def file_name_part(text: str) -> str:
    """``text`` (a fit's label, which comes from the result file's content) as one component of a file name: never a
    path. Every character outside letters, digits and ``_.,=+-`` becomes ``-`` (``cook-torrance:fresnel=a/../b`` →
    ``cook-torrance-fresnel=a-..-b``), and a leading ``.`` too, so that no name is ``..`` or hidden."""
    part = NAME_CHARACTERS.sub("-", text)
    return "-" + part[1:] if part.startswith(".") else part


def output_paths(figures, results, output: str | None, samples_path: str) -> list[Path]:
    """Where each figure goes, checked before any work: ``-o FILE`` for one figure, a folder (``-o OUTDIR/``, or
    the current folder) for several, named ``SAMPLES-stem.KIND[.SPEC].png``. (A file's suffix is checked by
    ``run``, after the check that it is no input.)"""
    stem = stem_of(samples_path)
    several_results = len(results) > 1

    def name(kind: str, index: int | None) -> str:
        from ..views.figures import label

        which = f".{file_name_part(label(results[index]))}" if index is not None and several_results else ""
        return f"{stem}.{kind}{which}.png"

    as_folder = bool(_names_a_folder(output))
    if as_folder and output is not None and Path(output).exists() and not Path(output).is_dir():
        raise BrdfInputError(f"-o {output}: {output.rstrip('/' + os.sep)} is a file; give a folder (OUTDIR/)")
    if len(figures) > 1 and output is not None and not as_folder:
        raise BrdfInputError(f"-o {output}: {len(figures)} figures need a folder; give OUTDIR/")
    if output is not None and not as_folder:
        path = output_file(output, "-o", ".png")  # -: one figure, a PNG on standard output
        return [path]
    folder = Path(output) if output else Path(".")
    if not folder.exists():  # created after every check, as fit's -o OUTDIR/
        existing = next(parent for parent in folder.parents if parent.exists())
        if not os.access(existing, os.W_OK):
            raise BrdfInputError(f"-o {output}: folder {existing} is not writable")
        return [folder / name(kind, index) for kind, index in figures]
    return [output_file(folder / name(kind, index), "-o") for kind, index in figures]
