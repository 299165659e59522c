"""brdffit computes in float64 without switching float64 on for the user's program.

The check runs in a fresh interpreter whose JAX is in its default float32 mode (the test suite itself runs
with float64 on, ``conftest.py``): every public entry point must give float64 results there, leave the user's
own arrays float32, and never ask JAX for a float64 it would silently truncate (JAX warns then; warnings are
errors in that interpreter).
"""

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from paths import EXAMPLE, ROOT

import brdffit
from brdffit import data_synth

SCRIPT = """
import json, warnings
import brdffit
warnings.simplefilter("error")
warnings.filterwarnings("ignore", category=brdffit.UncertaintyWarning)  # the short chain's; the subject is dtypes
import jax, jax.numpy as jnp, numpy as np
assert not jax.config.jax_enable_x64
user = jax.jit(lambda x: x * 2)
assert user(jnp.ones(3)).dtype == jnp.float32
from brdffit import data_synth
samples = brdffit.load_samples({example!r})
result = brdffit.fit(samples, "ward")
laplace = brdffit.fit(samples, "ward", uncertainty="laplace")
batch = brdffit.fit_batch([samples, samples], "lambert")
wi, wo = data_synth.uniform_random(20000, seed=3)
large = data_synth.synthesize("ward", result.params, wi, wo, noise=0.01, seed=4)
large_result = brdffit.fit(large, "ward")  # the search subset and the full-size solver compiled in a thread
sampled = brdffit.sample_posterior(result, samples, brdffit.MCMC(walkers=16, steps=30, burn=10, seed=2))
values = brdffit.evaluate("ward", result.params, samples.wi[:5], samples.wo[:5])
assert values.dtype == np.float64 and result.predict(samples.wi[:5], samples.wo[:5]).dtype == np.float64
assert not jax.config.jax_enable_x64, "brdffit switched float64 on for the process"
assert jnp.ones(3).dtype == jnp.float32 and user(jnp.ones(3)).dtype == jnp.float32
print(json.dumps({{
    "cost": result.cost, "alpha": result.params["alpha"], "stderr": laplace.uncertainty["stderr"]["alpha"],
    "batch": [one.cost for one in batch], "large": large_result.cost, "draws": sampled.draws.mean(axis=0).tolist(),
    "values": values.tolist(),
}}))
"""


@pytest.mark.slow
def test_brdffit_computes_in_float64_and_leaves_the_users_float32_alone():
    code = SCRIPT.format(example=str(EXAMPLE))
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=_without_x64(os.environ)
    )
    assert done.returncode == 0, done.stderr[-3000:]
    there = json.loads(done.stdout.strip().splitlines()[-1])

    # The same computations here, where float64 is on for the whole process: the same compiled programs,
    # so the same numbers up to the order XLA sums in (1e-12 relative is ~10⁴ ulp).
    samples = brdffit.load_samples(EXAMPLE)
    result = brdffit.fit(samples, "ward")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", brdffit.UncertaintyWarning)  # as in the script: the subject is dtypes
        laplace = brdffit.fit(samples, "ward", uncertainty="laplace")
        sampled = brdffit.sample_posterior(result, samples, brdffit.MCMC(walkers=16, steps=30, burn=10, seed=2))
    batch = brdffit.fit_batch([samples, samples], "lambert")
    wi, wo = data_synth.uniform_random(20000, seed=3)
    large = brdffit.fit(data_synth.synthesize("ward", result.params, wi, wo, noise=0.01, seed=4), "ward")
    values = brdffit.evaluate("ward", result.params, samples.wi[:5], samples.wo[:5])
    here = {
        "cost": result.cost,
        "alpha": result.params["alpha"],
        "stderr": laplace.uncertainty["stderr"]["alpha"],
        "batch": [one.cost for one in batch],
        "large": large.cost,
        "draws": sampled.draws.mean(axis=0).tolist(),
        "values": values.tolist(),
    }
    for key, value in here.items():
        np.testing.assert_allclose(there[key], value, rtol=1e-12, err_msg=key)


def _without_x64(environment) -> dict[str, str]:
    """The environment with JAX's float64 switch at its default (off), whatever this process was given."""
    return {key: value for key, value in environment.items() if key != "JAX_ENABLE_X64"}
