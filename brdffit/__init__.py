"""brdffit: differentiable BRDF fitting for measured reflectance data.

The public API (SPEC section 6)::

    samples = brdffit.load_samples("samples.csv")
    result = brdffit.fit(samples, model="ward", loss="log")
    result.params, result.to_json(), result.predict(wi, wo)
    values = brdffit.evaluate("cook-torrance", params, wi, wo, fresnel="schlick")
    results = brdffit.fit_batch([samples_a, samples_b], model="ward")
    result = brdffit.fit(samples, uncertainty="laplace")        # or "mcmc", mcmc=brdffit.MCMC(steps=5000)
    result.uncertainty["stderr"], print(result)                  # errors; the table shows value ± error
    posterior = brdffit.sample_posterior(result, samples)        # MCMC for an existing result
    brdffit.corner_plot(posterior, "corner.png")

Names are imported on first use (PEP 562), so ``import brdffit`` does no work;
the modules that use JAX switch it to float64 (``_jax.py``).
"""

import importlib

from ._version import __version__ as __version__

_EXPORTS = {
    "BrdfInputError": ".errors",
    "MCMC": ".uncertainty.mcmc",
    "UncertaintyWarning": ".errors",
    "corner_plot": ".views.corner",
    "laplace_uncertainty": ".uncertainty.laplace",
    "sample_posterior": ".uncertainty.mcmc",
    "FitResult": ".fitting.results",
    "LOSSES": ".fitting.losses",
    "MODELS": ".physics.models",
    "Model": ".physics.models",
    "Samples": ".data.samples",
    "enable_compilation_cache": ".cache",
    "evaluate": ".physics.evaluate",
    "fit": ".api",
    "fit_batch": ".api",
    "get_model": ".physics.models",
    "load_result": ".fitting.results",
    "save_result": ".fitting.results",
    "load_samples": ".data.load",
    "save_samples": ".data.load",
}


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'brdffit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])


__all__ = ["__version__", *_EXPORTS]
