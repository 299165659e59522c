"""What only some users install (the extras: plots, render, hdf5, cluster): a command that needs a missing one ends
in one line naming the extra, with exit status 2 and nothing written, before its work. The missing library is
simulated in a fresh process (``sys.modules[name] = None`` makes its import fail as an absent one does)."""

import subprocess
import sys

import pytest
from paths import EXAMPLE, ROOT

from brdffit import FitResult

LAMBERT = FitResult("lambert", {}, ("r", "g", "b"), {"rho_d": [0.2, 0.3, 0.4]}, "log", 0.0, 0.0, 1, 0, True)


def run_without(module: str, argv: list[str], cwd) -> subprocess.CompletedProcess:
    code = f"import sys; sys.modules[{module!r}] = None; from brdffit.cli import main; sys.exit(main({argv!r}))"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.mark.parametrize(
    ("module", "argv", "said"),
    [
        ("matplotlib", ["plot", "fit.json", str(EXAMPLE), "-o", "out.png"], "brdffit's figures need matplotlib"),
        (
            "corner",
            [
                "fit",
                str(EXAMPLE),
                "--model",
                "lambert",
                "--uncertainty",
                "laplace",
                "--corner",
                "out.png",
                "-o",
                "r.json",
            ],
            "corner plots need corner",
        ),
        ("matplotlib", ["render", "fit.json", "-o", "out.png"], "PNG images need matplotlib"),
        (
            "h5py",
            ["fit", str(EXAMPLE), "--model", "lambert", "--uncertainty", "mcmc", "--chain", "out.h5", "-o", "r.json"],
            "HDF5 needs h5py",
        ),
    ],
)
def test_a_missing_extra_is_one_line_naming_it_before_the_work(module, argv, said, tmp_path):
    (tmp_path / "fit.json").write_text(LAMBERT.to_json())
    done = run_without(module, argv, tmp_path)
    extra = {"matplotlib": "plots", "corner": "plots", "h5py": "hdf5"}[module]
    extra = "render" if argv[0] == "render" else extra
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and said in lines[0] and f"pip install 'brdffit[{extra}]'" in lines[0], done.stderr
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]  # nothing written


def test_the_core_imports_none_of_the_extras():
    """``import brdffit``, a fit and its result need no extra: the core install (pyproject's dependencies) is enough."""
    code = (
        "import sys\n"
        "for name in ('matplotlib', 'corner', 'h5py', 'mitsuba', 'dask', 'pandas'):\n"
        "    sys.modules[name] = None\n"
        "import brdffit\n"
        f"result = brdffit.fit({str(EXAMPLE)!r}, 'ward')\n"
        "print(result.fit_report().splitlines()[0])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0 and done.stdout.startswith("[[Model]]"), done.stderr
