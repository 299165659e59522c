"""The exception and the warnings users see.

:class:`BrdfInputError` is bad input: one line that names the file (or the argument), the row and column
where there is one, what was wrong and what is allowed. A message about an argument names it the way the
caller wrote it: the library speaks of Python arguments (``n_starts=0 is not allowed``), the command line
of its flags (``--starts 0 is not allowed``). Messages are built from text and :class:`Argument` parts, and
each interface spells the arguments its own way: Python here, the command line in ``brdffit/cli`` (the one
place that knows the flags).

The warnings, one line each and spelled the same way: :class:`InputWarning` (input read, but worth a look:
a header overridden, angles that look like radians read as degrees), :class:`FitWarning` (what a user must
know about a fit: a dead lobe, a parameter at a plausible bound, data that are not reciprocal; also the
result's ``fit.warnings``) and :class:`UncertaintyWarning` (an estimate that needs care: a degenerate pair,
an undetermined parameter, a short chain; also the result's ``uncertainty.warnings``).
"""

import contextlib
import os
import sys
import threading
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import FrameType


@dataclass(frozen=True)
class Argument:
    """An argument a message speaks of: its Python name and, where the message quotes it, the value as shown (written
    with ``str``)."""

    name: str
    shown: object = None

    @classmethod
    def given(cls, name: str, value) -> "Argument":
        """The argument ``name`` with ``value`` shown as Python writes it (``repr``)."""
        return cls(name, repr(value))

    def in_python(self) -> str:
        """``n_starts=0``, or ``n_starts`` without a value."""
        return self.name if self.shown is None else f"{self.name}={self.shown}"


class Spelled(Exception):
    """A message built from ``parts``, each a piece of text or an :class:`Argument`; ``str()`` spells the
    arguments as Python does, :meth:`spelled` as any caller wants. The base of brdffit's errors and warnings, each
    also a subclass of a built-in one (``ValueError``, ``UserWarning``, …)."""

    def __init__(self, *parts: "str | Argument"):
        self.parts = parts
        super().__init__(self.spelled(Argument.in_python))

    def spelled(self, spell: Callable[[Argument], str]) -> str:
        """The message with every argument written by ``spell``."""
        return "".join(part if isinstance(part, str) else spell(part) for part in self.parts)


class BrdfInputError(Spelled, ValueError):
    """Bad input: a file, an argument or a parameter value that brdffit cannot accept."""


class BrdfWriteError(Spelled, OSError):
    """A file that could not be written (a full disk, a folder that cannot be written): one line naming it."""


class InputWarning(Spelled, UserWarning):
    """Input brdffit read, but that a user should check: a file header overridden, angles that look mistaken."""


class FitWarning(Spelled, UserWarning):
    """What a user must know about a fit before trusting it; the same lines are the result's ``fit.warnings``."""


def not_allowed(name: str, value, allowed: str, verb: str = "is not allowed") -> BrdfInputError:
    """``name=value is not allowed; <allowed>``: the usual message for an argument's bad value."""
    return BrdfInputError(Argument.given(name, value), f" {verb}; {allowed}")


def not_a_choice(name: str, value, choices, verb: str = "is not allowed") -> BrdfInputError:
    """``name='x' is not allowed; choose one of: a, b, c``."""
    return not_allowed(name, value, f"choose one of: {', '.join(choices)}", verb)


class UncertaintyWarning(Spelled, UserWarning):
    """An uncertainty estimate that needs care: a degenerate pair, an undetermined parameter, a short chain."""

    #: The finding's code (``uncertainty/findings.py``), attached to the warnings an estimate issues.
    code: str


#: brdffit's own folder: frames of its files are skipped when a warning names where it was raised (:func:`warn`).
_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def warn(warning: Warning) -> None:
    """Issue ``warning`` at the line of the code that called brdffit (the first frame outside this package), so that the
    message, and a filter by module, name the user's line rather than brdffit's own (Python 3.12's
    ``skip_file_prefixes``, for 3.11 as well). Inside :func:`warnings_deferred` on this thread: kept, not issued."""
    kept = getattr(_deferred, "warnings", None)
    if kept is not None:
        kept.append(warning)
        return
    frame: FrameType | None
    frame, level = sys._getframe(1), 2
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    warnings.warn(warning, stacklevel=level)


_deferred = threading.local()


@contextlib.contextmanager
def warnings_deferred() -> Iterator[list[Warning]]:
    """Within, :func:`warn` on this thread keeps its warnings in the list given instead of issuing them. A thread that
    works for a caller (a fit's reciprocity check, ``data.reciprocity.ReciprocityAhead``) hands them over, and the
    caller issues each (:func:`warn`) where the user's code called it: issued in the thread, a warning would name
    ``threading.py``'s line and escape the caller's filters by module."""
    kept: list[Warning] = []
    outer = getattr(_deferred, "warnings", None)
    _deferred.warnings = kept
    try:
        yield kept
    finally:
        _deferred.warnings = outer


def needs(module: str, extra: str, what: str):
    """The optional ``module``, imported, or a one-line error naming what needs it and the extra that installs it:
    ``the figures need matplotlib, which is not installed: pip install 'brdffit[plots]'``."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise BrdfInputError(f"{what} need {module}, which is not installed: pip install 'brdffit[{extra}]'") from None
