"""The ``brdffit`` command line: the parser, and a module per command that it loads on demand.

Each command module (``fit.py``, ``compare.py``, ``plot.py``, ``report.py``, ``export.py``, ``render.py``,
``synth.py``, ``models.py``, ``info.py``, ``convert.py``, ``basis.py``) has ``configure(parser)``, which adds its
arguments, ``files(args)``, the files it reads and writes (``files.py``: checked before it runs, so that no output
is an input or another output), and ``run(args) -> int``.
Only the command being run is imported and configured, so ``brdffit --help`` and ``--version`` import no JAX
and no solver.

Exit status: 0 success; 1 a fit did not converge (its result is still written, with ``converged: false``);
2 bad input or usage, or a file that cannot be written (a full disk), reported in one line on stderr, with nothing
written (in a batch of fits, also a dataset whose fit is not finite: its line, no file for it, the others written);
130 interrupted (Ctrl-C), 143 terminated (SIGTERM), with nothing written from then on and nothing half-written (every
file is written to a temporary name and renamed, and ``_files.stop_writing`` stops every later rename, so an
interrupt that JAX swallows still stops the output).
"""

import argparse
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

from .._files import check_not_stopped, resume_writing, stop_writing
from .._version import __version__
from ..errors import BrdfInputError, BrdfWriteError, FitWarning, InputWarning, Spelled, UncertaintyWarning
from .arguments import QUIET_HELP
from .files import check_one_standard_input, is_standard, printing_to, standard_streams

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143

#: The commands, each a module of this package, with the line ``brdffit --help`` shows for it.
COMMANDS = {
    "fit": "fit a model to samples files",
    "compare": "fit several models to one samples file and rank them by cross-validated loss",
    "plot": "figures of fits against their samples: slices, polar plots, residual maps, lit spheres",
    "report": "compare models on one samples file and write a self-contained HTML report",
    "export": "a fit for a renderer: a Mitsuba 3 BSDF, a glTF 2.0 material or a MERL table",
    "render": "a sphere with a fit's Mitsuba 3 BSDF, rendered by Mitsuba (needs the render extra)",
    "synth": "write synthetic samples of a model",
    "models": "list the models, their parameters and domains",
    "convert": "convert samples between formats, or tabulate a fit result as a MERL file",
    "info": "what a samples file holds: count, channels, angular coverage (or what a basis file holds)",
    "basis": "learn a data-driven basis from a library of MERL tables, and choose the directions to measure",
    "svbrdf": "a spatially varying material: fit a capture's photographs texel by texel into maps, and relight them",
}


#: Two or three examples of each command, which its ``--help`` ends with (each is parsed by a test).
EXAMPLES = {
    "fit": (
        "brdffit fit examples/ward-pickled-oak.csv --model ward -o oak.json",
        "brdffit fit data.csv --model cook-torrance --fresnel conductor --shadowing smith --uncertainty laplace",
        "brdffit fit a.csv b.csv c.csv --model lafortune --lobes 2 -o fits/",
    ),
    "compare": (
        "brdffit compare examples/ward-pickled-oak.csv -o oak.compare.json",
        "brdffit compare data.csv --models ward,cook-torrance:conductor,lafortune:2 --folds 10",
    ),
    "plot": (
        "brdffit plot oak.json examples/ward-pickled-oak.csv -o figures/",
        "brdffit plot oak.json other.json data.csv --kind slices -o slices.png",
    ),
    "report": (
        "brdffit report examples/ward-pickled-oak.csv -o oak.html",
        "brdffit report data.csv --models ward,lafortune:2 --uncertainty mcmc -o data.html",
    ),
    "export": (
        "brdffit export oak.json --to mitsuba --samples examples/ward-pickled-oak.csv",
        "brdffit export oak.compare.json --to gltf -o oak.glb",
        "brdffit export oak.json --to merl -o oak.binary",
    ),
    "render": (
        "brdffit render oak.json -o oak.png",
        "brdffit render oak.json --samples examples/ward-pickled-oak.csv -o beside.png",
        "brdffit render oak.xml -o oak.exr",
    ),
    "synth": (
        "brdffit synth --model ward --params oak.json --noise 0.01 --seed 1 -o noisy.csv",
        "brdffit synth --model lambert --params '{\"rho_d\": [0.5]}' --geometry in-plane -o grey.csv",
        "brdffit synth capture capture/ --model ward --texels 64,64 --images 32 --noise 0.01",
    ),
    "models": ("brdffit models", "brdffit models | grep -A3 '^cook-torrance'"),
    "convert": (
        "brdffit convert tape.dat tape.csv",
        "brdffit convert oak.json oak.binary",
        "brdffit convert spectra.csv rgb.csv --spectral-to rgb",
    ),
    "info": ("brdffit info examples/ward-pickled-oak.csv", "brdffit info examples/retro-gray-tape.dat"),
    "basis": (
        "brdffit basis build merl/ -o basis.npz --components 16",
        "brdffit basis directions basis.npz -n 20 -o directions.csv",
    ),
    "svbrdf": (
        "brdffit svbrdf fit examples/ward-capture --model ward -o maps/",
        "brdffit svbrdf fit capture/ --model cook-torrance --fix f0=0.04 --uncertainty laplace --resume -o maps/",
        "brdffit svbrdf render maps/ --light 0,-150,250 --camera 0,0,400 -o relit.exr",
    ),
}


def _epilog(command: str) -> str:
    return "examples:\n" + "\n".join(f"  {example}" for example in EXAMPLES[command])


class UsageError(Exception):
    """An argparse usage error, reported like any other bad input."""


class Terminated(BaseException):
    """SIGTERM, raised where the program is (like ``KeyboardInterrupt`` for SIGINT): every ``finally`` and the atomic
    writers' clean-up run, so no temporary file is left."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        raise UsageError(f"{message} (see {self.prog} --help)")


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``) and return the exit status."""
    from .arguments import spell

    argv = sys.argv[1:] if argv is None else [str(argument) for argument in argv]
    resume_writing()
    try:
        if argv[:1] == ["--print-completion"]:
            return _print_completion(argv[1:])
        with _signals_stop_writing():
            args = build_parser(_command_in(argv)).parse_args(argv)
            product = is_standard(getattr(args, "output", None))  # -o -, convert's OUT -: a product on stdout
            check_one_standard_input(args)
            with warnings.catch_warnings(), standard_streams(product), _quiet(args.quiet):
                _warn_in_one_line()
                args.declared_files(args).check()
                status = args.run(args)
            check_not_stopped()  # an interrupt that was swallowed (JAX's gc callback): the work went on, unwritten
            return status
    except (BrdfInputError, BrdfWriteError) as error:
        print(f"brdffit: error: {error.spelled(spell)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except UsageError as error:
        print(f"brdffit: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemExit as exit_:  # --help and --version
        return exit_.code if isinstance(exit_.code, int) else EXIT_OK
    except KeyboardInterrupt:
        print("brdffit: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print("brdffit: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    finally:
        resume_writing()  # the stop is for this command only (``main`` is also called from Python)


@contextmanager
def _quiet(quiet: bool) -> Iterator[None]:
    """``-q``: what a command prints on standard output (tables, ``wrote …`` lines) goes to the null device, while a
    product written there (``-o -``, ``files.write_to_standard_output``) still reaches it; warnings and errors stay on
    standard error, and the commands show no progress bars (they read ``args.quiet``)."""
    if not quiet:
        yield
        return
    with open(os.devnull, "w") as null, printing_to(null):
        yield


def on_interrupt(signum, frame) -> None:
    """SIGINT: stop every later write (``_files.stop_writing``), then raise ``KeyboardInterrupt`` as Python does."""
    stop_writing()
    raise KeyboardInterrupt


def on_terminate(signum, frame) -> None:
    """SIGTERM: stop every later write, then raise :class:`Terminated` (the temporaries are removed on the way out)."""
    stop_writing(Terminated)
    raise Terminated


@contextmanager
def _signals_stop_writing() -> Iterator[None]:
    """:func:`on_interrupt` and :func:`on_terminate` as the handlers of SIGINT and SIGTERM while a command runs (only
    the main thread may set handlers; elsewhere, as in a test's thread, they are left alone; an ignored signal stays
    ignored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    # A signal the process was started ignoring (``nohup``, a background job) stays ignored, as Python leaves it.
    handlers = {signal.SIGINT: on_interrupt, signal.SIGTERM: on_terminate}
    previous = {
        number: signal.signal(number, handler)
        for number, handler in handlers.items()
        if signal.getsignal(number) is not signal.SIG_IGN
    }
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def run() -> None:
    """Console-script entry point."""
    status = None
    try:
        status = main()
        sys.stdout.flush()
    except BrokenPipeError:
        # The reader of a printed table went away (`brdffit fit … | head`): files are already written; say nothing
        # more (a result meant for standard output, -o -, is a write error: files.write_to_standard_output).
        # Python docs, "Note on SIGPIPE": point stdout at devnull so the final flush cannot fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = EXIT_OK if status is None else status
        sys.exit(status)
    _exit(status)


#: Modules whose presence means the interpreter's teardown must run: Dask's client and cluster, and the tools that
#: write their findings at exit (``python -m cProfile``, ``coverage run``, debuggers, other profilers).
EXIT_WATCHERS = (
    "distributed",
    "cProfile",
    "profile",
    "trace",
    "coverage",
    "pdb",
    "debugpy",
    "pydevd",
    "pyinstrument",
    "yappi",
    "memray",
    "scalene",
    "line_profiler",
)


def _exit(status: int) -> None:
    """Exit with ``status``, without the interpreter's teardown once JAX is loaded: tearing down its backend took
    0.2 s of a warm 1.1 s ``brdffit fit`` (issue 32). By now every file is written and closed; what the teardown would
    still do is flush logging and the standard streams (done here, C's too), free memory the process gives back anyway,
    and join idle threads. The teardown runs as usual where any other thread is still alive (a background compile
    writing the cache), where Dask was used (``--scheduler``, ``--workers``), under a tool that writes what it found on
    exit (a profiler, coverage, a debugger: :data:`EXIT_WATCHERS`, ``sys.monitoring``) and with ``python -i``."""
    if "jax" not in sys.modules or _exit_is_watched() or threading.active_count() > 1:
        sys.exit(status)
    import ctypes
    import logging

    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader gone, a stream closed: nothing more can reach it
            pass
    try:
        ctypes.CDLL(None).fflush(None)  # what a C library (Mitsuba's) left in its buffers
    except (OSError, AttributeError):
        pass
    os._exit(status)


def _exit_is_watched() -> bool:
    """Whether something expects the interpreter's teardown: a tracer or profiler, a module of
    :data:`EXIT_WATCHERS`, a ``sys.monitoring`` tool (Python 3.12+), or ``python -i``."""
    monitoring = getattr(sys, "monitoring", None)
    tools = monitoring is not None and any(monitoring.get_tool(tool) is not None for tool in range(6))
    traced = sys.gettrace() is not None or sys.getprofile() is not None
    return traced or tools or bool(sys.flags.inspect) or any(name in sys.modules for name in EXIT_WATCHERS)


def _warn_in_one_line() -> None:
    """brdffit's warnings as ``brdffit: warning: …`` lines, spelled with flags, each time they occur. A fit's and an
    estimate's are printed by ``fit`` from the results, naming the file each belongs to."""
    from .arguments import spell

    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if not isinstance(message, Spelled):
            return shown(message, category, filename, lineno, file, line)
        print(f"brdffit: warning: {message.spelled(spell)}", file=sys.stderr)

    warnings.showwarning = show
    warnings.simplefilter("always", InputWarning)
    warnings.simplefilter("ignore", FitWarning)
    warnings.simplefilter("ignore", UncertaintyWarning)


def build_parser(command: str | None = None, every: bool = False) -> argparse.ArgumentParser:
    """The parser, with the arguments of ``command`` (None: every command named, none configured; ``every``: every
    command configured, as shell completion needs it)."""
    parser = _Parser(
        prog="brdffit",
        description="Fit analytic BRDF models to measured reflectance samples.",
        allow_abbrev=False,
    )
    parser.add_argument("--version", action="version", version=f"brdffit {__version__}")
    parser.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    parser.add_argument(
        "--print-completion",
        metavar="SHELL",
        help="print the shell completion script of every command, for bash, zsh or tcsh (brdffit --print-completion"
        " bash > ~/.local/share/bash-completion/completions/brdffit)",
    )
    commands = parser.add_subparsers(title="commands", metavar="COMMAND", required=True)
    for name, summary in COMMANDS.items():
        subparser = commands.add_parser(
            name,
            help=summary,
            description=summary,
            epilog=_epilog(name),
            formatter_class=argparse.RawDescriptionHelpFormatter,
            allow_abbrev=False,
        )
        # Given after the command as well; unset there, the top level's value stands (argparse: a subparser's default
        # would overwrite it).
        subparser.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)
        if name == command or every:
            module = importlib.import_module(f".{name}", __name__)
            module.configure(subparser)
            subparser.set_defaults(run=module.run, declared_files=module.files)
    return parser


#: The shells ``--print-completion`` writes a script for (shtab's).
COMPLETION_SHELLS = ("bash", "zsh", "tcsh")


def _print_completion(words: list[str]) -> int:
    """``brdffit --print-completion SHELL``: shtab's completion script of every command and option, completing file
    names where an argument names a file (``arguments.FILE_METAVARS``)."""
    import shtab

    from .arguments import FILE_METAVARS

    if len(words) != 1 or words[0] not in COMPLETION_SHELLS:
        raise UsageError(f"--print-completion takes one shell: {', '.join(COMPLETION_SHELLS)}")
    parser = build_parser(every=True)
    parsers = [parser]
    while parsers:
        for action in parsers.pop()._actions:
            if isinstance(action, argparse._SubParsersAction):
                parsers += action.choices.values()
            elif action.metavar in FILE_METAVARS:
                action.complete = shtab.FILE  # type: ignore[attr-defined]  # shtab's attribute on argparse's Action
    print(shtab.complete(parser, shell=words[0]))
    return EXIT_OK


def _command_in(argv: list[str]) -> str | None:
    """The command ``argv`` names: its first word that is not an option (the top level has no valued options)."""
    first = next((word for word in argv if not word.startswith("-")), None)
    return first if first in COMMANDS else None
