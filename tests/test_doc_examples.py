"""Every command-line example in the README and docs/ whose output is shown, and whose input ships with brdffit, is run
and its output compared with the page's: the words exactly, the numbers to the digits printed (a relative 1e-3, the
printed 4 to 6 significant digits, and an absolute 1e-9 for zeros), so that a page cannot drift from what the command
says. An example is a line ``$ brdffit …`` in a fenced block, its output the lines up to the next ``$`` or the fence;
a line ``…`` stands for any lines. Examples of inputs that do not ship (``oak.csv`` stands for any samples file),
and those with pipes or redirections, are not run (:func:`runnable`)."""

import re
import shlex
import shutil
from pathlib import Path

import pytest
from paths import ROOT

from brdffit.cli import main

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: The suffixes of the files an example reads or writes.
FILE_SUFFIXES = (".csv", ".dat", ".json", ".binary", ".astm", ".npz", ".xml", ".gltf", ".glb", ".png", ".html", ".txt")
#: Names the pages give the shipped files: ``oak.csv`` is the oak example.
ALIASES = {"oak.csv": "ward-pickled-oak.csv", "oak2.csv": "ward-pickled-oak.csv"}
#: A number as a page prints it.
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
#: Printed numbers agree to this (relative): the 4 to 6 significant digits the tables print, with a rounding's room.
RELATIVE = 1e-3


def examples():
    """``(page, line number, command, expected output lines)`` of every example with output."""
    found = []
    for page in PAGES:
        lines = page.read_text(encoding="utf-8").splitlines()
        inside = False
        for number, line in enumerate(lines):
            if line.startswith("```"):
                inside = not inside
                continue
            if inside and line.startswith("$ brdffit "):
                output = []
                for following in lines[number + 1 :]:
                    if following.startswith(("```", "$ ")):
                        break
                    output.append(following)
                if output:
                    found.append((page, number + 1, line[2:], output))
    return found


def runnable(command: str) -> bool:
    """Whether the example runs as written: no pipe or redirection, no continued line, and every file it reads
    ships in ``examples/`` (the first file word is its input; the others are written)."""
    if any(mark in command for mark in ("|", ">", "\\")):
        return False
    words = shlex.split(command)
    if words[:2] == ["brdffit", "models"]:
        return True
    shipped_folders = [word for word in words if word.startswith("examples/") and (ROOT / word).is_dir()]
    files = [word for word in words if word.lower().endswith(FILE_SUFFIXES) or word in shipped_folders]
    return bool(files) and (ROOT / "examples" / ALIASES.get(Path(files[0]).name, Path(files[0]).name)).exists()


CASES = [case for case in examples() if runnable(case[2])]
#: Commands whose examples take a minute (``report`` compares every model and estimates errors): run with the heavy
#: cases (``make test-heavy``).
SLOW = ("report",)
#: Commands whose examples take ten seconds or more (``compare`` fits every candidate on every fold): marked ``slow``
#: (``make test-slow``, which CI runs too).
TENS_OF_SECONDS = ("compare",)


def _marks(command: str):
    """``heavy`` for a command of :data:`SLOW`, ``slow`` for one of :data:`TENS_OF_SECONDS`."""
    return pytest.mark.heavy if command in SLOW else pytest.mark.slow if command in TENS_OF_SECONDS else ()


def _skeleton(line: str) -> tuple[str, list[float]]:
    return NUMBER.sub("#", line.rstrip()), [float(number) for number in NUMBER.findall(line)]


def _same(expected: str, actual: str) -> bool:
    (text, numbers), (got_text, got) = _skeleton(expected), _skeleton(actual)
    return (
        text == got_text
        and len(numbers) == len(got)
        and all(abs(a - b) <= max(RELATIVE * max(abs(a), abs(b)), 1e-9) for a, b in zip(numbers, got, strict=True))
    )


def matches(expected: list[str], actual: list[str]) -> str | None:
    """None where ``actual`` is ``expected`` (``…`` lines matching any lines), else the first expected line not
    found where it should be."""
    position = 0
    skipping = False
    for line in expected:
        if line.strip() == "…":
            skipping = True
            continue
        while position < len(actual) and skipping and not _same(line, actual[position]):
            position += 1
        if position >= len(actual) or not _same(line, actual[position]):
            return line
        position += 1
        skipping = False
    return None if skipping or position == len(actual) else f"(more output: {actual[position]})"


@pytest.mark.parametrize(
    ("page", "number", "command", "expected"),
    [pytest.param(*case, marks=_marks(case[2].split()[1]), id=f"{case[0].name}:{case[1]}") for case in CASES],
)
def test_a_pages_example_says_what_the_command_says(page, number, command, expected, tmp_path, monkeypatch, capsys):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    for shipped in (ROOT / "examples").iterdir():
        if shipped.is_file():  # a capture (a folder) is named as examples/…
            shutil.copy(shipped, tmp_path / shipped.name)
    for alias, shipped in ALIASES.items():
        shutil.copy(ROOT / "examples" / shipped, tmp_path / alias)
    monkeypatch.chdir(tmp_path)
    words = [word.replace("/tmp/", f"{tmp_path}/") for word in shlex.split(command)[1:]]
    main(words)
    out, err = capsys.readouterr()
    actual = [line.replace(f"{tmp_path}/", "/tmp/") for line in (out + err).splitlines()]
    missing = matches(expected, actual)
    assert missing is None, (
        f"{page.name}:{number}: {command}\nexpected line: {missing}\nthe command says:\n" + "\n".join(actual)
    )


def test_the_examples_that_run_cover_the_shipped_inputs():
    """The check is not empty: examples of both shipped measurements (the oak example, the tape) run, and ``models``."""
    commands = [command for _, _, command, _ in CASES]
    assert any("ward-pickled-oak.csv" in command for command in commands)
    assert any("retro-gray-tape.dat" in command for command in commands)
    assert "brdffit models" in commands
    assert any("svbrdf fit examples/ward-capture" in command for command in commands)
