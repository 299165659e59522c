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
    from ..data.load import READING_OPTIONS
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
    # Not given, the reading options are the fits' (their fit.reading), else load_samples's defaults: _read_as_fitted.
    parser.set_defaults(**dict.fromkeys(READING_OPTIONS))
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
    from ..data.load import errors_name_the_reading
    from ..views.figures import check_figure_path
    from ..views.plots import KINDS
    from ..views.residuals import colour_limit

    incidences = _incidences(args.incidences)
    kinds, fits, figures, outputs = _figures(args)
    if _names_a_folder(args.output) is False and args.output != "-":  # -o FILE: a suffix matplotlib writes
        check_figure_path(args.output, argument="output")
    results = [fit for _, fit in fits]
    samples_path = args.files[-1]
    max_theta, taken = _read_as_fitted(args, fits, samples_path)
    with errors_name_the_reading(samples_path, taken, "the fits read their samples (their"):
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


def _read_as_fitted(args: argparse.Namespace, fits: list, samples_path: str) -> tuple[float | None, dict]:
    """Set ``args``' reading options to read the samples as the fits did, where the command line does not give
    them: the fits' quantity (when they record one and agree) and each option of ``fit.reading`` they agree on
    (:func:`~brdffit.data.load.agreed_reading`), else :func:`~brdffit.load_samples`'s defaults. Warns about a fit
    that read its samples otherwise than these are read. Returns the fits' ``max_theta`` when they agree (else
    None) and the options taken from the fits that are not the defaults."""
    from ..data.load import READING_OPTIONS, agreed_reading, load_samples_defaults
    from ..data.quantities import canonical

    defaults = load_samples_defaults()
    quantities = {fit.quantity for _, fit in fits if fit.quantity is not None}
    agreed = agreed_reading(fit.reading for _, fit in fits)
    taken = {}
    for name in ["quantity", *READING_OPTIONS]:
        if getattr(args, name) is None:  # not given: the fits decide
            fits_say = quantities.pop() if name == "quantity" and len(quantities) == 1 else agreed.get(name)
            setattr(args, name, fits_say if fits_say is not None else defaults[name])
            if fits_say is not None and name != "quantity":
                taken[name] = fits_say
        if name == "format" or (name in ("illuminant", "observer") and args.spectral_to == "keep"):
            continue  # a format read otherwise fails to read; these two describe a conversion neither side makes
        if name == "quantity":
            read_as = canonical(args.quantity) if args.quantity is not None else "brdf"
            used = [(path, fit.quantity) for path, fit in fits if fit.quantity is not None]
        else:
            read_as = getattr(args, name)
            used = [(path, fit.reading.get(name, defaults[name])) for path, fit in fits]
        for path, value in used:
            if value != read_as:
                warn(
                    InputWarning(
                        f"{path} was fitted to samples read {_read_with(name, value)}; {samples_path} is read"
                        f" {_read_with(name, read_as)}"
                    )
                )
    limits = {fit.max_theta for _, fit in fits}
    return (limits.pop() if len(limits) == 1 else None), taken


def _read_with(name: str, value) -> str:
    """How a reading option's value reads in a warning: ``as brdf`` (the quantity), ``with --angles radians``,
    ``without --bin-centres``."""
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
