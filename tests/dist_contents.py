"""What the wheel and the sdist carry (``make test-lowest`` builds both): ``python tests/dist_contents.py DIST``.

The wheel: the package (and no other top-level one), its ``py.typed`` (PEP 561) and the licence
(``license-files``). The sdist: the same and what its tests need (the tests, the examples, the Makefile and
``constraints.txt``: an sdist runs its tests, issue 30).
Prints what it checked; exits 1 naming what is missing.
"""

import sys
import tarfile
import zipfile
from pathlib import Path

WHEEL = ("brdffit/__init__.py", "brdffit/py.typed", "/licenses/LICENSE", "brdffit/data_synth/synthesize.py")
#: Top-level packages the wheel installs: brdffit alone (``data_synth`` lives inside it, issue 30).
TOP_LEVEL = {"brdffit"}
SDIST = (
    "/LICENSE",
    "/brdffit/py.typed",
    "/tests/conftest.py",
    "/tests/fitting/test_fit.py",
    "/examples/ward-pickled-oak.csv",
    "/Makefile",
    "/constraints.txt",
)


def missing(names: list[str], wanted: tuple[str, ...]) -> list[str]:
    """The entries of ``wanted`` that no name in ``names`` ends with."""
    return [end for end in wanted if not any(name.endswith(end) for name in names)]


def main(folder: Path) -> int:
    wheels, sdists = sorted(folder.glob("brdffit-*.whl")), sorted(folder.glob("brdffit-*.tar.gz"))
    if len(wheels) != 1 or len(sdists) != 1:
        print(f"{folder}: expected one wheel and one sdist, found {len(wheels)} and {len(sdists)}")
        return 1
    with zipfile.ZipFile(wheels[0]) as wheel:
        lacking = missing(wheel.namelist(), WHEEL)
        tops = {name.split("/")[0] for name in wheel.namelist() if "/" in name and ".dist-info" not in name}
    if tops != TOP_LEVEL:
        print(f"{wheels[0].name} installs {', '.join(sorted(tops))}; only {', '.join(sorted(TOP_LEVEL))} is wanted")
        return 1
    with tarfile.open(sdists[0]) as sdist:
        lacking += missing(sdist.getnames(), SDIST)
    if lacking:
        print(f"missing from {wheels[0].name} or {sdists[0].name}: {', '.join(lacking)}")
        return 1
    print(f"{wheels[0].name} and {sdists[0].name} carry LICENSE, py.typed, and (the sdist) the tests and examples")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1])))
