"""Pages of the documentation whose code is meant to run as it stands: it runs here, in a fresh interpreter."""

import re
import subprocess
import sys

import pytest
from paths import ROOT


def python_blocks(page: str) -> str:
    """The ``python`` code blocks of a page, in order, as one program."""
    return "\n\n".join(re.findall(r"```python\n(.*?)```", (ROOT / "docs" / page).read_text(), re.S))


@pytest.mark.slow
def test_adding_a_model_defines_registers_and_fits_a_model_that_is_not_built_in():
    code = python_blocks("adding-a-model.md")
    assert "register_model" in code and "brdffit.fit(" in code
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "gaussian fit" in run.stdout and "converged" in run.stdout


def test_the_api_reference_is_the_codes():
    """``docs/reference.md`` is written from the code (``docs/reference.py``): it cannot drift from the signatures."""
    run = subprocess.run([sys.executable, "docs/reference.py", "--check"], cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 0, "docs/reference.md or api.md is out of date: run `make docs` (python docs/reference.py)"


def test_the_docs_site_builds_strictly(tmp_path):
    """``make docs``'s site (``mkdocs.yml``: the pages, the API from the docstrings by mkdocstrings, the files outside
    ``docs/`` they link to) builds with ``--strict``: a broken link, a page left out of the navigation or a reference
    mkdocstrings cannot resolve fails it. The API page lists every public name (``docs/reference.py``)."""
    pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install 'brdffit[docs]'; the test extra has it)")
    site = tmp_path / "site"
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    api = (site / "api" / "index.html").read_text()
    assert ":::" not in api and all(f'id="brdffit.{name}"' in api for name in ("fit", "compare", "FitResult", "export"))
    assert (site / "repository" / "benchmarks" / "results" / "exports" / "index.html").exists()  # linked from export.md


def documented_calls(page: str) -> list[tuple[str, str]]:
    """``name(arguments)`` of every public function the page's tables show with its arguments."""
    import brdffit

    text = (ROOT / "docs" / page).read_text()
    calls = re.findall(r"^\| `(?:brdffit\.)?((?:svbrdf\.)?\w+)\(((?:[^()]|\([^()]*\))*)\)`", text, re.M)
    # A call that starts with … is an example of use (``fit(…, uncertainty="laplace")``), not a signature.
    return [
        (name, arguments)
        for name, arguments in calls
        if name.split(".")[0] in brdffit.__all__ and arguments[:1] not in "…"
    ]


def public(name: str):
    """``brdffit.<name>``, where ``name`` may name a module's member (``svbrdf.fit``)."""
    import brdffit

    value = brdffit
    for part in name.split("."):
        value = getattr(value, part)
    return value


def top_level_parts(arguments: str) -> list[str]:
    """``arguments`` split at the commas outside brackets."""
    parts, depth, current = [], 0, ""
    for character in arguments:
        depth += (character in "([{" and 1) or 0
        depth -= (character in ")]}" and 1) or 0
        if character == "," and depth == 0:
            parts.append(current.strip())
            current = ""
        else:
            current += character
    return [*parts, current.strip()]


@pytest.mark.parametrize("name, arguments", documented_calls("python.md"), ids=lambda value: str(value)[:30])
def test_the_guides_signatures_are_the_codes(name, arguments):
    """Each call the Python guide writes out names the function's parameters in order, with their defaults; one
    written with ``…`` may leave some out."""
    import inspect

    parameters = inspect.signature(public(name)).parameters
    written = [part for part in top_level_parts(arguments) if part not in ("*", "…", "")]
    names = [part.split("=")[0].lstrip("*") for part in written]
    real = [key for key in parameters if key in names]
    assert real == names, f"{name}: the guide writes {names}, the code takes {list(parameters)}"
    if "…" not in arguments:
        assert names == list(parameters), f"{name}: the guide leaves out {sorted(set(parameters) - set(names))}"
    for part in written:
        key, equals, default = part.partition("=")
        if not equals or default == "…":
            continue
        code_default = parameters[key].default
        if code_default is not inspect.Parameter.empty and repr(code_default) != "<factory>":
            assert default.replace('"', "'") == repr(code_default), f"{name}: {key}'s default"


def test_the_time_table_of_a_single_fit_is_the_benchmarks():
    """docs/scale.md's table of where a fit's time goes is the last ``make bench-phases`` (which writes both)."""
    page = (ROOT / "docs" / "scale.md").read_text()
    table = page.split("<!-- phases: made by benchmarks/phases.py -->\n")[1].split("<!-- phases: end -->")[0]
    assert table == (ROOT / "benchmarks" / "results" / "phases.md").read_text()
