"""The solver: Levenberg-Marquardt on optimistix (``levenberg_marquardt.py``, independent of BRDFs, tested on NIST's
certified problems), the coordinates it moves when parameters are held (``hold.py``), and one compiled solve of a
BRDF fit with its tolerances, its outcomes and its derivatives with respect to the data (``compiled.py``)."""
