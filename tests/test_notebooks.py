"""The notebooks run: their code cells executed in order (no Jupyter needed), figures drawn off-screen."""

import json
import warnings
from pathlib import Path

import matplotlib
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[path.stem for path in NOTEBOOKS])
def test_notebook_runs(notebook, monkeypatch):
    import brdffit

    matplotlib.use("Agg")
    monkeypatch.chdir(notebook.parent)
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    namespace: dict = {"__name__": "__notebook__"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", brdffit.UncertaintyWarning)  # the notebook shows them on purpose
        for cell in cells:
            if cell["cell_type"] == "code":
                exec(compile("".join(cell["source"]), f"{notebook.name}", "exec"), namespace)
    import matplotlib.pyplot as plt

    assert plt.get_fignums(), "the notebook draws figures"
    plt.close("all")
