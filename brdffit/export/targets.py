"""The export targets, by the name ``brdffit export --to`` takes: what each writes, in which formats, and how.

Every writer imports its module when it runs, so naming the targets (``brdffit export --help``) costs nothing.
"""

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..checks import choice
from ..errors import Argument, BrdfInputError


@dataclass(frozen=True)
class Target:
    """An export target: ``description``, its ``formats`` (name → default suffix, the first the default) and
    ``write(result, path, format, samples, bin_centres) -> lines``, the lines a user should read (exact or how far,
    how far from the data when ``samples`` are given, notes); ``bin_centres`` applies to MERL's table alone."""

    description: str
    formats: dict[str, str]
    write: Callable


def _mitsuba(result, path: Path, kind: str, samples, bin_centres: bool = False) -> list[str]:
    from .._files import write_text_atomic
    from .mitsuba import mitsuba_bsdf

    exported = mitsuba_bsdf(result)
    if samples is not None:
        exported = exported.compared_with(result, samples)
    write_text_atomic(path, exported.to_xml() if kind == "xml" else exported.to_python())
    return exported.comment_lines()[1:]


def _gltf(result, path: Path, kind: str, samples, bin_centres: bool = False) -> list[str]:
    from .gltf import write_gltf

    _, approximation, notes = write_gltf(result, path, binary=kind == "glb", samples=samples)
    if any(note.startswith("exact") for note in notes):  # a gltf fit: its numbers written, nothing fitted
        return [*notes, f"the written material against the fit: {approximation.line()}"]
    return [f"approximate: the glTF BRDF fitted to it, {approximation.line()}", *notes]


def _merl(result, path: Path, kind: str, samples, bin_centres: bool = False) -> list[str]:
    from .at_data import data_error
    from .merl import merl_brdf, write_merl

    notes = write_merl(result.model, result.params, path, bin_centres=bin_centres, **result.model_options)
    if samples is not None:  # the table as it was written, read back: after the write, which cannot hold it
        written = merl_brdf(path, bin_centres)
        notes.insert(0, data_error(result, samples, written, "the written table, read back by brdffit").line())
    return ["exact: the fitted model tabulated", *notes]


#: The targets: Mitsuba 3 (XML for ``mitsuba.load_file``, or a Python dictionary for ``mitsuba.load_dict``),
#: glTF 2.0 (JSON ``.gltf`` or binary ``.glb``) and MERL.
TARGETS = {
    "mitsuba": Target("a Mitsuba 3 BSDF", {"xml": ".xml", "dict": ".mitsuba.py"}, _mitsuba),
    "gltf": Target(
        "a glTF 2.0 material (pbrMetallicRoughness) on a preview sphere", {"gltf": ".gltf", "glb": ".glb"}, _gltf
    ),
    "merl": Target("a MERL table (90 × 90 × 180 bins)", {"binary": ".binary"}, _merl),
}


def export_format(to: str, format: str | None = None, path: str | os.PathLike | None = None) -> str:
    """The format a target writes: ``format`` if the target takes it; else the one whose suffix ``path`` ends
    with, if any; else the target's first. One-line errors for a format the target does not write, and for a
    ``path`` whose suffix is another of the target's formats' (``--format glb -o oak.gltf``); a path that ends with
    none of them is :func:`check_suffix`'s."""
    choice("to", to, TARGETS)
    formats = TARGETS[to].formats
    named = _named_format(formats, path)
    kind = format or named or next(iter(formats))
    if kind not in formats:
        raise BrdfInputError(
            Argument("format", kind), f" does not apply to target {to}; it writes {', '.join(formats)}"
        )
    if named is not None and path is not None and named != kind:  # named: path ends with a format's suffix
        raise BrdfInputError(
            Argument("format", kind),
            f" writes {formats[kind]} files, not {Path(path).name} (a {named} file's name); name it"
            f" {Path(path).name[: -len(formats[named])]}{formats[kind]} or leave the format out",
        )
    return kind


def check_suffix(to: str, path: str | os.PathLike, standard_output: bool = False) -> None:
    """A one-line error for a file ``path`` whose name ends with none of the suffixes of the target ``to``'s formats:
    ``--to mitsuba -o oak.json`` would put XML where every other command reads a result, ``--to merl -o oak.csv`` a
    binary table where they read samples. ``standard_output``: ``-`` is standard output (the command's ``-o -``),
    not a file named ``-``."""
    choice("to", to, TARGETS)
    formats = TARGETS[to].formats
    if not (standard_output and str(path) == "-") and _named_format(formats, path) is None:
        written = " or ".join(f"{suffix} ({kind})" for kind, suffix in formats.items())
        raise BrdfInputError(
            Argument("path", str(path)), f": a {to} export is written to a {written} file; give the file that name"
        )


def _named_format(formats: dict[str, str], path: str | os.PathLike | None) -> str | None:
    """The format among ``formats`` (name → suffix) whose suffix ``path``'s name ends with, or None."""
    return next((kind for kind, suffix in formats.items() if path and str(path).lower().endswith(suffix)), None)


def export(
    result, to: str, path: str | os.PathLike, format: str | None = None, samples=None, *, bin_centres: bool = False
) -> list[str]:
    """Write ``result`` (a :class:`~brdffit.FitResult`) for the renderer ``to`` (:data:`TARGETS`) to ``path``,
    atomically, in ``format`` (default: the one ``path``'s suffix names, else the target's first:
    :func:`export_format`); returns the lines a user should read (whether it is exact, how far it lies otherwise,
    notes). ``path`` is written as it is: ``brdffit.export`` and ``brdffit export`` refuse a name without the
    target's suffixes first (:func:`check_suffix`; the command checks the name given, whose link it then resolves).
    ``samples``: the data the fit was made from (a :class:`~brdffit.Samples` or a file, read as the fit read it), at
    whose directions the export is evaluated as its renderer evaluates it and compared (``at_data.py``): printed
    first, and stored in the file where the format has room (Mitsuba's, glTF's). ``bin_centres`` (MERL): each bin
    evaluated at its centre, not its lower edge (``physics/merl_table.py``)."""
    kind = export_format(to, format, path)
    if bin_centres and to != "merl":
        raise BrdfInputError(Argument("bin_centres"), f" applies to MERL tables (to='merl'), not to {to}")
    if samples is not None:
        from .at_data import data_for

        samples = data_for(result, samples)
    return TARGETS[to].write(result, Path(path), kind, samples, bin_centres)
