"""The files a command reads and writes, declared in one place and checked together before any work.

Each command module has ``files(args) -> Files``: every file it reads (samples, ``--start``, ``--basis``,
``--params``, ``--directions``, ``--samples``, a result…) and every file it writes (``-o`` and its default name,
``--chain``, ``--corner``…), each under the option that names it. ``main`` calls it and :meth:`Files.check` before
the command runs, so an option added to a command is checked as soon as it is declared there, and
``tests/cli/test_collisions.py`` fails while any option that takes a file is not.

The rule: every input is a file (or a folder), not a device or a pipe; no output is an input (the user's data is
never overwritten) and no two outputs are one file (the later would replace the earlier, and the run would still say
it wrote both). Paths are compared as the operating system resolves them: two existing files by
:func:`os.path.samefile` (a link, a hard link, another spelling of the same folder), anything else by its resolved
path.
"""

import os
import sys
from collections.abc import Iterable, Mapping
from contextvars import ContextVar
from dataclasses import dataclass, field

from ..errors import BrdfInputError, BrdfWriteError

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
            if os.path.exists(path) and not (os.path.isfile(path) or os.path.isdir(path)):
                raise BrdfInputError(f"{option} {path}: is not a regular file (a device or a pipe); give a file")
        for index, (option, path) in enumerate(self.outputs):
            for input_option, given in self.inputs:
                if same_file(path, given):
                    raise BrdfInputError(
                        f"{option} {path}: is the input {given} ({input_option}); give another output name"
                        " (inputs are never overwritten)"
                    )
            for other_option, other in self.outputs[:index]:
                if same_file(path, other):
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


#: Where a product sent to standard output goes: the stream of the command's standard output when ``-q`` sends its
#: printing to the null device (``cli._quiet``); None: ``sys.stdout``.
PRODUCT_STREAM: ContextVar = ContextVar("PRODUCT_STREAM", default=None)


def write_to_standard_output(text: str) -> None:
    """A command's product written to standard output (``-o -``) and flushed. A reader that went away before it
    (``brdffit fit … -o - | true``) is a write error, exit status 2: the product is lost, where a table printed
    into a closed pipe is not (``run``). Standard output then points at the null device, so that the final flush
    cannot fail again (Python's documentation, "Note on SIGPIPE")."""
    stream = PRODUCT_STREAM.get() or sys.stdout
    try:
        stream.write(text)
        stream.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise BrdfWriteError(
            "-o -: standard output was closed before the result was written (its reader went away); nothing was written"
        ) from None
