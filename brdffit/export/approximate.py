"""A fitted BRDF approximated by another model: what an export does when a renderer has no exact counterpart.

The fitted model is tabulated on a dense hemisphere grid (:func:`dense_grid`); the renderer's model is fitted to
those values with the fit's own loss; how far the two differ is reported (:class:`Approximation`): the rmse over
the grid, in 1/sr, and the worst relative difference of their directional albedos ``∫ f cos θo dωo`` (the light a
surface reflects, at the incidences ``fitting/single/caveats.py`` checks: 0°, 30°, 60°, 80°).
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..data.samples import Samples
from ..fitting.options import Holding
from ..fitting.single.caveats import ALBEDO_INCIDENCE, albedo_directions, albedo_quadrature
from ..fitting.single.fit import fit_one
from ..fitting.single.result import FitResult
from ..physics.geometry import spherical_to_direction
from ..physics.models.model import Model
from ..physics.models.registry import get_model

#: An approximation whose rmse exceeds this fraction of the BRDF's own rms misses its shape, and says so.
POOR_SHAPE = 0.5
#: The grid a fit is tabulated on: light zeniths, viewer zeniths (midpoints of equal bins over [0°, 90°)) and viewer
#: azimuths (midpoints of equal bins over [0°, 360°)); 12 × 45 × 72 = 38,880 pairs, every 2° in θo and 5° in φo.
GRID = (12, 45, 72)


def dense_grid(shape: tuple[int, int, int] = GRID) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs ``wi``, ``wo`` (N, 3) on a hemisphere grid: the light at azimuth 0 and ``shape[0]`` zeniths,
    the viewer at ``shape[1]`` zeniths × ``shape[2]`` azimuths (all bins' midpoints)."""
    n_light, n_theta, n_phi = shape
    light = (np.arange(n_light) + 0.5) * (np.pi / 2) / n_light
    view = (np.arange(n_theta) + 0.5) * (np.pi / 2) / n_theta
    azimuth = (np.arange(n_phi) + 0.5) * (2 * np.pi) / n_phi
    theta_i, theta_o, phi_o = (a.ravel() for a in np.meshgrid(light, view, azimuth, indexing="ij"))
    return spherical_to_direction(theta_i, 0.0 * theta_i), spherical_to_direction(theta_o, phi_o)


@dataclass(frozen=True)
class Approximation:
    """How far an approximating BRDF lies from the fitted one: ``rmse`` over :func:`dense_grid` (1/sr), the same as
    a fraction of the fitted BRDF's own rms there (``relative_rmse``: the shape's error, which albedos cannot see,
    e.g. a retro-reflective lobe turned forward), and the worst relative difference of their directional albedos
    (``albedo_error``, a fraction) over the incidences and channels, at ``albedo_incidence`` (degrees) in channel
    ``albedo_channel``."""

    rmse: float
    albedo_error: float
    albedo_incidence: float
    albedo_channel: str
    relative_rmse: float = float("nan")

    def to_dict(self) -> dict:
        return {
            "rmse": self.rmse,
            "relative_rmse": self.relative_rmse,
            "albedo_error": self.albedo_error,
            "albedo_incidence": self.albedo_incidence,
            "albedo_channel": self.albedo_channel,
        }

    def warnings(self, target: str) -> list[str]:
        """What a user must know about this approximation by ``target`` (a renderer's model)."""
        if not self.relative_rmse > POOR_SHAPE:
            return []
        return [
            f"{target} misses most of this BRDF's shape ({self.relative_rmse:.0%} of its rms): no such material"
            " reflects like it (a retro-reflective lobe, say); look at the sphere before using it"
        ]

    def line(self) -> str:
        """One line a person reads: ``rmse 0.0021 1/sr (4.1% of the BRDF's rms) over the hemisphere, directional
        albedo within 3.2% (worst at θi = 80°, channel r)``."""
        return (
            f"rmse {self.rmse:.3g} 1/sr ({self.relative_rmse:.1%} of the BRDF's rms) over the hemisphere,"
            f" directional albedo within {self.albedo_error:.2%} (worst at θi = {self.albedo_incidence:g}°,"
            f" channel {self.albedo_channel})"
        )


def tabulated(result: FitResult, shape: tuple[int, int, int] = GRID) -> Samples:
    """The fitted BRDF of ``result`` on :func:`dense_grid`, as samples (its channels; values, not measurements)."""
    wi, wo = dense_grid(shape)
    return Samples.from_arrays(wi, wo, result.predict(wi, wo), channels=result.channels, source="the fitted BRDF")


def approximation_error(result: FitResult, brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Approximation:
    """How far ``brdf(wi, wo) -> (N, C)`` (1/sr) lies from ``result``'s fitted BRDF (:class:`Approximation`)."""
    wi, wo = dense_grid()
    fitted = result.predict(wi, wo)
    rmse = float(np.sqrt(np.mean((brdf(wi, wo) - fitted) ** 2)))
    relative = rmse / max(float(np.sqrt(np.mean(fitted**2))), 1e-300)
    original = _albedos(lambda a, b: result.predict(a, b))
    approximate = _albedos(brdf)
    albedo = np.abs(approximate - original) / np.maximum(original, 1e-12)
    worst = np.unravel_index(int(np.argmax(albedo)), albedo.shape)
    return Approximation(
        rmse, float(albedo[worst]), float(ALBEDO_INCIDENCE[worst[0]]), str(result.channels[worst[1]]), relative
    )


def refit(result: FitResult, model: Model | str, **model_options) -> tuple[FitResult, Approximation]:
    """``model`` fitted to ``result``'s BRDF on :func:`dense_grid` with ``result``'s loss, and how far it lies; every
    parameter the renderer's model has is free (a conductor's ``ks`` too, which a fit holds at 1 by default: the
    renderer's ``specular_reflectance`` takes any value)."""
    model = get_model(model, **model_options)
    freed = Holding(fixed={name: None for name, _ in getattr(model, "held", ())})
    fitted = fit_one(tabulated(result), model, result.loss, holding=freed)
    return fitted, approximation_error(result, fitted.predict)


def _albedos(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], n: int = 128) -> np.ndarray:
    """Directional albedos (incidences, C) of ``brdf`` by the fit caveats' quadrature (``caveats.py``)."""
    wi, wo = albedo_directions(n)
    return albedo_quadrature(np.asarray(brdf(wi, wo)), n)[0]
