"""Pages of the documentation whose code is meant to run as it stands: it runs here, in a fresh interpreter."""

import re
import subprocess
import sys

from paths import ROOT


def python_blocks(page: str) -> str:
    """The ``python`` code blocks of a page, in order, as one program."""
    return "\n\n".join(re.findall(r"```python\n(.*?)```", (ROOT / "docs" / page).read_text(), re.S))


def test_adding_a_model_defines_registers_and_fits_a_model_that_is_not_built_in():
    code = python_blocks("adding-a-model.md")
    assert "register_model" in code and "brdffit.fit(" in code
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "gaussian fit" in run.stdout and "converged" in run.stdout
