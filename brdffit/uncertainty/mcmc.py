"""Posterior sampling of a fit's parameters with emcee (Foreman-Mackey et al. 2013, PASP 125, 306).

The walkers of emcee's affine-invariant ensemble sampler (Goodman & Weare
2010) start in a small Gaussian ball around the Levenberg-Marquardt optimum
(a tenth of the Laplace standard errors wide, ``laplace.py``) and move over
the posterior of ``posterior.py``, whose log density is jit-compiled and
evaluates every walker of a move at once. The first ``burn`` steps are
discarded and the rest thinned by ``thin``.

Diagnostics: the mean acceptance fraction, the integrated autocorrelation
time τ of each coordinate (emcee's estimator, Sokal 1989) and the effective
sample size ``walkers · (steps - burn) / τ``. emcee's own guideline is a chain
of at least 50 τ; a shorter one gets a warning.
"""

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _jax  # noqa: F401  (float64 before any array)
from .._files import atomic_path
from ..checks import whole_number
from ..data.samples import Samples
from ..errors import BrdfInputError
from ..fitting.results import FitResult
from .density import LOG_NOISE, Setup, log_probability_function, physical_draws, setup
from .laplace import Curvature, UncertaintyWarning, curvature_at_optimum, laplace_block
from .layout import (
    QUANTILES,
    correlation,
    matrix_block,
    quantile_dict,
    stderr_dict,
    with_block,
)

#: emcee's guideline: a chain should be at least this many autocorrelation times long.
MIN_AUTOCORRELATION_TIMES = 50
#: The start ball's width in Laplace standard errors.
BALL = 0.1
#: Chain file suffixes: numpy's .npz, or emcee's HDF5 backend.
CHAIN_SUFFIXES = (".npz", ".h5", ".hdf5")


@dataclass(frozen=True)
class MCMC:
    """Settings of the posterior sampler (``--walkers``, ``--steps``, ``--burn``, ``--thin``, ``--seed``).

    ``walkers`` must be at least twice the number of sampled coordinates
    (emcee's requirement); ``burn`` steps are discarded, the rest kept every
    ``thin`` steps. ``seed`` fixes the start ball and every move.
    """

    walkers: int = 32
    steps: int = 2000
    burn: int = 500
    thin: int = 1
    seed: int = 0

    def __post_init__(self):
        whole_number("--walkers", self.walkers, 2)
        whole_number("--steps", self.steps, 1)
        whole_number("--burn", self.burn, 0)
        whole_number("--thin", self.thin, 1)
        whole_number("--seed", self.seed, 0)
        if self.burn >= self.steps:
            raise BrdfInputError(f"--burn {self.burn} must be less than --steps {self.steps}")
        if (self.steps - self.burn) // self.thin < 1:
            raise BrdfInputError(f"--thin {self.thin} keeps no step of the {self.steps - self.burn} after burn-in")


def sampled_labels(model, samples: Samples) -> list[str]:
    """The coordinates the walkers move on ``samples``: the sampling vector, and ``ln s`` without sigma."""
    return model.sampling_labels(tuple(samples.channels)) + ([] if samples.sigma is not None else [LOG_NOISE])


def check_walkers(settings: MCMC, model, samples: Samples) -> None:
    """emcee needs at least two walkers per sampled coordinate."""
    n_dimensions = len(sampled_labels(model, samples))
    if settings.walkers < 2 * n_dimensions:
        raise BrdfInputError(
            f"--walkers {settings.walkers} is too few for {n_dimensions} sampled parameters; give at least"
            f" {2 * n_dimensions}"
        )


def check_chain_path(path) -> Path:
    """``path`` if its suffix names a chain format and its folder exists; a one-line error otherwise."""
    path = Path(path)
    if path.suffix.lower() not in CHAIN_SUFFIXES:
        raise BrdfInputError(f"--chain {path}: the file must end in {', '.join(CHAIN_SUFFIXES)}")
    if not path.parent.is_dir():
        raise BrdfInputError(f"--chain {path}: folder {path.parent} does not exist")
    if path.suffix.lower() != ".npz":
        try:
            import h5py  # noqa: F401
        except ImportError:
            raise BrdfInputError(f"--chain {path}: HDF5 needs h5py (pip install h5py), or use .npz") from None
    return path


def sample_posterior(
    result: FitResult,
    samples: Samples,
    settings: MCMC | None = None,
    *,
    chain: str | os.PathLike | None = None,
    progress: bool = False,
) -> FitResult:
    """``result`` with the MCMC ``uncertainty`` block (SPEC section 5) and its posterior draws.

    ``samples`` are those ``result`` was fitted to. ``chain``: save the whole
    chain (burn-in included) to a ``.npz`` file or emcee's HDF5 backend
    (``.h5``). ``progress``: show a progress bar. Warns
    (:class:`~brdffit.laplace.UncertaintyWarning`) when the chain is shorter
    than 50 autocorrelation times; the warnings are also written to the block.
    The draws (physical parameters, burn-in dropped, thinned) are
    ``result.posterior``, in the order of ``uncertainty["covariance"]["names"]``.
    """
    settings = settings or MCMC()
    chain_path = None if chain is None else check_chain_path(chain)
    posterior = setup(result, samples)
    check_walkers(settings, posterior.model, samples)
    block, draws = mcmc_block(result, posterior, settings, chain_path, progress)
    for message in block["warnings"]:
        warnings.warn(message, UncertaintyWarning, stacklevel=2)
    return with_block(result, block).with_posterior(draws)


def start_ball(
    posterior: Setup, curvature: Curvature, settings: MCMC, n_dimensions: int, rng: np.random.Generator, log_prob
) -> np.ndarray:
    """Walker starts (W, D) with finite posterior density: the optimum plus Gaussian offsets of :data:`BALL`
    Laplace standard errors, no wider than a tenth of a bounded domain or of a positive value's magnitude.

    A walker that still lands outside the prior's support (an optimum on a bound) is drawn again, in a ball
    halved each time; a walker with density ``-inf`` would never move and would poison the draws.
    """
    v = posterior.optimum
    noise2 = 1.0 if posterior.has_sigma else curvature.chi2 / max(posterior.n_values - v.size, 1)
    width = BALL * np.sqrt(noise2 * np.diag(curvature.inverse))
    limits = []
    for value, domain in zip(v, posterior.model.sampling_domains(posterior.n_channels), strict=True):
        lower, upper = domain.bounds
        limits.append(BALL * (upper - lower) if np.isfinite(upper) else BALL * max(abs(value), 1e-3))
    fallback = 1e-4 * np.maximum(np.abs(v), 1e-3)  # where the Laplace error is undetermined
    width = np.where(np.isfinite(width) & (width > 0), np.minimum(width, limits), fallback)
    centre = v
    if n_dimensions > v.size:  # ln s, known to about 1/sqrt(2n)
        centre = np.append(v, 0.5 * np.log(noise2))
        width = np.append(width, BALL / np.sqrt(2.0 * posterior.n_values))
    walkers = centre + width * rng.standard_normal((settings.walkers, n_dimensions))
    for attempt in range(1, 60):
        bad = ~np.isfinite(log_prob(walkers))
        if not bad.any():
            return walkers
        walkers[bad] = centre + width * 0.5**attempt * rng.standard_normal((int(bad.sum()), n_dimensions))
    raise BrdfInputError("the posterior density is -inf around the fitted parameters; the fit cannot be sampled")


def mcmc_block(
    result: FitResult, posterior: Setup, settings: MCMC, chain_path: Path | None, progress: bool
) -> tuple[dict, np.ndarray]:
    import emcee

    model, c = posterior.model, posterior.n_channels
    labels = posterior.labels + ([] if posterior.has_sigma else [LOG_NOISE])
    n_dimensions = len(labels)
    rng = np.random.default_rng(settings.seed)
    log_prob = log_probability_function(posterior)
    curvature = curvature_at_optimum(posterior)  # one pass: the start ball's widths and Laplace's warnings
    start = start_ball(posterior, curvature, settings, n_dimensions, rng, log_prob)

    if chain_path is None:
        chain, accepted = _chain_of(run_sampler(settings, start, log_prob, progress))
    else:
        with atomic_path(chain_path) as temporary:
            if chain_path.suffix.lower() == ".npz":
                sampler = run_sampler(settings, start, log_prob, progress)
                save_chain(temporary, sampler, labels, settings)
            else:  # emcee's HDF5 backend writes as it goes, into the temporary file
                temporary.unlink()
                backend = emcee.backends.HDFBackend(str(temporary))
                backend.reset(settings.walkers, n_dimensions)
                sampler = run_sampler(settings, start, log_prob, progress, backend)
            chain, accepted = _chain_of(sampler)  # read before the file is renamed

    after_burn = settings.steps - settings.burn
    kept = chain[settings.burn + settings.thin - 1 :: settings.thin].reshape(-1, n_dimensions)  # as emcee's get_chain
    draws = physical_draws(model, kept[:, : posterior.optimum.size], c)
    tau = emcee.autocorr.integrated_time(chain[settings.burn :], tol=0)
    effective = settings.walkers * after_burn / tau
    acceptance = float(np.mean(accepted))

    messages = []
    if not result.converged:
        messages.append("the fit did not converge: the chain started from the point where it stopped")
    # What the Laplace approximation finds at the optimum holds for the posterior too: an undetermined parameter
    # makes it improper (walkers drift with the prior), a degenerate pair long and slow, a varying scatter narrow.
    messages += [
        message
        for message in laplace_block(result, posterior, curvature)["warnings"]
        if "did not converge" not in message
    ]
    longest = int(np.argmax(tau))
    if after_burn < MIN_AUTOCORRELATION_TIMES * tau[longest]:
        needed = int(np.ceil(MIN_AUTOCORRELATION_TIMES * tau[longest])) + settings.burn
        messages.append(
            f"the chain is shorter than {MIN_AUTOCORRELATION_TIMES} autocorrelation times ({after_burn} steps after"
            f" burn-in, τ = {tau[longest]:.0f} steps for {labels[longest]}): the quantiles are rough; run"
            f" --steps {needed} or more"
        )
    if acceptance < 0.1:
        messages.append(f"the acceptance fraction is {acceptance:.2f}: the walkers hardly move")

    names = model.physical_labels(tuple(result.channels))
    covariance = np.atleast_2d(np.cov(draws, rowvar=False))
    noise = {} if posterior.has_sigma else {"noise_scale": _noise_quantiles(kept[:, -1])}
    block = {
        "method": "mcmc",
        "stderr": stderr_dict(model, np.std(draws, axis=0, ddof=1), c),
        "quantiles": quantile_dict(model, np.quantile(draws, QUANTILES, axis=0), c),
        "covariance": matrix_block(names, covariance),
        "correlation": matrix_block(names, correlation(covariance)),
        "diagnostics": {
            "acceptance": acceptance,
            "sampled": labels,
            "autocorr_time": tau.tolist(),
            "effective_samples": effective.tolist(),
            "n_walkers": settings.walkers,
            "n_steps": settings.steps,
            "burn": settings.burn,
            "thin": settings.thin,
            "seed": settings.seed,
            "n_draws": int(kept.shape[0]),
        }
        | noise,
        "warnings": messages,
    }
    return block, draws


def _chain_of(sampler) -> tuple[np.ndarray, np.ndarray]:
    """The whole chain (steps, walkers, D) and each walker's acceptance fraction, in memory."""
    return sampler.get_chain(), np.asarray(sampler.acceptance_fraction)


def run_sampler(settings: MCMC, start: np.ndarray, log_prob, progress: bool, backend=None):
    """emcee's EnsembleSampler run from ``start`` for ``settings.steps`` steps, every random draw seeded."""
    import emcee

    sampler = emcee.EnsembleSampler(settings.walkers, start.shape[1], log_prob, vectorize=True, backend=backend)
    with np.errstate(invalid="ignore", over="ignore"):  # a proposal of density -inf is rejected, not an error
        sampler.run_mcmc(
            emcee.State(start, random_state=np.random.RandomState(settings.seed).get_state()),
            settings.steps,
            progress=progress,
            progress_kwargs={"desc": "mcmc", "unit": "step", "leave": False},
            skip_initial_state_check=True,  # the ball's widths span many orders of magnitude by design
        )
    return sampler


def _noise_quantiles(log_noise: np.ndarray) -> dict[str, float]:
    """Quantiles of the noise scale ``s`` (in the loss's units) from draws of ``ln s``."""
    return {
        f"{q:g}": float(value) for q, value in zip(QUANTILES, np.exp(np.quantile(log_noise, QUANTILES)), strict=True)
    }


def save_chain(path: Path, sampler, labels: list[str], settings: MCMC) -> None:
    """The whole chain (steps, walkers, D), its log densities, coordinate names and settings, as ``.npz``."""
    with open(path, "wb") as handle:
        np.savez(
            handle,
            chain=sampler.get_chain(),
            log_prob=sampler.get_log_prob(),
            names=np.array(labels),
            acceptance_fraction=sampler.acceptance_fraction,
            burn=settings.burn,
            thin=settings.thin,
            seed=settings.seed,
        )
