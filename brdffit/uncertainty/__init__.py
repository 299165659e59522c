"""Error bars of a fitted result: the posterior density, Laplace's approximation of it, and emcee's samples.

``methods.py`` applies either method to a :class:`~brdffit.fitting.single.result.FitResult`. Imports ``physics``,
``data`` and ``fitting``.
"""
