"""Shared test set-up: float64 for the tests' own JAX arrays, warnings as errors (pyproject), a private cache.

brdffit itself never switches float64 on for the process (``brdffit/_jax/precision.py``); the tests build JAX arrays
of their own and compare them with brdffit's to 1e-12, so they run with it on, as equinox's tests do.
``tests/test_float64.py`` checks in a fresh interpreter that brdffit leaves a user's float32 JAX alone.
"""

import atexit
import gc
import os
import shutil
import tempfile

import jax
import numpy as np
import pytest
from hypothesis import settings

from brdffit._programs import stored as stored_programs

jax.config.update("jax_enable_x64", True)

# Every random choice takes a seed, hypothesis's too: its examples are derived from each test's source and signature
# (``derandomize``), so a run repeats the one before it on any machine (editing a test changes its examples), and
# nothing is kept between runs (``database=None``). A developer who wants fresh examples runs
# ``HYPOTHESIS_PROFILE=explore pytest ...``: random draws, and a failure prints how to reproduce it (``print_blob``).
settings.register_profile("seeded", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False, database=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "seeded"))

# The command line keeps compiled programs in ~/.cache; the tests keep theirs in a folder of their own, one for each
# pytest-xdist worker (the controller's, which the workers inherit, was shared by both: two processes writing one
# cache's entries at once), removed when the process ends (every run left three behind: 485 in /tmp by 2026-11-27).
if "PYTEST_XDIST_WORKER" in os.environ or "BRDFFIT_CACHE_DIR" not in os.environ:
    os.environ["BRDFFIT_CACHE_DIR"] = tempfile.mkdtemp(prefix="brdffit-test-cache-")
    atexit.register(shutil.rmtree, os.environ["BRDFFIT_CACHE_DIR"], ignore_errors=True)

# Within a test worker JAX never writes its persistent cache, even after a command run in-process has pointed it at a
# folder: the tests need not serialise every executable they compile. The commands the tests start as processes still
# use the cache above (it is their speed-up); brdffit's own stored programs (``_programs/stored.py``) do not depend on
# this switch and stay tested.
jax.config.update("jax_enable_compilation_cache", False)

#: A worker's memory mappings above which JAX's compiled programs are dropped (``jax.clear_caches``) after a test.
#: Every executable XLA compiles for the CPU maps its code: a worker that kept them all grew by ~5,000 mappings a minute
#: and, some 1,500 tests in, reached Linux's default limit (``vm.max_map_count``, 65,530), where LLVM's next mapping
#: fails and XLA's compile (or its serialisation into the cache) dies with a segmentation fault (five whole runs on
#: 2026-11-26/27 lost a worker so; clearing the caches there took a process of 1,732 mappings back to 742).
MAPPINGS_BEFORE_CLEARING = 30_000


def memory_mappings() -> int | None:
    """How many memory mappings this process has (Linux's ``/proc/self/maps``), or None where that is not known."""
    try:
        with open("/proc/self/maps", "rb") as maps:
            return sum(1 for _ in maps)
    except OSError:
        return None


@pytest.fixture(autouse=True)
def _compiled_programs_dropped_before_the_mappings_run_out():
    """After a test, JAX's compiled programs are dropped where the worker's mappings exceed
    :data:`MAPPINGS_BEFORE_CLEARING` (a later test compiles what it needs again)."""
    yield
    count = memory_mappings()
    if count is not None and count > MAPPINGS_BEFORE_CLEARING:
        jax.clear_caches()
        stored_programs.forget_loaded()  # the executables of stored programs, which clear_caches does not hold
        gc.collect()


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def random_directions(rng, n: int, min_cos: float = 1e-3) -> np.ndarray:
    """``n`` unit vectors uniform in solid angle with ``cos θ ∈ [min_cos, 1]``."""
    cos_theta = min_cos + (1.0 - min_cos) * rng.random(n)
    phi = 2 * np.pi * rng.random(n)
    sin_theta = np.sqrt(1.0 - cos_theta**2)
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=-1)


def save_in_radians(samples, path, channels=None):
    """``samples`` written to the CSV ``path`` with its angle columns in radians (read with ``angles="radians"``), its
    value columns named ``channels`` (default: the samples' own); returns ``path``."""
    from brdffit.physics.geometry import angles_from_directions

    angles = [np.radians(angle) for angle in angles_from_directions(samples.wi, samples.wo)]
    header = ",".join(["theta_i", "phi_i", "theta_o", "phi_o", *(channels or samples.channels)])
    np.savetxt(path, np.column_stack([*angles, samples.values]), delimiter=",", header=header, comments="", fmt="%.17g")
    return path


def directions_from_degrees(theta, phi) -> np.ndarray:
    theta, phi = np.radians(np.atleast_1d(theta)), np.radians(np.atleast_1d(phi))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


# ---------------------------------------------------------------------- the command-line tests' fixtures
# (here rather than in tests/cli/conftest.py: a second conftest module would shadow this one for the tests that
# import its helpers, `from conftest import random_directions`, under pytest's default import mode)


@pytest.fixture
def no_fit(monkeypatch):
    """Fail the test if a fit starts: the checks must come first."""

    import brdffit.api

    def refuse(*args, **kwargs):
        raise AssertionError("a fit ran before the bad input was reported")

    monkeypatch.setattr(brdffit.api, "fit", refuse)
    monkeypatch.setattr(brdffit.api, "fit_batch", refuse)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small Ward dataset (``ward.csv``, one channel, 432 samples) and its fit (``ward.json``) in a folder."""
    from brdffit import data_synth, fit, save_samples

    folder = tmp_path_factory.mktemp("ward")
    samples = data_synth.synthesize(
        "ward", {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}, *data_synth.hemisphere_grid(4, 9, 12), noise=0.01
    )
    save_samples(samples, folder / "ward.csv")
    fit(samples, "ward").save(folder / "ward.json")
    return folder
