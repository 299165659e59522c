"""brdffit: differentiable BRDF fitting for measured reflectance data.

The public API::

    samples = brdffit.load_samples("samples.csv")
    print(brdffit.describe(samples))                             # what brdffit info prints
    result = brdffit.fit(samples, model="ward", loss="log")
    result.params, result.to_json(), result.predict(wi, wo)
    values = brdffit.evaluate("cook-torrance", params, wi, wo, fresnel="schlick")
    wi, wo = brdffit.directions_from_angles(theta_i, phi_i, theta_o, phi_o)  # degrees, as files hold them
    results = brdffit.fit_batch([samples_a, samples_b], model="ward")
    comparison = brdffit.compare(samples, ["ward", "lafortune:lobes=2"])  # ranked by cross-validated loss
    result = brdffit.fit(samples, uncertainty="laplace")        # or "mcmc", mcmc=brdffit.MCMC(steps=5000)
    result.uncertainty["stderr"], print(result)                  # errors; the table shows value ± error
    sampled = brdffit.sample_posterior(result, samples)          # MCMC for an existing result; sampled.draws
    brdffit.corner_plot(sampled, "corner.png")
    brdffit.plots.slices([result, other], samples, path="slices.png")  # also polar, residuals, sphere
    brdffit.report(samples, path="report.html")                 # compare, fit, plot: one HTML file
    brdffit.export(result, "mitsuba", "oak.xml", samples=samples)  # or "gltf", "merl": the lines to read
    brdffit.render(result, "oak.png", samples=samples)          # Mitsuba's sphere of the export (the render extra)
    brdffit.save_basis(brdffit.build_basis(merl_files), "basis.npz")  # a data-driven basis (docs/data-driven.md)
    brdffit.write_directions(brdffit.choose_directions("basis.npz", 20).angles, "directions.csv")
    result = brdffit.fit("sparse.csv", model="pca", basis="basis.npz")
    brdffit.register_model("gauss", brdffit.ModelEntry(build))  # a model of one's own (docs/adding-a-model.md)
    maps = brdffit.svbrdf.fit("capture/", model="ward", output="maps/")  # one fit per texel (docs/svbrdf.md)
    image = brdffit.svbrdf.render(maps, light_mm=[0, -150, 250], camera_mm=[0, 0, 400])

Names are imported on first use (PEP 562), so ``import brdffit`` does no work; the ``TYPE_CHECKING`` block
below says the same to IDEs and type checkers. brdffit computes in float64 without switching float64 on
for the rest of a program (``_jax/precision.py``).
"""

import importlib
from typing import TYPE_CHECKING

from ._version import __version__ as __version__

_EXPORTS = {
    "BrdfInputError": ".errors",
    "UncertaintyWarning": ".errors",
    "FitWarning": ".errors",
    "InputWarning": ".errors",
    "MODELS": ".physics.models.registry",
    "Model": ".physics.models.model",
    "LobeModel": ".physics.models.model",
    "ModelEntry": ".physics.models.model",
    "Lobe": ".physics.models.lobe",
    "MappedLobe": ".physics.models.lobe",
    "Params": ".physics.models.params",
    "get_model": ".physics.models.registry",
    "register_model": ".physics.models.registry",
    "evaluate": ".physics.evaluate",
    "directions_from_angles": ".physics.geometry",
    "angles_from_directions": ".physics.geometry",
    "Samples": ".data.samples",
    "load_samples": ".data.load",
    "save_samples": ".data.load",
    "describe": ".data.summary",
    "LOSSES": ".fitting.objective.losses",
    "FitResult": ".fitting.single.result",
    "load_result": ".fitting.single.result",
    "save_result": ".fitting.single.result",
    "fit": ".api",
    "fit_batch": ".api",
    "compare": ".fitting.comparison.compare",
    "Comparison": ".fitting.comparison.compare",
    "load_comparison": ".fitting.comparison.compare",
    "Solving": ".fitting.options",
    "Holding": ".fitting.options",
    "MCMC": ".uncertainty.mcmc",
    "laplace_uncertainty": ".uncertainty.laplace",
    "sample_posterior": ".uncertainty.mcmc",
    "corner_plot": ".views.corner",
    "report": ".views.report",
    "render": ".export.mitsuba_render:render_sphere",
    "enable_compilation_cache": "._programs.cache",
    "build_basis": ".datadriven.build",
    "load_basis": ".datadriven.basis",
    "save_basis": ".datadriven.basis",
    "choose_directions": ".datadriven.directions",
    "read_directions": ".datadriven.directions",
    "write_directions": ".datadriven.directions",
}

if TYPE_CHECKING:
    from . import export as export
    from . import svbrdf as svbrdf
    from ._programs.cache import enable_compilation_cache as enable_compilation_cache
    from .api import fit as fit
    from .api import fit_batch as fit_batch
    from .data.load import load_samples as load_samples
    from .data.load import save_samples as save_samples
    from .data.samples import Samples as Samples
    from .data.summary import describe as describe
    from .datadriven.basis import load_basis as load_basis
    from .datadriven.basis import save_basis as save_basis
    from .datadriven.build import build_basis as build_basis
    from .datadriven.directions import choose_directions as choose_directions
    from .datadriven.directions import read_directions as read_directions
    from .datadriven.directions import write_directions as write_directions
    from .errors import BrdfInputError as BrdfInputError
    from .errors import FitWarning as FitWarning
    from .errors import InputWarning as InputWarning
    from .errors import UncertaintyWarning as UncertaintyWarning
    from .export.mitsuba_render import render_sphere as render  # noqa: F401 (brdffit.render; __all__ is built below)
    from .fitting.comparison.compare import Comparison as Comparison
    from .fitting.comparison.compare import compare as compare
    from .fitting.comparison.compare import load_comparison as load_comparison
    from .fitting.objective.losses import LOSSES as LOSSES
    from .fitting.options import Holding as Holding
    from .fitting.options import Solving as Solving
    from .fitting.single.result import FitResult as FitResult
    from .fitting.single.result import load_result as load_result
    from .fitting.single.result import save_result as save_result
    from .physics.evaluate import evaluate as evaluate
    from .physics.geometry import angles_from_directions as angles_from_directions
    from .physics.geometry import directions_from_angles as directions_from_angles
    from .physics.models.lobe import Lobe as Lobe
    from .physics.models.lobe import MappedLobe as MappedLobe
    from .physics.models.model import LobeModel as LobeModel
    from .physics.models.model import Model as Model
    from .physics.models.model import ModelEntry as ModelEntry
    from .physics.models.params import Params as Params
    from .physics.models.registry import MODELS as MODELS
    from .physics.models.registry import get_model as get_model
    from .physics.models.registry import register_model as register_model
    from .uncertainty.laplace import laplace_uncertainty as laplace_uncertainty
    from .uncertainty.mcmc import MCMC as MCMC
    from .uncertainty.mcmc import sample_posterior as sample_posterior
    from .views import plots as plots
    from .views.corner import corner_plot as corner_plot
    from .views.report import report as report


#: Modules of the public API, also imported on first use (``export`` is also a function: ``export/__init__.py``).
_MODULES = {"plots": ".views.plots", "export": ".export", "svbrdf": ".svbrdf"}


def __getattr__(name: str):
    if name in _MODULES:
        module = importlib.import_module(_MODULES[name], __name__)
        globals()[name] = module
        return module
    if name in _EXPORTS:
        module_name, _, attribute = _EXPORTS[name].partition(":")
        value = getattr(importlib.import_module(module_name, __name__), attribute or name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'brdffit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS, *_MODULES])


__all__ = ["__version__", *_EXPORTS, *_MODULES]
