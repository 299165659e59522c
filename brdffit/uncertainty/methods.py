"""The uncertainty of a fit, by either method: ``laplace`` (``laplace.py``) or ``mcmc`` (``mcmc.py``).

:func:`with_uncertainty` is the one place that applies a method to a result; the public ``brdffit.fit``
and ``brdffit.fit_batch`` (``brdffit/api.py``) and the command line all come through it.
"""

import os

from ..checks import choice
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from .laplace import laplace_uncertainty
from .mcmc import MCMC, check_chain_path, sample_posterior

METHODS = ("laplace", "mcmc")


def check_options(method: str | None, mcmc: MCMC | None = None, chain: str | os.PathLike | None = None) -> None:
    """The uncertainty arguments, checked before any work: the method, MCMC settings only with ``"mcmc"``,
    and a chain file the sampler can write."""
    if isinstance(method, MCMC):
        raise BrdfInputError(
            Argument("uncertainty"),
            " takes 'laplace' or 'mcmc'; pass MCMC settings as ",
            Argument("mcmc", "brdffit.MCMC(...)"),
        )
    if method is not None:
        choice("uncertainty", method, METHODS)
    if mcmc is not None and not isinstance(mcmc, MCMC):
        raise BrdfInputError(Argument("mcmc"), f" must be brdffit.MCMC(...), got {type(mcmc).__name__}")
    if method != "mcmc" and (mcmc is not None or chain is not None):
        raise BrdfInputError("mcmc settings and chain apply only to uncertainty='mcmc'")
    if chain is not None:
        check_chain_path(chain)


def with_uncertainty(
    result: FitResult,
    samples: Samples,
    method: str,
    *,
    mcmc: MCMC | None = None,
    chain: str | os.PathLike | None = None,
    progress: bool = False,
) -> FitResult:
    """``result`` with its uncertainty by ``method``; ``samples`` are those it was fitted to (after ``max_theta``).

    ``mcmc``, ``chain`` and ``progress`` apply to ``method="mcmc"`` (see :func:`brdffit.sample_posterior`).
    A result that is not finite (:meth:`FitResult.non_finite`: data beyond float64's range) is returned as it is:
    it has no result file, so it gets no estimate and no chain file is written.
    """
    check_options(method, mcmc, chain)
    if result.non_finite() is not None:
        return result
    if method == "laplace":
        return laplace_uncertainty(result, samples)
    return sample_posterior(result, samples, mcmc, chain=chain, progress=progress)
