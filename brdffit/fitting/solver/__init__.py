"""The solver: Levenberg-Marquardt on optimistix (``levenberg_marquardt.py``, independent of BRDFs), the
coordinates it moves when parameters are held (``hold.py``), derivatives of an optimum with respect to its data
(``implicit.py``), and one compiled solve of a BRDF fit with its tolerances and outcomes (``compiled.py``)."""
