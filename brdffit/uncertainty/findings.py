"""What an uncertainty estimate warns about: a code that programs test, and a sentence that people read.

Both methods share findings (MCMC repeats what Laplace's approximation finds at the optimum, except what
applies to Laplace alone), so each is named by a code rather than recognised by its words.
"""

from typing import NamedTuple

from ..errors import UncertaintyWarning


class Finding(NamedTuple):
    """One warning of an estimate: ``code`` (one of the constants below) and ``message``."""

    code: str
    message: str

    def warning(self) -> UncertaintyWarning:
        """The finding as a Python warning, its ``code`` attached."""
        warning = UncertaintyWarning(self.message)
        warning.code = self.code
        return warning


#: The fit stopped without converging: the estimate describes the point where it stopped.
NOT_CONVERGED = "not-converged"
#: Too few values to estimate the noise scale without a sigma column.
NO_DEGREES_OF_FREEDOM = "no-degrees-of-freedom"
#: A parameter the samples do not determine (zero or singular Jacobian).
UNDETERMINED = "undetermined"
#: Without sigma, the residuals' scatter varies: the robust errors exceed the reported ones.
HETEROSCEDASTIC = "heteroscedastic"
#: Two parameters the samples fix only in combination.
DEGENERATE = "degenerate"
#: The chain is shorter than emcee's guideline of 50 autocorrelation times.
SHORT_CHAIN = "short-chain"
#: The walkers hardly move.
LOW_ACCEPTANCE = "low-acceptance"
