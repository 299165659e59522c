"""A fit: losses, the problem as padded arrays, data-driven starts, the Levenberg-Marquardt solver, the result.

``fit.py`` fits one dataset (:func:`~brdffit.fitting.fit.fit_one`), ``batch.py`` many
(:func:`~brdffit.fitting.batch.fit_many`); the public ``brdffit.fit`` and ``fit_batch`` (``brdffit/api.py``)
add the uncertainty on top. Imports ``physics`` and ``data``.
"""
