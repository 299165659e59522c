"""One fit, start to result (``fit.py``): the compiled programs it runs, shared with fits of many datasets
(``stacked.py``), what a user holds (``constraints.py``), what a user must know (``caveats.py``), the solve as a
result (``outcome.py``), the result, its file and its printed table (``result.py``)."""
