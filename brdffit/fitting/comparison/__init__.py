"""Which model suits a measurement: every candidate fitted and ranked by cross-validation, AIC and BIC, and the
printed ranking (``compare.py``); the folds, whole light directions held out where the data allow (``folds.py``)."""
