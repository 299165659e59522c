"""Measurements: the :class:`~brdffit.data.samples.Samples` container and the formats it is read from and written to.

``load.py`` is the one place that knows every format (``csv.py``, ``merl.py``, ``alta.py``, ``astm.py``);
``checks.py`` and ``text.py`` hold what the readers share; ``quantities.py`` and ``spectral.py`` turn what
a file holds into BRDF values per channel. Imports only ``physics`` (for geometry), and no JAX.
"""
