"""A fitted BRDF approximated by another model: what an export does when a renderer has no exact counterpart.

The fitted model is tabulated on a dense hemisphere grid (:func:`dense_grid`); the renderer's model is fitted to
those values with the fit's own loss; how far the two differ is reported (:class:`Approximation`): the rmse over
:func:`error_grid` (the dense grid and the plane of incidence, where the highlight is: the dense grid's azimuths are
bins' midpoints, which never sample the mirror direction), in 1/sr, and the worst relative difference of their
directional albedos ``∫ f cos θo dωo`` (the light a surface reflects, at the incidences
``fitting/single/caveats.py`` checks: 0°, 30°, 60°, 80°).
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..data.samples import Samples
from ..fitting.options import HOLDING_NOTHING, Holding, Solving
from ..fitting.single.caveats import ALBEDO_INCIDENCE, albedo_directions, albedo_quadrature
from ..fitting.single.fit import fit_one
from ..fitting.single.result import FitResult
from ..physics.geometry import direction_to_spherical, spherical_to_direction
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


def plane_of_incidence(shape: tuple[int, int, int] = GRID) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs ``wi``, ``wo`` (N, 3) in the plane of incidence: the light at azimuth 0 and ``shape[0]``
    zeniths (:func:`dense_grid`'s), the viewer at azimuths 0 and 180° and ``shape[1]`` zeniths, and each light's
    mirror direction: where a glossy lobe peaks, and where a renderer's model may differ most (a Fresnel term at
    grazing angles)."""
    n_light, n_theta, _ = shape
    light = (np.arange(n_light) + 0.5) * (np.pi / 2) / n_light
    view = (np.arange(n_theta) + 0.5) * (np.pi / 2) / n_theta
    theta_i, theta_o, phi_o = (a.ravel() for a in np.meshgrid(light, view, [0.0, np.pi], indexing="ij"))
    theta_i, theta_o = np.concatenate([theta_i, light]), np.concatenate([theta_o, light])
    phi_o = np.concatenate([phi_o, np.full(n_light, np.pi)])
    return spherical_to_direction(theta_i, 0.0 * theta_i), spherical_to_direction(theta_o, phi_o)


def error_grid() -> tuple[np.ndarray, np.ndarray]:
    """The pairs an approximation's error is measured on: :func:`dense_grid` and :func:`plane_of_incidence`
    (38,880 + 1,092 pairs)."""
    pairs = dense_grid(), plane_of_incidence()
    return tuple(np.concatenate([pair[i] for pair in pairs]) for i in (0, 1))


@dataclass(frozen=True)
class Approximation:
    """How far an approximating BRDF lies from the fitted one: ``rmse`` over :func:`error_grid` (1/sr), the same as
    a fraction of the fitted BRDF's own rms there (``relative_rmse``: the shape's error, which albedos cannot see,
    e.g. a retro-reflective lobe turned forward), and the worst relative difference of their directional albedos
    (``albedo_error``, a fraction) over the incidences and channels, at ``albedo_incidence`` (degrees) in channel
    ``albedo_channel``; ``largest``: where on the grid the two differ most (``theta_i``, ``theta_o``, ``phi_o`` in
    degrees, the light at azimuth 0; the ``channel``; the ``fit``'s and the ``approximation``'s values, 1/sr)."""

    rmse: float
    albedo_error: float
    albedo_incidence: float
    albedo_channel: str
    relative_rmse: float = float("nan")
    largest: dict[str, float] | None = None

    def to_dict(self) -> dict:
        return {
            "rmse": self.rmse,
            "relative_rmse": self.relative_rmse,
            "albedo_error": self.albedo_error,
            "albedo_incidence": self.albedo_incidence,
            "albedo_channel": self.albedo_channel,
            "largest_difference": self.largest,
        }

    def warnings(self, target: str) -> list[str]:
        """What a user must know about this approximation by ``target`` (a renderer's model)."""
        if not self.relative_rmse > POOR_SHAPE:
            return []
        return [
            f"{target} misses most of this BRDF's shape ({self.relative_rmse:.0%} of its rms; {self._largest_text()}):"
            " look at the rendered sphere and at the data there before using it"
        ]

    def _largest_text(self) -> str:
        if not self.largest:
            return "largest difference unknown"
        where = self.largest
        return (
            f"largest at θi {where['theta_i']:.0f}°, θo {where['theta_o']:.0f}°, φo {where['phi_o']:.0f}°:"
            f" {where['approximation']:.3g} where the fit has {where['fit']:.3g} 1/sr"
        )

    def line(self) -> str:
        """One line a person reads: ``rmse 0.0021 1/sr (4.1% of the BRDF's rms) over the hemisphere and the plane of
        incidence, directional albedo within 3.2% (worst at θi = 80°, channel r)``."""
        return (
            f"rmse {self.rmse:.3g} 1/sr ({self.relative_rmse:.1%} of the BRDF's rms) over the hemisphere and the plane"
            " of incidence,"
            f" directional albedo within {self.albedo_error:.2%} (worst at θi = {self.albedo_incidence:g}°,"
            f" channel {self.albedo_channel})"
        )


def tabulated(result: FitResult, shape: tuple[int, int, int] = GRID) -> Samples:
    """The fitted BRDF of ``result`` on :func:`dense_grid`, as samples (its channels; values, not measurements)."""
    wi, wo = dense_grid(shape)
    return Samples.from_arrays(wi, wo, result.predict(wi, wo), channels=result.channels, source="the fitted BRDF")


def approximation_error(result: FitResult, brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Approximation:
    """How far ``brdf(wi, wo) -> (N, C)`` (1/sr) lies from ``result``'s fitted BRDF (:class:`Approximation`)."""
    wi, wo = error_grid()
    fitted, approximated = result.predict(wi, wo), np.asarray(brdf(wi, wo))
    rmse = float(np.sqrt(np.mean((approximated - fitted) ** 2)))
    relative = rmse / max(float(np.sqrt(np.mean(fitted**2))), 1e-300)
    original = _albedos(lambda a, b: result.predict(a, b))
    approximate = _albedos(brdf)
    albedo = np.abs(approximate - original) / np.maximum(original, 1e-12)
    worst = np.unravel_index(int(np.argmax(albedo)), albedo.shape)
    pair, channel = np.unravel_index(int(np.argmax(np.abs(approximated - fitted))), fitted.shape)
    (theta_i, _), (theta_o, phi_o) = (np.degrees(direction_to_spherical(w[pair])) for w in (wi, wo))
    largest = {
        "theta_i": float(theta_i),
        "theta_o": float(theta_o),
        "phi_o": float(phi_o) % 360.0,
        "channel": str(result.channels[channel]),
        "fit": float(fitted[pair, channel]),
        "approximation": float(approximated[pair, channel]),
    }
    return Approximation(
        rmse, float(albedo[worst]), float(ALBEDO_INCIDENCE[worst[0]]), str(result.channels[worst[1]]), relative, largest
    )


#: How a renderer's model is fitted to a fit: the model in float32, refined in float64 (the optimum is float64's).
#: Measured on the oak example's Ward fit, Mitsuba's GGX stand-in on the 38,880 pairs: 3.1 s, against 6.8 s in
#: float64, the same cost to 7 digits (2-core Xeon, warm).
REFIT_SOLVING = Solving(dtype="float32")


def refit(
    result: FitResult, model: Model | str, holding: Holding = HOLDING_NOTHING, **model_options
) -> tuple[FitResult, Approximation]:
    """``model`` fitted to ``result``'s BRDF on :func:`dense_grid` with ``result``'s loss, and how far it lies. Every
    parameter the renderer's model has is free (a conductor's ``ks`` too, which a fit holds at 1 by default: the
    renderer's ``specular_reflectance`` takes any value) but what ``holding`` holds (a renderer's range:
    ``{"ks": (0, 1)}``). Solved in float32 and refined in float64 (:data:`REFIT_SOLVING`)."""
    model = get_model(model, **model_options)
    held = holding.fixed.keys() | holding.bounds.keys()
    freed = {name: None for name, _ in getattr(model, "held", ()) if name not in held}
    holding = Holding(fixed=freed | dict(holding.fixed), bounds=holding.bounds)
    fitted = fit_one(tabulated(result), model, result.loss, solving=REFIT_SOLVING, holding=holding)
    return fitted, approximation_error(result, fitted.predict)


def _albedos(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], n: int = 128) -> np.ndarray:
    """Directional albedos (incidences, C) of ``brdf`` by the fit caveats' quadrature (``caveats.py``)."""
    wi, wo = albedo_directions(n)
    return albedo_quadrature(np.asarray(brdf(wi, wo)), n)[0]
