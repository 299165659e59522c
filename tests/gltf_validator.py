"""The Khronos glTF validator (npm ``gltf-validator``), run by Node.js on a file: its issues as a dictionary.

``make test`` installs it into ``.venv/node`` (the Makefile's ``validator`` target); ``GLTF_VALIDATOR`` names another
install (the package's folder). Where Node.js or the validator is absent, the tests that need it skip with a reason.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).with_name("gltf_validator.js")
MODULE = Path(os.environ.get("GLTF_VALIDATOR") or Path(sys.prefix) / "node" / "node_modules" / "gltf-validator")
NODE = shutil.which("node")

#: Skips a test where Node.js or the validator is absent (a user's machine without npm).
needs_validator = pytest.mark.skipif(
    NODE is None or not (MODULE / "package.json").is_file(),
    reason=f"the Khronos glTF validator needs Node.js and npm's gltf-validator in {MODULE} (make test installs it)",
)


def validate(path: str | os.PathLike) -> dict:
    """The validator's ``issues`` for ``path``: ``numErrors``, ``numWarnings``, ``numInfos``, ``numHints`` and the
    ``messages`` (each with ``code``, ``message``, ``severity`` 0 error … 3 hint, ``pointer``)."""
    done = subprocess.run(
        [NODE, str(SCRIPT), str(MODULE), str(path)], capture_output=True, text=True, timeout=120, check=False
    )
    assert done.returncode == 0, f"the validator failed on {path}: {done.stderr.strip()}"
    return json.loads(done.stdout)


def assert_valid(path: str | os.PathLike) -> dict:
    """Asserts that the validator finds no error and no warning in ``path``; returns its issues."""
    issues = validate(path)
    serious = [message for message in issues["messages"] if message["severity"] <= 1]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, f"{path}: {serious}"
    return issues
