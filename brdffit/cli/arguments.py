"""What the commands share: argument groups, the flags that spell the library's arguments, output checks, and the
Dask client of ``--scheduler ADDRESS`` or ``--workers N`` (:func:`cluster_client`), with one-line errors.

The library names its arguments as Python does (``n_starts``); :data:`FLAGS` and :func:`spell` are the one
place where they become the command line's flags (``--starts``), so that every message reads as the user
typed it.
"""

import argparse
import contextlib
import logging
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from .._files import parse_json, read_json_text
from ..errors import Argument, BrdfInputError

#: Flags whose name is not the argument's with ``_`` as ``-`` (``max_theta`` → ``--max-theta``).
FLAGS = {
    "n_starts": "--starts",
    "fixed": "--fix",
    "n": "-n",  # brdffit basis directions
    # brdffit plot's positional files and its -o
    "results": "RESULT",
    "result": "RESULT",
    "samples": "SAMPLES",
    "path": "-o",
    "output": "-o",
}

#: The metavars of arguments that name a file (shell completion completes file names there;
#: ``tests/cli/test_collisions.py`` checks each such argument is declared among its command's files).
FILE_METAVARS = frozenset(
    {"SAMPLES", "FILE", "PARAMS", "CSV", "DATA", "RESULT.json", "IN", "OUT", "BASIS", "LIB", "CAPTURE", "MAPS", "IMAGE"}
)


def flag(name: str) -> str:
    """The command line's flag for the library argument ``name``."""
    return FLAGS.get(name, "--" + name.replace("_", "-"))


def spell(argument: Argument) -> str:
    """An argument as the command line writes it: ``--starts 0``, or ``--starts`` without a value."""
    return flag(argument.name) if argument.shown is None else f"{flag(argument.name)} {argument.shown}"


#: The model options as flags: each model takes some (``brdffit models`` lists them).
MODEL_OPTIONS = ("fresnel", "distribution", "shadowing", "anisotropic", "sheen", "lobes", "int_ior", "basis", "ridge")


#: What ``-q`` does, as every command's help says it.
QUIET_HELP = (
    "print nothing but warnings and errors (the exit status says how it went; a product sent to standard output"
    " with -o - is still written there); no progress bars"
)


def quiet(action: argparse.ArgumentParser) -> None:
    """``-q`` after an action's name too (``brdffit svbrdf fit … -q``), as after a command's: unset there, the
    command's or the top level's value stands."""
    action.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)


def add_model_options(command: argparse.ArgumentParser, default: str | None) -> None:
    """``--model`` and the model options (``--fresnel``, ``--distribution``, ``--shadowing``, ``--anisotropic``,
    ``--sheen``, ``--lobes``, ``--int-ior``, ``--basis``, ``--ridge``)."""
    from ..physics.fresnel import FRESNEL
    from ..physics.microfacet import DISTRIBUTIONS, SHADOWING
    from ..physics.models.registry import MODELS

    default_text = f" (default {default})" if default else " (default: the model of a result file given as --params)"
    command.add_argument("--model", default=default, metavar="NAME", help=f"one of: {', '.join(MODELS)}{default_text}")
    for name, kinds, what in (
        ("fresnel", FRESNEL, "Fresnel term"),
        ("distribution", DISTRIBUTIONS, "microfacet distribution"),
        ("shadowing", SHADOWING, "masking-shadowing term"),
    ):
        command.add_argument(
            f"--{name}",
            metavar="KIND",
            help=f"cook-torrance's {what}: {', '.join(kinds)} (default {next(iter(kinds))})"
            + ("; roughplastic's: beckmann (default), ggx" if name == "distribution" else ""),
        )
    command.add_argument(
        "--anisotropic",
        metavar="true|false",
        help="cook-torrance: anisotropic roughness alpha_u, alpha_v and the tangent's azimuth phi_t in place of m"
        " (default false)",
    )
    command.add_argument(
        "--sheen",
        metavar="true|false",
        help="gltf: KHR_materials_sheen's sheen, sheen_color (per channel) and sheen_roughness, fitted (default false)",
    )
    command.add_argument("--lobes", type=int, metavar="K", help="lafortune: number of lobes (default 1)")
    command.add_argument(
        "--int-ior", type=float, metavar="ETA", help="roughplastic: the coating's index of refraction (default 1.49)"
    )
    command.add_argument("--basis", metavar="FILE", help="pca: the basis file (from brdffit basis build)")
    command.add_argument(
        "--ridge",
        type=float,
        metavar="W",
        help="pca: weight of the library prior in the basis's mapped space (default 1e-3; docs/data-driven.md)",
    )


def model_options(args: argparse.Namespace) -> dict[str, Any]:
    """The model options :func:`add_model_options` gave (None where not given: the model's default)."""
    return {name: getattr(args, name) for name in MODEL_OPTIONS}


def add_holding_options(command: argparse.ArgumentParser) -> None:
    """``--fix``, ``--bounds`` and ``--free``: parameters held at values or within ranges, or freed from the model's
    default holds (``docs/holding.md``)."""
    holding = command.add_argument_group("holding parameters (names as in the result file; docs/holding.md)")
    holding.add_argument(
        "--fix",
        action="append",
        metavar="NAME=VALUE[,…]",
        help="hold parameters at values, out of the fit: eta=1.5, kd=0 (every channel), kd=[0.1,0.2,0.3],"
        " lobes[1].cxy=0.577",
    )
    holding.add_argument(
        "--bounds",
        action="append",
        metavar="NAME=LO:HI[,…]",
        help="search parameters only within [LO, HI], inside their domains: m=0.05:0.3",
    )
    holding.add_argument(
        "--free",
        action="append",
        metavar="NAME[,…]",
        help="fit a parameter the model holds by default: ks of a conductor (held at 1)",
    )


def holding_arguments(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """``fixed`` and ``bounds`` as :func:`brdffit.fit` takes them, from ``--fix``, ``--bounds`` and ``--free`` (a freed
    name fixed at None; each flag may be given more than once, each a comma-separated list); the names and values
    are checked against the model by the fit."""
    fixed: dict[str, Any] = {}
    for item in _held_items(args.fix, "--fix"):
        name, value = _name_and_text(item, "--fix", "NAME=VALUE (eta=1.5, kd=[0.1,0.2,0.3])")
        try:
            parsed = parse_json(value)
        except ValueError:
            raise BrdfInputError(f"--fix {item}: {value!r} is not a number or a list of numbers") from None
        fixed[_new(name, fixed, "--fix")] = parsed
    for name in _held_items(getattr(args, "free", None), "--free"):
        fixed[_new(name, fixed, "--free")] = None  # None frees a default hold (constraints.py)
    bounds: dict[str, Any] = {}
    for item in _held_items(args.bounds, "--bounds"):
        name, value = _name_and_text(item, "--bounds", "NAME=LO:HI (m=0.05:0.3)")
        low, colon, high = value.partition(":")
        try:
            bounds[_new(name, bounds, "--bounds")] = [float(low), float(high)] if colon else None
        except ValueError:
            bounds[name] = None
        if bounds[name] is None:
            raise BrdfInputError(f"--bounds {item}: give the range as LO:HI, two numbers (m=0.05:0.3)")
    return {"fixed": fixed, "bounds": bounds}


def _held_items(values: list[str] | None, flag: str) -> list[str]:
    """The ``NAME=…`` items of every ``flag`` given, split at commas outside ``[…]`` (a per-channel list)."""
    items = []
    for value in values or []:
        depth, current = 0, ""
        for character in value:
            depth += {"[": 1, "]": -1}.get(character, 0)
            if character == "," and depth == 0:
                items.append(current.strip())
                current = ""
            else:
                current += character
        items.append(current.strip())
    if any(not item for item in items):
        raise BrdfInputError(f"{flag}: an empty item; give NAME=… separated by commas")
    return items


def _name_and_text(item: str, flag: str, form: str) -> tuple[str, str]:
    name, equals, value = item.partition("=")
    if not equals or not name.strip() or not value.strip():
        raise BrdfInputError(f"{flag} {item}: give {form}")
    return name.strip(), value.strip()


def _new(name: str, given: dict[str, Any], flag: str) -> str:
    if name in given:
        raise BrdfInputError(f"{flag}: {name} is given twice")
    return name


def add_comparison_options(command: argparse.ArgumentParser) -> None:
    """The options of a model comparison (``compare`` and ``report``): the samples, the models, the loss, the folds,
    the solver's settings, the seed and the reading options."""
    from ..fitting.objective.losses import LOSSES
    from ..fitting.options import MAX_STEPS, N_STARTS

    command.add_argument("samples", metavar="SAMPLES", help="samples file: CSV, MERL, ALTA, ASTM")
    command.add_argument(
        "--models",
        metavar="SPEC,…",
        help="models to compare, each NAME[:key=value,…] (cook-torrance:fresnel=conductor, lafortune:lobes=2,"
        " shorthand lafortune:2); default: every model, Lafortune with 1–3 lobes, Cook-Torrance with each Fresnel",
    )
    command.add_argument("--loss", default="log", metavar="NAME", help=f"one of: {', '.join(LOSSES)} (default log)")
    command.add_argument(
        "--basis", metavar="FILE", help="pca's basis (brdffit basis build); adds pca to the default models"
    )
    command.add_argument("--ridge", type=float, metavar="W", help="pca's ridge in --models (default 1e-3)")
    command.add_argument(
        "--folds", type=int, default=5, metavar="K", help="cross-validation folds (default 5, at least 2)"
    )
    command.add_argument("--max-theta", type=float, metavar="DEG", help="drop samples with θi or θo above DEG degrees")
    command.add_argument("--starts", type=int, default=N_STARTS, metavar="N", help=f"as for fit (default {N_STARTS})")
    command.add_argument(
        "--max-steps", type=int, default=MAX_STEPS, metavar="N", help=f"as for fit (default {MAX_STEPS})"
    )
    command.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the folds, the start search's subset, --subsample and the mcmc walkers (default 0)",
    )
    add_holding_options(command)
    add_loading_options(command)


def add_mcmc_options(group) -> None:
    """The sampler's settings, as ``fit`` and ``report`` take them with ``--uncertainty mcmc``."""
    group.add_argument("--walkers", type=int, metavar="N", help="mcmc: walkers (default 32)")
    group.add_argument("--steps", type=int, metavar="N", help="mcmc: steps per walker (default 2000)")
    group.add_argument("--burn", type=int, metavar="N", help="mcmc: steps discarded as burn-in (default 500)")
    group.add_argument("--thin", type=int, metavar="N", help="mcmc: keep every N-th step (default 1)")


def mcmc_settings(args: argparse.Namespace, also: tuple[str, ...] = ()):
    """The :class:`~brdffit.MCMC` settings :func:`add_mcmc_options` gave (seeded by ``--seed``), checked; None unless
    ``--uncertainty mcmc``, when giving any of them (or of ``also``, other options that apply only to mcmc) is an
    error."""
    from ..uncertainty.mcmc import MCMC

    given = {
        name: getattr(args, name) for name in ("walkers", "steps", "burn", "thin") if getattr(args, name) is not None
    }
    if args.uncertainty != "mcmc":
        for name in [*given, *(name for name in also if getattr(args, name))]:
            raise BrdfInputError(Argument(name), " applies only to ", Argument("uncertainty", "mcmc"))
        return None
    return MCMC(**given, seed=args.seed)


def comparison_arguments(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of :func:`brdffit.compare` that :func:`add_comparison_options` gave, checked (the
    models and the loss) before any work."""
    from ..fitting.comparison.compare import default_specs
    from ..fitting.objective.losses import get_loss
    from ..physics.models.specs import model_of_spec, split_specs

    get_loss(args.loss)
    given = {"basis": args.basis, "ridge": args.ridge}
    specs = None if args.models is None else split_specs(args.models, completed=lambda spec: _with(spec, given))
    if args.basis is not None or args.ridge is not None:  # the data-driven model's options: pca is compared
        if specs is None:
            specs = [*default_specs(), _with("pca", given)]
        elif not any(spec.partition(":")[0].strip() == "pca" for spec in specs):
            raise BrdfInputError("--basis and --ridge apply to pca, which --models does not name; add pca to it")
    return {
        "models": None if specs is None else [model_of_spec(spec) for spec in specs],
        "loss": args.loss,
        "folds": args.folds,
        "seed": args.seed,
        "max_theta": args.max_theta,
        "n_starts": args.starts,
        "max_steps": args.max_steps,
        **holding_arguments(args),
    }


def _with(spec: str, options: dict[str, Any]) -> str:
    """A pca spec completed with ``--basis`` and ``--ridge`` where it does not name them (other specs as they are)."""
    name, _, written = spec.partition(":")
    if name.strip() != "pca":
        return spec
    named = {item.partition("=")[0].strip() for item in written.split(",")}
    added = [f"{key}={value}" for key, value in options.items() if value is not None and key not in named]
    return spec if not added else f"{spec}{',' if written else ':'}{','.join(added)}"


#: What ``--bin-centres`` does, wherever a MERL table is read or written.
BIN_CENTRES_HELP = (
    "MERL: each bin at its centre, not its lower edge (where MERL's BRDFRead.cpp looks a direction up; the default)"
)


def add_loading_options(command: argparse.ArgumentParser) -> None:
    """How a samples file is read (:func:`brdffit.load_samples`'s arguments)."""
    from ..data.csv import ANGLE_UNITS
    from ..data.load import FORMATS
    from ..data.quantities import QUANTITIES
    from ..data.spectral import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, SPECTRAL_TARGETS

    reading = command.add_argument_group("reading the samples")
    kinds = ", ".join(f"{name} ({kind.description})" for name, kind in FORMATS.items())
    reading.add_argument("--format", metavar="NAME", help=f"{kinds}; default: from the extension and first lines")
    reading.add_argument(
        "--quantity",
        metavar="Q",
        help=f"what the values are: {', '.join(QUANTITIES)} (cosine-weighted means cosine-weighted-in);"
        " default: what the file's header says, else brdf (brdffit info checks it on reciprocal pairs)",
    )
    reading.add_argument(
        "--angles", default="degrees", metavar="UNIT", help=f"CSV angle columns in {' or '.join(ANGLE_UNITS)}"
    )
    reading.add_argument(
        "--spectral-to",
        default="keep",
        metavar="T",
        help=f"value columns named by wavelength (nm): {', '.join(SPECTRAL_TARGETS)} (default keep: every band)",
    )
    reading.add_argument(
        "--illuminant",
        default=DEFAULT_ILLUMINANT,
        metavar="NAME",
        help=f"for --spectral-to (default {DEFAULT_ILLUMINANT})",
    )
    reading.add_argument(
        "--observer",
        default=DEFAULT_OBSERVER,
        metavar="NAME",
        help=f"colour-matching functions for --spectral-to (default: {DEFAULT_OBSERVER})",
    )
    reading.add_argument("--subsample", type=int, metavar="N", help="MERL: keep N samples")
    reading.add_argument(
        "--subsample-method", default="random", metavar="M", help="MERL: random (default) or stratified (over θh)"
    )
    reading.add_argument("--bin-centres", action="store_true", help=BIN_CENTRES_HELP)


def load(path: str, args: argparse.Namespace):
    """``path`` (``-``: standard input, ``files.py``) read with the loading options of ``args``."""
    import dataclasses

    from ..data.load import load_samples
    from .files import input_path, is_standard

    samples = load_samples(input_path(path), **read_options(args))
    return dataclasses.replace(samples, source="-") if is_standard(path) else samples


def read_options(args: argparse.Namespace) -> dict:
    """The loading options of ``args`` as ``load_samples`` takes them."""
    return dict(
        format=args.format,
        angles=args.angles,
        quantity=args.quantity,
        spectral_to=args.spectral_to,
        illuminant=args.illuminant,
        observer=args.observer,
        subsample=args.subsample,
        subsample_method=args.subsample_method,
        seed=args.seed,
        bin_centres=args.bin_centres,
    )


def json_argument(value: str, option: str) -> Any:
    """Inline JSON (starting with ``{``) or the content of the JSON file ``value``."""
    from .files import input_path

    if value.lstrip().startswith("{"):
        text, where = value, f"{option} (inline JSON)"
    else:
        where = f"{option} {value}"
        try:
            text = read_json_text(input_path(value))
        except FileNotFoundError:
            raise BrdfInputError(f"{where}: no such file") from None
        except (OSError, ValueError) as error:  # ValueError: too large, and UnicodeDecodeError
            raise BrdfInputError(f"{where}: cannot be read ({error})") from None
    try:
        return parse_json(text)
    except ValueError as error:
        raise BrdfInputError(f"{where}: not valid JSON ({error})") from None


def json_file(value: str | None) -> str | None:
    """The file a :func:`json_argument` reads; None for inline JSON or no value."""
    return None if not value or value.lstrip().startswith("{") else value


def model_files(model_options: dict[str, Any]) -> list[str]:
    """The files a model's options name (the data-driven model's basis), which no output may overwrite."""
    basis = model_options.get("basis")
    return [str(basis)] if basis else []


def output_file(value: str | os.PathLike, option: str, standard_suffix: str = "") -> Path:
    """The file ``option`` writes, checked before any work; returns the path to write to (for ``-``, standard output:
    a temporary file named with ``standard_suffix``, copied there when the command is done, ``files.py``).

    A symbolic link is followed: the file it points to is replaced (atomically) and the link kept. The
    target must not be a folder, a device or anything else that is not a regular file, and its folder must
    exist and be writable. That it is no input and no other output is checked for every command at once
    (``files.py``).
    """
    from .files import is_standard, output_path

    if is_standard(value):
        return output_path(value, standard_suffix)
    path = Path(value)
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    where = f"{option} {value}"
    # What the path names, links followed by the system (``/dev/stdout`` is a link to ``/proc/self/fd/1``, a pipe whose
    # resolved name, ``pipe:[…]``, names nothing): a folder, a device or a pipe is refused before any work.
    if path.is_dir() or target.is_dir():
        raise BrdfInputError(f"{where}: is a folder; give a file name")
    if (path.exists() and not path.is_file()) or (target.exists() and not target.is_file()):
        raise BrdfInputError(
            f"{where}: is not a regular file (a device or a pipe); give a file name"
            + (", or - for standard output" if option == "-o" else "")
        )
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise BrdfInputError(f"{where}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise BrdfInputError(f"{where}: folder {folder} is not writable")
    return target


def fit_file(path: str):
    """The fit a file holds (a :class:`~brdffit.FitResult`): a result file's, or a comparison file's best, what
    ``export`` and ``render`` take; JAX is imported only for a comparison."""
    from ..fitting.single.result import FitResult, is_comparison, read_json_object
    from .files import input_path

    content = read_json_object(input_path(path), "brdffit result or comparison file")
    if not is_comparison(content):
        return FitResult.from_dict(content, path)
    from ..fitting.comparison.compare import Comparison

    return Comparison.from_dict(content, path).best.result


def fit_of(args: argparse.Namespace):
    """The fit of ``args.result`` (:func:`fit_file`), read once per command: the check of its files before the work
    (:func:`fit_file_files`, the basis its model names) and the work itself share it."""
    if getattr(args, "read_fit", None) is None:
        args.read_fit = fit_file(args.result)
    return args.read_fit


def fit_file_files(args: argparse.Namespace, output: str):
    """What ``export`` and ``render`` read (RESULT, the basis its model names, ``--samples``) and write (``output``:
    ``-o`` or its default name), as :class:`~brdffit.cli.files.Files`."""
    from .files import Files

    return Files.of(
        inputs={
            "RESULT.json": args.result,
            "the result's basis": model_files(fit_of(args).model_options),
            "--samples": args.samples,
        },
        outputs={"-o": output},
    )


# ------------------------------------------------------------------ --scheduler, --workers: a Dask client
#: How long to wait for a scheduler to answer, in seconds.
CONNECT_SECONDS = 10


@contextlib.contextmanager
def cluster_client(address: str | None, workers: int | None) -> Iterator:
    """A ``dask.distributed.Client`` of the scheduler at ``address``, or of a local cluster of ``workers`` worker
    processes (one thread each: a fit's programs use the cores of their process) closed on leaving."""
    try:
        import distributed
    except ImportError:
        option = "--scheduler" if address else "--workers"
        raise BrdfInputError(f"{option} needs Dask: pip install 'brdffit[cluster]'") from None
    # Dask's start-up and shut-down notices, here and in the worker processes it starts (which read the variable)
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "error")
    logging.getLogger("distributed").setLevel(logging.ERROR)
    if address:
        try:
            client = distributed.Client(address, timeout=CONNECT_SECONDS)
        except Exception as error:  # whatever fails, no scheduler answers: an HTTP server's bytes, read by Dask as a
            # frame length, asked for 3 EiB (MemoryError)
            reason = f"{type(error).__name__}: {error}".splitlines()[0]
            raise BrdfInputError(f"--scheduler {address}: no Dask scheduler answers there ({reason})") from None
        with client, _killed_workers(distributed, f"--scheduler {address}"):
            yield client
        return
    try:
        cluster = distributed.LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0"
        )
    except Exception as error:  # Dask's event loop gives up after 10 s on a loaded machine (a bare AssertionError)
        reason = f"{type(error).__name__}: {error}".splitlines()[0].rstrip(": ")
        raise BrdfInputError(
            f"--workers {workers}: a local Dask cluster did not start ({reason}); nothing written"
        ) from None
    with cluster, distributed.Client(cluster) as client, _killed_workers(distributed, f"--workers {workers}"):
        yield client


@contextlib.contextmanager
def _killed_workers(distributed, where: str) -> Iterator[None]:
    """A fit that killed every worker it was given (Dask gives up after a few: ``KilledWorker``) as one line."""
    try:
        yield
    except distributed.KilledWorker as error:
        reason = str(error).split(". ")[0]  # "Attempted to run task … on 4 different workers, but all … died …"
        raise BrdfInputError(
            f"{where}: Dask workers died while fitting ({reason[:1].lower()}{reason[1:]}); nothing written"
        ) from None
