"""The notebooks run: their code cells executed in order (no Jupyter needed), figures drawn off-screen.

A cell's last expression is evaluated as Jupyter would display it; every figure shown (returned by a cell, or drawn
with pyplot) must render to pixels that are finite and not blank.
"""

import ast
import json
import warnings
from pathlib import Path

import matplotlib
import numpy as np
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))


def run_cell(source: str, name: str, namespace: dict):
    """Execute a cell; return the value of its last expression (what Jupyter displays), or None. IPython's magics
    (``%matplotlib inline``: show figures made without pyplot) are Jupyter's business and are left out here."""
    source = "".join(line for line in source.splitlines(keepends=True) if not line.lstrip().startswith("%"))
    tree = ast.parse(source)
    last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
    exec(compile(tree, name, "exec"), namespace)
    if last is None:
        return None
    return eval(compile(ast.Expression(last.value), name, "eval"), namespace)


@pytest.mark.slow
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[path.stem for path in NOTEBOOKS])
def test_notebook_runs(notebook, monkeypatch):
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    import brdffit

    matplotlib.use("Agg")
    monkeypatch.chdir(notebook.parent)
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    namespace: dict = {"__name__": "__notebook__"}
    shown = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", brdffit.UncertaintyWarning)  # the notebooks show them on purpose
        warnings.simplefilter("ignore", brdffit.FitWarning)  # the losing models' caveats, shown in the comparison
        for cell in cells:
            if cell["cell_type"] == "code":
                value = run_cell("".join(cell["source"]), notebook.name, namespace)
                if isinstance(value, Figure):
                    shown.append(value)
    shown += [plt.figure(number) for number in plt.get_fignums()]
    assert shown, "the notebook draws figures"
    for figure in shown:
        canvas = FigureCanvasAgg(figure)
        canvas.draw()
        pixels = np.asarray(canvas.buffer_rgba(), dtype=float)
        assert np.all(np.isfinite(pixels)) and pixels.std() > 0
    plt.close("all")


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[path.stem for path in NOTEBOOKS])
def test_notebook_keeps_the_outputs_of_its_code(notebook):
    """The file holds what Jupyter showed for the code as it is (``make notebooks``): its code cells run in order, each
    with an output and none an error, and the code unchanged since (the digest ``notebooks/execute.py`` recorded)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("execute", notebook.parent / "execute.py")
    execute = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(execute)
    document = json.loads(notebook.read_text(encoding="utf-8"))
    code = [cell for cell in document["cells"] if cell["cell_type"] == "code"]
    recorded = document["metadata"].get("brdffit", {}).get("code_digest")
    assert recorded == execute.code_digest(document["cells"]), "code changed since its outputs: run make notebooks"
    assert [cell["execution_count"] for cell in code] == list(range(1, len(code) + 1))
    for cell in code:
        source = "".join(cell["source"])
        assert cell["outputs"], f"no output kept: {source[:60]!r}"
        assert not [output for output in cell["outputs"] if output["output_type"] == "error"], source[:60]
