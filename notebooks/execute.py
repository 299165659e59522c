"""Run the notebooks in Jupyter's own kernel and keep their outputs in the files (``make notebooks``).

    .venv/bin/python notebooks/execute.py [NOTEBOOK ...]     # default: every notebooks/*.ipynb

Each notebook runs from its own folder (as ``jupyter lab notebooks/`` opens it), in a fresh ``python3`` kernel
(ipykernel, in this virtual environment), cell by cell with at most :data:`CELL_SECONDS` each; a cell that fails stops
the run with its error, and the file is left as it was. The executed notebook replaces the file atomically. Its
outputs are what a reader sees on a code host without running anything: the tables, the figures (PNG), the warnings.
The notebook's metadata records a digest of its code cells (:func:`code_digest`), so that
``tests/test_notebooks.py`` can check that the outputs are those of the code as it is (a cell edited since the last
run fails it), that every code cell kept its output and that none is an error.
"""

import argparse
import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

#: The longest one cell may run (seconds): the tape notebook's comparison of six models takes about a minute cold.
CELL_SECONDS = 900
NOTEBOOKS = Path(__file__).resolve().parent


def code_digest(cells: list[dict]) -> str:
    """SHA-256 of the notebook's code cells' sources, in order (``cells``: the file's JSON cells)."""
    sources = ["".join(cell["source"]) for cell in cells if cell["cell_type"] == "code"]
    return hashlib.sha256(json.dumps(sources).encode()).hexdigest()


def execute(path: Path) -> None:
    """Run the notebook at ``path`` in a fresh kernel and write it back with its outputs."""
    import nbclient
    import nbformat

    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=CELL_SECONDS, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()
    notebook.metadata["brdffit"] = {"code_digest": code_digest(notebook.cells)}
    with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".ipynb", delete=False, encoding="utf-8") as out:
        nbformat.write(notebook, out)
    os.chmod(out.name, path.stat().st_mode & 0o777)  # the file's own mode, not the temporary file's 0600
    os.replace(out.name, path)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("notebooks", nargs="*", type=Path, help="notebooks to run (default: notebooks/*.ipynb)")
    paths = parser.parse_args().notebooks or sorted(NOTEBOOKS.glob("*.ipynb"))
    for path in paths:
        print(f"running {path}", flush=True)
        execute(path.resolve())
    return 0


if __name__ == "__main__":
    sys.exit(main())
