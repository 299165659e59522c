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

#: Modules the documentation once named by their old paths (``brdffit.fitting.compare.load_comparison``), kept as
#: attributes of this package where they live now; new code imports them from their rooms, or the names from brdffit.
_MOVED = {"compare": ".comparison.compare", "losses": ".objective.losses", "problem": ".objective.problem"}


def __getattr__(name: str):
    if name in _MOVED:
        return importlib.import_module(_MOVED[name], __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
