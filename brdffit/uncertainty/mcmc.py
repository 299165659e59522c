"""Posterior sampling of a fit's parameters with emcee (Foreman-Mackey et al. 2013, PASP 125, 306).

The walkers of emcee's affine-invariant ensemble sampler (Goodman & Weare
2010) start in a small Gaussian ball around the Levenberg-Marquardt optimum
(a tenth of the Laplace standard errors wide, ``laplace.py``) and move over
the posterior of ``density.py``, whose log density is jit-compiled and
evaluates every walker of a move at once. The first ``burn`` steps are
discarded and the rest thinned by ``thin``.

Three steps, one function each, which :func:`sample_and_estimate` runs in turn: :func:`run_chain`
samples (and writes the chain file), :func:`diagnose` judges the chain, :func:`draws_estimate` lays the
draws out as the result's uncertainty. Diagnostics: the mean acceptance fraction, the integrated autocorrelation
time τ of each coordinate (emcee's estimator, Sokal 1989) and the effective
sample size ``walkers · (steps - burn) / τ``. emcee's own guideline is a chain
of at least 50 τ; a shorter one gets a warning.
"""

import os
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._files import atomic_path, check_not_stopped
from .._jax import float64
from ..checks import whole_number
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError, warn
from ..fitting.single.result import FitResult, Uncertainty
from . import findings as codes
from .density import LOG_NOISE, Density, counted_values, density_of, log_probability_function, physical_draws
from .findings import Finding
from .laplace import Curvature, curvature_at_optimum, laplace_estimate
from .layout import QUANTILES, estimate

#: emcee's guideline: a chain should be at least this many autocorrelation times long.
MIN_AUTOCORRELATION_TIMES = 50
#: The start ball's width in Laplace standard errors.
BALL = 0.1
#: The most walkers: each step evaluates the model for every walker at once (walkers × samples values), and emcee's
#: vectorized moves hold as many; 10,000 is 300 times the default. ``--walkers 1e9`` ran out of memory.
MAX_WALKERS = 10_000
#: The most positions a chain holds (walkers × steps, burn-in included; 8 bytes per sampled parameter each): the
#: default is 64,000. Beyond, the chain alone would need gigabytes.
MAX_CHAIN_POSITIONS = 50_000_000
#: Chain file suffixes: numpy's .npz, or emcee's HDF5 backend.
CHAIN_SUFFIXES = (".npz", ".h5", ".hdf5")
#: Below this mean acceptance fraction the walkers hardly move.
LOW_ACCEPTANCE = 0.1


@dataclass(frozen=True)
class MCMC:
    """Settings of the posterior sampler.

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
        for name, minimum in (("walkers", 2), ("steps", 1), ("burn", 0), ("thin", 1), ("seed", 0)):
            object.__setattr__(self, name, whole_number(name, getattr(self, name), minimum))
        whole_number("walkers", self.walkers, 2, MAX_WALKERS)
        if self.walkers * self.steps > MAX_CHAIN_POSITIONS:
            raise BrdfInputError(
                Argument("walkers", str(self.walkers)),
                " × ",
                Argument("steps", str(self.steps)),
                f" is {self.walkers * self.steps:,} chain positions; at most {MAX_CHAIN_POSITIONS:,}"
                f" ({MAX_CHAIN_POSITIONS * 8 // 2**20:,} MiB of chain per sampled parameter)",
            )
        if self.burn >= self.steps:
            raise BrdfInputError(
                Argument("burn", str(self.burn)), " must be less than ", Argument("steps", str(self.steps))
            )
        if (self.steps - self.burn) // self.thin < 1:
            raise BrdfInputError(
                Argument("thin", str(self.thin)), f" keeps no step of the {self.steps - self.burn} after burn-in"
            )


def sampled_labels(sampling_labels: list[str], has_sigma: bool) -> list[str]:
    """The coordinates the walkers move: the sampling vector's, and the noise's ``ln s`` without sigma."""
    return sampling_labels + ([] if has_sigma else [LOG_NOISE])


def check_walkers(settings: MCMC, model, samples: Samples, constraints=None) -> None:
    """emcee needs at least two walkers per sampled coordinate (the free ones, when ``constraints`` fix some)."""
    n_parameters = model.sampling.size(samples.n_channels) if constraints is None else constraints.n_free
    _check_walker_count(settings, n_parameters + (samples.sigma is None))


def _check_walker_count(settings: MCMC, n_dimensions: int) -> None:
    if settings.walkers < 2 * n_dimensions:
        raise BrdfInputError(
            Argument("walkers", str(settings.walkers)),
            f" is too few for {n_dimensions} sampled parameters; give at least {2 * n_dimensions}",
        )


def check_chain_path(path) -> Path:
    """``path`` if its suffix names a chain format and its folder exists; a one-line error otherwise."""
    path = Path(path)
    where = Argument("chain", str(path))
    if path.suffix.lower() not in CHAIN_SUFFIXES:
        raise BrdfInputError(where, f": the file must end in {', '.join(CHAIN_SUFFIXES)}")
    if not path.parent.is_dir():
        raise BrdfInputError(where, f": folder {path.parent} does not exist")
    if path.suffix.lower() != ".npz":
        try:
            import h5py  # noqa: F401
        except ImportError:
            raise BrdfInputError(
                where, ": HDF5 needs h5py, which is not installed: pip install 'brdffit[hdf5]', or use .npz"
            ) from None
    return path


def sample_posterior(
    result: FitResult,
    samples: Samples,
    settings: MCMC | None = None,
    *,
    chain: str | os.PathLike | None = None,
    progress: bool = False,
) -> FitResult:
    """``result`` with its MCMC :class:`~brdffit.fitting.single.result.Uncertainty` and the draws behind it.

    ``samples`` are those ``result`` was fitted to. ``chain``: save the whole
    chain (burn-in included) to a ``.npz`` file or emcee's HDF5 backend
    (``.h5``). ``progress``: show a progress bar. Warns
    (:class:`~brdffit.UncertaintyWarning`) when the chain is shorter
    than 50 autocorrelation times; the warnings are also the estimate's ``warnings``.
    The draws (physical parameters, burn-in dropped, thinned) are
    ``result.draws``, in the order of ``uncertainty.covariance["names"]``.
    """
    settings = settings or MCMC()
    chain_path = None if chain is None else check_chain_path(chain)
    with float64():
        density = density_of(result, samples)
        _check_walker_count(settings, len(sampled_labels(density.free_labels, density.has_sigma)))
        laid_out, found, draws = sample_and_estimate(result, density, settings, chain_path, progress)
    for finding in found:
        warn(finding.warning())
    return result.with_estimate(laid_out, draws)


def sample_and_estimate(
    result: FitResult, density: Density, settings: MCMC, chain_path: Path | None, progress: bool
) -> tuple[Uncertainty, list[Finding], np.ndarray]:
    """Sample, diagnose and lay out: the estimate, what it warns about, and the draws (S, p)."""
    curvature = curvature_at_optimum(density)  # one pass: the start ball's widths and Laplace's findings
    chain = run_chain(density, curvature, settings, chain_path, progress)
    diagnosis = diagnose(chain, settings, sampled_labels(density.free_labels, density.has_sigma))
    # What Laplace's approximation finds at the optimum holds for the posterior too: an undetermined parameter
    # makes it improper (walkers drift with the prior), a degenerate pair long and slow, a varying scatter narrow.
    _, at_optimum = laplace_estimate(result, density, curvature, for_method="mcmc")
    found = [finding for finding in at_optimum if finding.code != codes.NOT_CONVERGED]
    if not result.converged:
        found.insert(
            0,
            Finding(codes.NOT_CONVERGED, "the fit did not converge: the chain started from the point where it stopped"),
        )
    found += diagnosis.findings
    return draws_estimate(result, density, settings, chain, diagnosis, found)


def start_ball(
    density: Density, curvature: Curvature, settings: MCMC, n_dimensions: int, rng: np.random.Generator, log_prob
) -> np.ndarray:
    """Walker starts (W, D) with finite posterior density: the optimum plus Gaussian offsets of :data:`BALL`
    Laplace standard errors, no wider than a tenth of a bounded domain or of a positive value's magnitude.

    A walker that still lands outside the prior's support (an optimum on a bound) is drawn again, in a ball
    halved each time; a walker with density ``-inf`` would never move and would poison the draws. Only the free
    coordinates are walked (``density.free``).
    """
    free = density.free
    v = density.optimum[free]
    noise2 = 1.0 if density.has_sigma else curvature.chi2 / max(counted_values(density) - v.size, 1)
    width = BALL * np.sqrt(noise2 * np.diag(curvature.inverse)[free])
    limits = []
    domains = [d for d, moves in zip(density.model.sampling.domains(density.n_channels), free, strict=True) if moves]
    for value, domain in zip(v, domains, strict=True):
        lower, upper = domain.bounds
        limits.append(BALL * (upper - lower) if np.isfinite(upper) else BALL * max(abs(value), 1e-3))
    fallback = 1e-4 * np.maximum(np.abs(v), 1e-3)  # where the Laplace error is undetermined
    width = np.where(np.isfinite(width) & (width > 0), np.minimum(width, limits), fallback)
    centre = v
    if n_dimensions > v.size:  # ln s, known to about 1/sqrt(2n)
        centre = np.append(v, 0.5 * np.log(noise2))
        width = np.append(width, BALL / np.sqrt(2.0 * density.n_values))
    walkers = centre + width * rng.standard_normal((settings.walkers, n_dimensions))
    for attempt in range(1, 60):
        bad = ~np.isfinite(log_prob(walkers))
        if not bad.any():
            return walkers
        walkers[bad] = centre + width * 0.5**attempt * rng.standard_normal((int(bad.sum()), n_dimensions))
    raise BrdfInputError("the posterior density is -inf around the fitted parameters; the fit cannot be sampled")


class Chain(NamedTuple):
    """A sampler's whole run: positions (steps, walkers, D) and each walker's acceptance fraction."""

    positions: np.ndarray
    acceptance: np.ndarray


def run_chain(density: Density, curvature: Curvature, settings: MCMC, chain_path: Path | None, progress: bool) -> Chain:
    """Run emcee from the start ball; with ``chain_path``, the whole chain is written there (atomically)."""
    import emcee

    labels = sampled_labels(density.free_labels, density.has_sigma)
    n_dimensions = len(labels)
    rng = np.random.default_rng(settings.seed)
    density_at = log_probability_function(density)

    def log_prob(points):
        # a stop is seen at every step, also one whose exception Python swallowed (raised inside a gc callback: the
        # sampler would otherwise run its million steps on)
        check_not_stopped()
        return density_at(points)

    start = start_ball(density, curvature, settings, n_dimensions, rng, log_prob)
    if chain_path is None:
        return _chain_of(run_sampler(settings, start, log_prob, progress))
    with atomic_path(chain_path) as temporary:
        if chain_path.suffix.lower() == ".npz":
            sampler = run_sampler(settings, start, log_prob, progress)
            save_chain(temporary, sampler, labels, settings)
        else:  # emcee's HDF5 backend writes as it goes, into the temporary file
            temporary.unlink()
            backend = emcee.backends.HDFBackend(str(temporary))
            backend.reset(settings.walkers, n_dimensions)
            sampler = run_sampler(settings, start, log_prob, progress, backend)
        return _chain_of(sampler)  # read before the file is renamed


class Diagnosis(NamedTuple):
    """How well a chain explored the posterior."""

    autocorr_time: np.ndarray  # τ per coordinate, steps
    effective_samples: np.ndarray  # walkers · (steps - burn) / τ
    acceptance: float  # the mean acceptance fraction
    findings: list[Finding]


def diagnose(chain: Chain, settings: MCMC, labels: list[str]) -> Diagnosis:
    """Autocorrelation times, effective sample sizes and acceptance, with a warning for a short or stuck chain."""
    import emcee

    after_burn = settings.steps - settings.burn
    tau = emcee.autocorr.integrated_time(chain.positions[settings.burn :], tol=0)
    effective = settings.walkers * after_burn / tau
    acceptance = float(np.mean(chain.acceptance))
    found = []
    longest = int(np.argmax(tau))
    if after_burn < MIN_AUTOCORRELATION_TIMES * tau[longest]:
        needed = int(np.ceil(MIN_AUTOCORRELATION_TIMES * tau[longest])) + settings.burn
        found.append(
            Finding(
                codes.SHORT_CHAIN,
                f"the chain is shorter than {MIN_AUTOCORRELATION_TIMES} autocorrelation times ({after_burn} steps"
                f" after burn-in, τ = {tau[longest]:.0f} steps for {labels[longest]}): the quantiles are rough;"
                f" run {needed} steps or more",
            )
        )
    if acceptance < LOW_ACCEPTANCE:
        found.append(
            Finding(codes.LOW_ACCEPTANCE, f"the acceptance fraction is {acceptance:.2f}: the walkers hardly move")
        )
    return Diagnosis(tau, effective, acceptance, found)


def draws_estimate(
    result: FitResult, density: Density, settings: MCMC, chain: Chain, diagnosis: Diagnosis, found: list[Finding]
) -> tuple[Uncertainty, list[Finding], np.ndarray]:
    """The draws after burn-in and thinning as the result's uncertainty; returns it, ``found`` and the draws."""
    model, c = density.model, density.n_channels
    n_dimensions = chain.positions.shape[2]
    kept = chain.positions[settings.burn + settings.thin - 1 :: settings.thin].reshape(-1, n_dimensions)  # as emcee
    draws = physical_draws(model, density.embedded(kept[:, : np.count_nonzero(density.free)]), c)
    covariance = np.atleast_2d(np.cov(draws, rowvar=False))
    constant = np.ptp(draws, axis=0) == 0  # a fixed parameter: its mean's rounding would make a variance of 1e-30
    covariance[constant, :] = covariance[:, constant] = 0.0
    noise = {} if density.has_sigma else {"noise_scale": _noise_quantiles(kept[:, -1])}
    diagnostics = {
        "acceptance": diagnosis.acceptance,
        "sampled": sampled_labels(density.free_labels, density.has_sigma),
        "fixed": sorted(result.fixed),
        "autocorr_time": diagnosis.autocorr_time.tolist(),
        "effective_samples": diagnosis.effective_samples.tolist(),
        "n_walkers": settings.walkers,
        "n_steps": settings.steps,
        "burn": settings.burn,
        "thin": settings.thin,
        "seed": settings.seed,
        "n_draws": int(kept.shape[0]),
    } | noise
    laid_out = estimate(
        "mcmc",
        model,
        tuple(result.channels),
        stderr=np.where(constant, 0.0, np.std(draws, axis=0, ddof=1)),
        quantiles=np.quantile(draws, QUANTILES, axis=0),
        covariance=covariance,
        diagnostics=diagnostics,
        findings=found,
    )
    return laid_out, found, draws


def _chain_of(sampler) -> Chain:
    """The whole chain (steps, walkers, D) and each walker's acceptance fraction, in memory."""
    return Chain(sampler.get_chain(), np.asarray(sampler.acceptance_fraction))


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
