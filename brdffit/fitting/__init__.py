"""Fitting, one room per concept, each using only the rooms before it:

``objective/``   what is minimised: losses, the data as padded arrays, residuals and normal equations
``solver/``      Levenberg-Marquardt (independent of BRDFs), held parameters, the compiled solve of a fit
``starts/``      data-driven starting points: variable projection over a grid, lobes one at a time
``single/``      one fit, start → solve → caveats → result, and the result file
``many/``        many datasets: buckets, batches, threads, a Dask cluster
``comparison/``  which model suits the data: cross-validation, AIC, BIC

The public ``brdffit.fit`` and ``fit_batch`` (``brdffit/api.py``) add the uncertainty on top. Imports ``physics``,
``data`` and the data-driven model's fit (``brdffit/datadriven/fit.py``).
"""

import importlib
import importlib.abc
import importlib.util
import sys

#: Modules by the paths the documentation once gave them, and where they live now: ``from brdffit.fitting.fit import
#: compiled_solver``, ``brdffit.fitting.compare.load_comparison`` and results pickled by an older brdffit still work.
#: New code imports from the rooms (or the public names from ``brdffit``).
MOVED = {
    "compare": "comparison.compare",
    "fit": "single.fit",
    "losses": "objective.losses",
    "problem": "objective.problem",
    "results": "single.result",
}


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``brdffit.fitting.<old name>`` as the module of :data:`MOVED`, the same module object under both names."""

    def find_spec(self, fullname, path=None, target=None):
        package, _, name = fullname.rpartition(".")
        return importlib.util.spec_from_loader(fullname, self) if package == __name__ and name in MOVED else None

    def create_module(self, spec):
        module = importlib.import_module(f"{__name__}.{MOVED[spec.name.rpartition('.')[2]]}")
        spec.loader_state = module.__spec__  # its own, which the import system replaces by this one
        return module

    def exec_module(self, module):
        """Nothing to run (the module was imported under its own name); but the import system has set the module's
        ``__spec__`` to the old name's, which would make its relative imports look elsewhere: its own is put back."""
        module.__spec__ = module.__spec__.loader_state


if not any(isinstance(finder, _MovedModules) for finder in sys.meta_path):
    sys.meta_path.append(_MovedModules())
