"""The files a command reads and writes, declared in one place and checked together before any work.

Each command module has ``files(args) -> Files``: every file it reads (samples, ``--start``, ``--basis``, ``--params``,
``--directions``, ``--samples``, a result…) and every file it writes (``-o`` and its default name, ``--chain``,
``--corner``…), each under the option that names it. ``main`` calls it and :meth:`Files.check` before the command runs,
so an option added to a command is checked as soon as it is declared there, and ``tests/cli/test_collisions.py`` fails
while any option that takes a file is not.

The rule: every input is a file (or a folder), not a device or a pipe (``-``, standard input, is read into a file first:
below); no output is an input (the user's data is never overwritten) and no two outputs are one file (the later would
replace the earlier, and the run would still say it wrote both). Paths are compared as the operating system resolves
them: two existing files by :func:`os.path.samefile` (a link, a hard link, another spelling of the same folder),
anything else by its resolved path.

**Standard input and output**: ``-``, in every command. An input given as ``-`` (a samples file, a result, ``--params``,
``--start``, ``--samples``…) is standard input, read once (it is one stream) into a temporary file that the command
reads as it reads any file: every format, every check. An output given as ``-`` (``-o -``, ``convert``'s ``OUT``) is
written to a temporary file, atomically as every output is, and copied to standard output once the command has written
it, byte for byte (a PNG or a MERL table too); while a command sends a product there, what it prints goes to standard
error, so that standard output holds the product alone. Messages name ``-`` where they would name a temporary file.
Outside a command (:func:`standard_streams`), ``-`` is a file name like any other.
"""

import os
import shutil
import sys
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager, redirect_stdout
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import overload

from ..errors import BrdfInputError, BrdfWriteError, Spelled

#: A path as a command has it: a string or path object; None (an option not given) declares nothing.
PathOrNone = str | os.PathLike | None


@dataclass(frozen=True)
class Files:
    """The files of one run of a command, each as ``(option, path)``: the option as the user would type it
    (``-o``, ``--chain``, ``SAMPLES``), the path as given (for messages)."""

    inputs: tuple[tuple[str, str], ...] = field(default=())
    outputs: tuple[tuple[str, str], ...] = field(default=())

    @classmethod
    def of(
        cls,
        inputs: Mapping[str, PathOrNone | Iterable[PathOrNone]] | None = None,
        outputs: Mapping[str, PathOrNone | Iterable[PathOrNone]] | None = None,
    ) -> "Files":
        """Files from ``{option: path, …}`` mappings; a value may be one path, several, or None (not given)."""
        return cls(_pairs(inputs or {}), _pairs(outputs or {}))

    def check(self) -> None:
        """Refuse, in one line, an input that is a device or a pipe (``/dev/zero`` never ends; a FIFO blocks, and is
        gone once read), and an output that is one of the inputs or an earlier output (nothing is written)."""
        for option, path in self.inputs:
            if path != "-" and os.path.exists(path) and not (os.path.isfile(path) or os.path.isdir(path)):
                raise BrdfInputError(f"{option} {path}: is not a regular file (a device or a pipe); give a file")
        for index, (option, path) in enumerate(self.outputs):
            if path == "-":  # standard output: no file to collide with
                continue
            for input_option, given in self.inputs:
                if given == "-":
                    continue
                if same_file(path, given):
                    raise BrdfInputError(
                        f"{option} {path}: is the input {given} ({input_option}); give another output name"
                        " (inputs are never overwritten)"
                    )
            for other_option, other in self.outputs[:index]:
                if other != "-" and same_file(path, other):
                    raise BrdfInputError(
                        f"{option} {path}: is also the output of {other_option} {other}; give each output its own name"
                    )


def same_file(one: str | os.PathLike, other: str | os.PathLike) -> bool:
    """Whether two paths name the same file, as the operating system resolves them (either may not exist yet)."""
    try:
        return os.path.samefile(one, other)
    except OSError:  # one of them does not exist (yet): the paths that links and ``..`` resolve to
        return os.path.realpath(one) == os.path.realpath(other)


def _pairs(declared: Mapping[str, PathOrNone | Iterable[PathOrNone]]) -> tuple[tuple[str, str], ...]:
    pairs = []
    for option, value in declared.items():
        values = value if isinstance(value, list | tuple) else [value]
        pairs += [(option, str(path)) for path in values if path is not None]
    return tuple(pairs)


#: Where a product sent to standard output goes: the command's standard output while what it prints goes elsewhere
#: (:func:`printing_to`); None: ``sys.stdout``.
PRODUCT_STREAM: ContextVar = ContextVar("PRODUCT_STREAM", default=None)


@contextmanager
def printing_to(stream) -> Iterator[None]:
    """What the command prints (``sys.stdout``) goes to ``stream`` meanwhile, while its product still reaches the
    command's standard output (:data:`PRODUCT_STREAM`): standard error while a product goes to standard output
    (:func:`standard_streams`), the null device for ``-q``."""
    token = PRODUCT_STREAM.set(PRODUCT_STREAM.get() or sys.stdout)
    try:
        with redirect_stdout(stream):
            yield
    finally:
        PRODUCT_STREAM.reset(token)


def write_to_standard_output(product: str | bytes) -> None:
    """A command's product written to standard output (``-o -``) and flushed: text, or bytes as they are (a PNG, a
    MERL table). A reader that went away before it (``brdffit fit … -o - | true``) is a write error, exit status 2:
    the product is lost, where a table printed into a closed pipe is not (``run``). Standard output then points at
    the null device, so that the final flush cannot fail again (:func:`_silenced`)."""
    stream = PRODUCT_STREAM.get() or sys.stdout
    try:
        if isinstance(product, str):
            stream.write(product)
        elif getattr(stream, "buffer", None) is None:  # a text stream alone (a test's capture)
            stream.write(product.decode("utf-8"))
        else:
            stream.flush()
            stream.buffer.write(product)
        stream.flush()
    except BrokenPipeError:
        _silenced(stream)
        raise BrdfWriteError(
            "-o -: standard output was closed before the result was written (its reader went away); nothing was written"
        ) from None


# ---------------------------------------------------------------------- - as standard input and output
#: How a command line names standard input or standard output.
STANDARD = "-"


@dataclass
class _Streams:
    """One command's temporary folder (made when ``-`` is first met), its copy of standard input (once read) and the
    outputs bound for standard output."""

    made: Path | None = None
    stdin: Path | None = None
    outputs: list[Path] = field(default_factory=list)

    @property
    def folder(self) -> Path:
        if self.made is None:
            self.made = Path(tempfile.mkdtemp(prefix="brdffit-streams-"))
        return self.made


_current: ContextVar[_Streams | None] = ContextVar("_current", default=None)


@contextmanager
def standard_streams(product: bool) -> Iterator[None]:
    """While a command runs: ``-`` names standard input and output (module docstring). ``product``: some output is
    standard output, so what the command prints goes to standard error meanwhile."""
    streams = _Streams()
    token = _current.set(streams)
    try:
        if not product:
            yield
        else:
            with printing_to(sys.stderr):
                yield
                for path in streams.outputs:
                    if path.exists():  # else the command wrote nothing there (a fit that is not finite: said already)
                        write_to_standard_output(path.read_bytes())
    except (BrdfInputError, BrdfWriteError) as error:  # a message that names a temporary file names "-"
        raise _renamed(error, streams) from None
    finally:
        _current.reset(token)
        if streams.made is not None:
            shutil.rmtree(streams.made, ignore_errors=True)


def check_one_standard_input(args) -> None:
    """A one-line error, before anything is read, where more than one input of the command line ``args`` is ``-``
    (every argument but ``output`` names an input where it is ``-``): standard input is one stream."""
    given = [
        name
        for name, value in vars(args).items()
        if name != "output"
        for item in (value if isinstance(value, list) else [value])
        if is_standard(item)
    ]
    if len(given) > 1:
        raise BrdfInputError("only one input can be - (standard input is one stream); give the others file names")


def is_standard(value) -> bool:
    """Whether a command-line value names standard input or output."""
    return isinstance(value, str) and value == STANDARD


@overload
def input_path(value: str) -> str: ...
@overload
def input_path(value: None) -> None: ...
def input_path(value: str | None) -> str | None:
    """The file to read for the input ``value``: itself (None too), or for ``-`` the copy of standard input (read at
    the first call; a command reads one input from it)."""
    streams = _current.get()
    if not is_standard(value) or streams is None:
        return value
    if streams.stdin is None:
        streams.stdin = streams.folder / "stdin"
        streams.stdin.write_bytes(sys.stdin.buffer.read())
    return str(streams.stdin)


def output_path(value, suffix: str = "") -> Path:
    """The file to write for the output ``value``: itself, or for ``-`` a temporary file (named with ``suffix``,
    which a writer may read its format from) copied to standard output when the command is done."""
    streams = _current.get()
    if not is_standard(value) or streams is None:
        return Path(value)
    path = streams.folder / f"stdout{suffix}"
    if path not in streams.outputs:  # asked again (a command's check of its files, then its work): the same file
        streams.outputs.append(path)
    return path


def stem(value: str) -> str:
    """The stem a default output name is made from: ``stdin`` for ``-``."""
    return "stdin" if is_standard(value) else Path(value).stem


def _silenced(stream) -> None:
    """Standard output, whose reader went away, pointed at the null device, so that the final flush cannot fail again
    (Python's documentation, "Note on SIGPIPE"): the product's own stream, not ``sys.stdout``, which may be standard
    error meanwhile (a command's lines go there while a product goes to standard output)."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())
    except (OSError, ValueError):  # a stream without a descriptor (a test's capture): nothing to point elsewhere
        pass


def _renamed(error: Spelled, streams: _Streams) -> Spelled:
    """``error`` with every temporary path of ``streams`` written as ``-``."""
    names = [str(path) for path in (streams.stdin, *streams.outputs) if path is not None]
    if not any(name in part for part in error.parts if isinstance(part, str) for name in names):
        return error
    parts = []
    for part in error.parts:
        if isinstance(part, str):
            for name in names:
                part = part.replace(name, STANDARD)
        parts.append(part)
    return type(error)(*parts)
