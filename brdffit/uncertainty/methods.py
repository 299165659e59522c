"""Uncertainty of a fit, by either method: ``laplace`` (``laplace.py``) or ``mcmc`` (``mcmc.py``)."""

import os

from ..data.samples import Samples
from ..errors import BrdfInputError
from ..fitting.results import FitResult
from .laplace import laplace_uncertainty
from .mcmc import MCMC, check_chain_path, sample_posterior

METHODS = ("laplace", "mcmc")


def check_method(method: str | None) -> str | None:
    if isinstance(method, MCMC):
        raise BrdfInputError("uncertainty takes 'laplace' or 'mcmc'; pass MCMC settings as mcmc=brdffit.MCMC(...)")
    if method is not None and method not in METHODS:
        raise BrdfInputError(f"--uncertainty {method!r} is not allowed; choose one of: {', '.join(METHODS)}")
    return method


def check_options(method: str | None, mcmc: MCMC | None = None, chain: str | os.PathLike | None = None) -> None:
    """The API's uncertainty arguments, checked before any work: the method, MCMC settings only with ``"mcmc"``,
    and a chain file the sampler can write."""
    check_method(method)
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
    """``result`` with its ``uncertainty`` block by ``method``; ``samples`` are those it was fitted to.

    ``mcmc``, ``chain`` and ``progress`` apply to ``method="mcmc"`` (see
    :func:`brdffit.sample_posterior`).
    """
    check_options(method, mcmc, chain)
    if method == "laplace":
        return laplace_uncertainty(result, samples)
    return sample_posterior(result, samples, mcmc, chain=chain, progress=progress)
