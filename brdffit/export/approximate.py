"""A fitted BRDF approximated by another model: what an export does when a renderer has no exact counterpart.

The fitted model is tabulated on a dense hemisphere grid (:func:`fitting_grid`: :func:`dense_grid`, or half of it
where the fitted BRDF is mirror-symmetric about the plane of incidence, as a light at azimuth 0 makes every isotropic
BRDF: the other half repeats it, and the optimum is the same; an anisotropic BRDF, :func:`isotropic`, is tabulated
with the light at :data:`ANISOTROPIC_TURNS` azimuths, which pin its tangent, on fewer viewer zeniths,
:data:`ANISOTROPIC_FIT_GRID`); the renderer's model is fitted to those values with the fit's own loss, coarse to fine
(:func:`refit`: the fit's own start search on a coarse subset of the grid, its optimum solved again on the whole, or
on :data:`ANISOTROPIC_FIT_GRID`); how far the two differ is reported (:class:`Approximation`): the rmse over
:func:`error_grid` (the dense grid and the plane of incidence with each light's mirror direction, where the highlight
is: the dense grid's azimuths are bins' midpoints, which never sample the mirror direction), in 1/sr, and the worst
relative difference of their directional albedos ``∫ f cos θo dωo`` (the light a surface reflects, at the incidences
``fitting/single/caveats.py`` checks: 0°, 30°, 60°, 80°). What an approximation needs of the fit is computed once for
every candidate model (:class:`Reference`).
"""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..data.samples import Samples
from ..errors import BrdfInputError
from ..fitting.options import HOLDING_NOTHING, Holding, Solving
from ..fitting.single.caveats import ALBEDO_INCIDENCE, albedo_directions, albedo_quadrature
from ..fitting.single.fit import fit_one, start_vector
from ..fitting.single.result import FitResult
from ..physics.geometry import direction_to_spherical, in_turned_frame, mirror_direction, spherical_to_direction
from ..physics.models.model import Model
from ..physics.models.registry import get_model

#: An approximation whose rmse exceeds this fraction of the BRDF's own rms misses its shape, and says so.
POOR_SHAPE = 0.5
#: The grid an approximation's error is measured on (:func:`dense_grid`): light zeniths, viewer zeniths (midpoints of
#: equal bins over [0°, 90°)) and viewer azimuths (midpoints of equal bins over [0°, 360°)); 12 × 45 × 72 = 38,880
#: pairs, every 2° in θo and 5° in φo.
GRID = (12, 45, 72)
#: The grid a renderer's model is fitted on where the BRDF is isotropic (:func:`fitting_grid`; an anisotropic one's:
#: :data:`ANISOTROPIC_FIT_GRID`): :data:`GRID`, halved where the BRDF is mirror-symmetric (19,440 pairs: the same
#: optimum as the whole grid's, for half the work).
FIT_GRID = GRID
#: The grid the start search runs on (:func:`coarse_refit`, and glTF's ``fit_material``): a subset of :data:`GRID`, its
#: 12 light zeniths, every third viewer zenith (6°) and every third azimuth (15°); 12 × 15 × 12 = 2,160 pairs where
#: the BRDF is mirror-symmetric. (Fewer light zeniths, 6, put the search's optimum of glTF's model in another valley.)
COARSE_GRID = (12, 15, 24)
#: How many light azimuths an anisotropic BRDF is tabulated at: 0°, 45°, 90° and 135° (:func:`turned`). With the
#: light at azimuth 0 alone the grid sees an anisotropic lobe from one side only; these four see its tangent from
#: every side, because every anisotropic lobe brdffit has is the same with both directions turned by 180° (it depends
#: on the half vector's squared components along its tangent and bitangent). The coarse grid the start search runs on
#: has two of them, 0° and 90° (half the pairs; on a Ward fit with ``alpha_x`` 0.05 and ``alpha_y`` 0.4 the stand-ins'
#: refined optima are those of a search on all four, to 5 digits, in a third of the time).
ANISOTROPIC_TURNS = 4
#: The grid an anisotropic BRDF's renderer model is fitted on, with the light at each of :data:`ANISOTROPIC_TURNS`
#: azimuths: :data:`GRID`'s light zeniths and viewer azimuths (every 5°), every third of its viewer zeniths (6°, the
#: coarse grid's); 4 × 12 × 15 × 72 = 51,840 pairs, a third of :data:`GRID`'s at four azimuths (155,520). Its light
#: azimuths pin a turned tangent; its viewer zeniths do not: fitted on this grid, the Mitsuba and glTF stand-ins of a
#: ``ward-aniso`` fit (``alpha_x`` 0.05, ``alpha_y`` 0.4) and of GGX and Beckmann lobes turned by 30° and −30° lay as
#: far from the fits on :func:`error_grid` as when fitted on the whole of :data:`GRID` (relative rmse 0.1% worse to
#: 3.6% better), where fitted with the light at two azimuths, 0° and 90°, one lay 57% further (a Beckmann stand-in of a
#: turned GGX lobe).
ANISOTROPIC_FIT_GRID = (12, 15, 72)


def turned(pairs: tuple[np.ndarray, np.ndarray], turns: int) -> tuple[np.ndarray, np.ndarray]:
    """The direction pairs ``wi``, ``wo`` (N, 3), and copies of them with both directions turned about the normal by
    ``k · 180°/turns`` for ``k = 1 … turns − 1``, one after another ((turns · N, 3) each): ``turns = 1``, the pairs
    as they are."""
    angles = -np.arange(turns) * np.pi / turns  # in_turned_frame turns the frame: a direction turns the other way
    wi, wo = (np.concatenate([in_turned_frame(w, angle) for angle in angles]) for w in pairs)
    return wi, wo


def dense_grid(shape: tuple[int, int, int] = GRID, turns: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs ``wi``, ``wo`` (N, 3) on a hemisphere grid: the light at azimuth 0 and ``shape[0]`` zeniths,
    the viewer at ``shape[1]`` zeniths × ``shape[2]`` azimuths (all bins' midpoints); with ``turns`` > 1, the same
    with the light at ``turns`` azimuths (:func:`turned`)."""
    n_light, n_theta, n_phi = shape
    light = (np.arange(n_light) + 0.5) * (np.pi / 2) / n_light
    view = (np.arange(n_theta) + 0.5) * (np.pi / 2) / n_theta
    azimuth = (np.arange(n_phi) + 0.5) * (2 * np.pi) / n_phi
    theta_i, theta_o, phi_o = (a.ravel() for a in np.meshgrid(light, view, azimuth, indexing="ij"))
    return turned((spherical_to_direction(theta_i, 0.0 * theta_i), spherical_to_direction(theta_o, phi_o)), turns)


def fitting_grid(
    shape: tuple[int, int, int] = FIT_GRID, symmetric: bool = False, turns: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs ``wi``, ``wo`` (N, 3) a renderer's model is fitted on: :func:`dense_grid`'s (``shape[2]``
    even; with ``turns`` light azimuths), or with ``symmetric`` (one light azimuth) those of its azimuths in (0°, 180°)
    alone, for a BRDF that is the same at ``φo`` and ``−φo`` (:func:`mirror_symmetric`): the azimuths' midpoints lie
    in mirror pairs (``φo`` and ``360° − φo``), so the half grid's cost is half the whole one's at every parameter, and
    its optimum the same."""
    if symmetric and turns != 1:
        raise ValueError("a mirror-symmetric grid has the light at azimuth 0 alone (turns = 1)")
    wi, wo = dense_grid(shape, turns)
    if not symmetric:
        return wi, wo
    upper = wo[:, 1] > 0.0
    return wi[upper], wo[upper]


#: A BRDF whose values at two symmetric pairs agree within this (relative) has the symmetry: float64 rounding.
SYMMETRY_TOLERANCE = 1e-9


def mirror_symmetric(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> bool:
    """Whether ``brdf(wi, wo) -> (N, C)`` is the same with the viewer mirrored about the plane of incidence (``wo_y →
    −wo_y``, the light at azimuth 0): every isotropic BRDF, and an anisotropic one whose axes lie along and across
    that plane (:func:`_unchanged`)."""
    return _unchanged(brdf, lambda wi, wo: (wi, wo * np.array([1.0, -1.0, 1.0])))


def isotropic(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> bool:
    """Whether ``brdf(wi, wo) -> (N, C)`` is the same with both directions turned about the normal (by 50°, an angle
    no lobe's symmetry hides): an anisotropic BRDF is not (:func:`_unchanged`)."""
    turn = np.radians(50.0)
    return _unchanged(brdf, lambda wi, wo: (in_turned_frame(wi, turn), in_turned_frame(wo, turn)))


def _unchanged(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], change: Callable) -> bool:
    """Whether ``brdf`` has the same values, within :data:`SYMMETRY_TOLERANCE`, at the coarse grid's pairs
    (:data:`COARSE_GRID`) and at those pairs changed by ``change(wi, wo) -> (wi, wo)``."""
    wi, wo = dense_grid(COARSE_GRID)
    values, changed = (np.asarray(brdf(*pair)) for pair in ((wi, wo), change(wi, wo)))
    return bool(np.all(np.abs(values - changed) <= SYMMETRY_TOLERANCE * np.maximum(np.abs(values), 1e-300)))


def plane_of_incidence(shape: tuple[int, int, int] = GRID, turns: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs ``wi``, ``wo`` (N, 3) in the plane of incidence: the light at azimuth 0 and ``shape[0]``
    zeniths (:func:`dense_grid`'s), the viewer at azimuths 0 and 180° and ``shape[1]`` zeniths, and each light's
    mirror direction: where a glossy lobe peaks, and where a renderer's model may differ most (a Fresnel term at
    grazing angles); with ``turns`` > 1, the same for each of ``turns`` light azimuths (:func:`turned`)."""
    n_light, n_theta, _ = shape
    light = (np.arange(n_light) + 0.5) * (np.pi / 2) / n_light
    view = (np.arange(n_theta) + 0.5) * (np.pi / 2) / n_theta
    theta_i, theta_o, phi_o = (a.ravel() for a in np.meshgrid(light, view, [0.0, np.pi], indexing="ij"))
    theta_i, theta_o = np.concatenate([theta_i, light]), np.concatenate([theta_o, light])
    phi_o = np.concatenate([phi_o, np.full(n_light, np.pi)])
    return turned((spherical_to_direction(theta_i, 0.0 * theta_i), spherical_to_direction(theta_o, phi_o)), turns)


def error_grid(turns: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The pairs an approximation's error is measured on: :func:`dense_grid` and :func:`plane_of_incidence`
    (38,880 + 1,092 pairs), with the light at ``turns`` azimuths (:func:`turned`)."""
    pairs = dense_grid(turns=turns), plane_of_incidence(turns=turns)
    wi, wo = (np.concatenate([pair[i] for pair in pairs]) for i in (0, 1))
    return wi, wo


@dataclass(frozen=True)
class Approximation:
    """How far an approximating BRDF lies from the fitted one: ``rmse`` over :func:`error_grid` (1/sr), the same as
    a fraction of the fitted BRDF's own rms there (``relative_rmse``: the shape's error, which albedos cannot see,
    e.g. a retro-reflective lobe turned forward), and the worst relative difference of their directional albedos
    (``albedo_error``, a fraction) over the incidences, light azimuths and channels, at ``albedo_incidence`` and
    ``albedo_phi_i`` (degrees; the light's azimuth is 0 but for an anisotropic fit's) in channel ``albedo_channel``;
    ``largest``: where on the grid the two differ most (``theta_i``, ``phi_i``, ``theta_o``,
    ``phi_o`` in degrees; the ``channel``; the ``fit``'s and the ``approximation``'s values, 1/sr)."""

    rmse: float
    albedo_error: float
    albedo_incidence: float
    albedo_channel: str
    relative_rmse: float = float("nan")
    largest: dict[str, Any] | None = None
    albedo_phi_i: float = 0.0

    def to_dict(self) -> dict:
        return {
            "rmse": self.rmse,
            "relative_rmse": self.relative_rmse,
            "albedo_error": self.albedo_error,
            "albedo_incidence": self.albedo_incidence,
            "albedo_phi_i": self.albedo_phi_i,
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
        light = f", φi {where['phi_i']:.0f}°" if where.get("phi_i", 0.0) else ""
        return (
            f"largest at θi {where['theta_i']:.0f}°{light}, θo {where['theta_o']:.0f}°, φo {where['phi_o']:.0f}°:"
            f" {where['approximation']:.3g} where the fit has {where['fit']:.3g} 1/sr"
        )

    def line(self) -> str:
        """One line a person reads: ``rmse 0.0021 1/sr (4.1% of the BRDF's rms) over the hemisphere and the plane of
        incidence, directional albedo within 3.2% (worst at θi = 80°, channel r)``."""
        return (
            f"rmse {self.rmse:.3g} 1/sr ({self.relative_rmse:.1%} of the BRDF's rms) over the hemisphere and the plane"
            " of incidence,"
            f" directional albedo within {self.albedo_error:.2%} (worst at θi = {self.albedo_incidence:g}°,"
            + (f" φi = {self.albedo_phi_i:g}°," if self.albedo_phi_i else "")
            + f" channel {self.albedo_channel})"
        )


@dataclass(frozen=True)
class Reference:
    """A fit as its approximations need it, computed once for all the candidate models an export tries: the fitted
    BRDF tabulated on :func:`fitting_grid` (``fine``, :data:`FIT_GRID`; :data:`ANISOTROPIC_FIT_GRID` where it is not
    :func:`isotropic`) and on the coarse grid its start search runs on
    (``coarse``, :data:`COARSE_GRID`), half of each where it is mirror-symmetric (``symmetric``,
    :func:`mirror_symmetric`), with the light at ``turns`` azimuths (1, or :data:`ANISOTROPIC_TURNS` where it is not
    :func:`isotropic`, the coarse grid at half of them); its values on :func:`error_grid` (``values``, (N, C) 1/sr)
    and its directional albedos with the light at each of those azimuths (``albedos``, (turns, incidences, C))."""

    result: FitResult
    symmetric: bool
    fine: Samples | None
    coarse: Samples | None
    values: np.ndarray
    albedos: np.ndarray
    turns: int = 1

    def grids(self) -> tuple[Samples, Samples]:
        """``fine`` and ``coarse``, of a reference that tabulated them (:func:`reference`)."""
        assert self.fine is not None and self.coarse is not None, "a reference of values alone (reference_values)"
        return self.fine, self.coarse


def light_turns(result: FitResult) -> int:
    """How many light azimuths ``result``'s BRDF is tabulated and measured at: 1 where it is :func:`isotropic`, else
    :data:`ANISOTROPIC_TURNS`."""
    return 1 if isotropic(result.predict) else ANISOTROPIC_TURNS


def reference(result: FitResult) -> Reference:
    """The :class:`Reference` of ``result``."""
    turns = light_turns(result)
    symmetric = turns == 1 and mirror_symmetric(result.predict)
    fine = tabulated(result, FIT_GRID if turns == 1 else ANISOTROPIC_FIT_GRID, symmetric, turns)
    coarse = tabulated(result, COARSE_GRID, symmetric, max(1, turns // 2))
    values = np.asarray(result.predict(*error_grid(turns)))
    return Reference(result, symmetric, fine, coarse, values, _albedos(result.predict, turns), turns)


def tabulated(
    result: FitResult, shape: tuple[int, int, int] = FIT_GRID, symmetric: bool = False, turns: int = 1
) -> Samples:
    """The fitted BRDF of ``result`` on :func:`fitting_grid`, as samples (its channels; values, not measurements)."""
    wi, wo = fitting_grid(shape, symmetric, turns)
    return Samples.from_arrays(wi, wo, result.predict(wi, wo), channels=result.channels, source="the fitted BRDF")


def approximation_error(
    result: FitResult, brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], known: Reference | None = None
) -> Approximation:
    """How far ``brdf(wi, wo) -> (N, C)`` (1/sr) lies from ``result``'s fitted BRDF (:class:`Approximation`);
    ``known``: ``result``'s :class:`Reference`, when it was computed already."""
    known = reference_values(result) if known is None else known
    wi, wo = error_grid(known.turns)
    fitted, approximated = known.values, np.asarray(brdf(wi, wo))
    rmse = float(np.sqrt(np.mean((approximated - fitted) ** 2)))
    relative = rmse / max(float(np.sqrt(np.mean(fitted**2))), 1e-300)
    original = known.albedos
    approximate = _albedos(brdf, known.turns)
    albedo = np.abs(approximate - original) / np.maximum(original, 1e-12)
    worst = np.unravel_index(int(np.argmax(albedo)), albedo.shape)  # (turn, incidence, channel)
    pair, channel = np.unravel_index(int(np.argmax(np.abs(approximated - fitted))), fitted.shape)
    (theta_i, phi_i), (theta_o, phi_o) = (np.degrees(direction_to_spherical(w[pair])) for w in (wi, wo))
    largest: dict[str, Any] = {
        "theta_i": float(theta_i),
        "phi_i": float(phi_i) % 360.0 if theta_i > 0.0 else 0.0,
        "theta_o": float(theta_o),
        "phi_o": float(phi_o) % 360.0,
        "channel": str(result.channels[channel]),
        "fit": float(fitted[pair, channel]),
        "approximation": float(approximated[pair, channel]),
    }
    return Approximation(
        rmse,
        float(albedo[worst]),
        float(ALBEDO_INCIDENCE[worst[1]]),
        str(result.channels[worst[2]]),
        relative,
        largest,
        albedo_phi_i=float(worst[0]) * 180.0 / known.turns,
    )


def reference_values(result: FitResult) -> Reference:
    """What :func:`approximation_error` needs of ``result`` alone (no tabulation): its values on :func:`error_grid`
    and its albedos."""
    turns = light_turns(result)
    values = np.asarray(result.predict(*error_grid(turns)))
    return Reference(result, False, None, None, values, _albedos(result.predict, turns), turns)


def grid_rmse(known: Reference, brdf: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> float:
    """The rmse (1/sr) of ``brdf(wi, wo) -> (N, C)`` against the fit of ``known`` over :func:`error_grid`: how
    :func:`approximation_error` ranks approximations, without their albedos."""
    wi, wo = error_grid(known.turns)
    return float(np.sqrt(np.mean((np.asarray(brdf(wi, wo)) - known.values) ** 2)))


#: How a renderer's model is solved on the fine grid from its coarse optimum: in float64 (a few steps from there; the
#: float32 solve and its float64 refinement that a search from the grid's starts took cost a program more, and ended
#: at the same optimum to 8 digits on the oak example's Ward fit).
REFIT_SOLVING = Solving()
#: How a renderer's model is solved on the coarse grid: to find the valley its optimum lies in, at most 64 steps. Its
#: stand-ins' coarse solves creep along a flat valley and had not converged after 1,024 steps; refined from 32, 64, 256
#: or 1,024 steps they ended at the same optimum (costs equal to 9 digits on the oak example's Ward fit; the
#: anisotropic stand-ins of a ``ward-aniso`` fit to 6), and the coarse steps were most of an export's time.
COARSE_SOLVING = Solving(max_steps=64)


def refit(
    result: FitResult,
    model: Model | str,
    holding: Holding = HOLDING_NOTHING,
    known: Reference | None = None,
    **model_options,
) -> tuple[FitResult, Approximation]:
    """``model`` fitted to ``result``'s BRDF with ``result``'s loss (:func:`coarse_refit`, then :func:`refined`), and
    how far it lies; ``known``: ``result``'s :class:`Reference`, when it was computed already."""
    known = reference(result) if known is None else known
    fitted = refined(known, coarse_refit(known, model, holding, **model_options), holding)
    return fitted, approximation_error(result, fitted.predict, known)


def coarse_refit(
    known: Reference, model: Model | str, holding: Holding = HOLDING_NOTHING, **model_options
) -> FitResult:
    """``model`` fitted to the BRDF of ``known`` (a :class:`Reference`) on its coarse grid with the fit's loss and
    every start a fit searches, at most :data:`COARSE_SOLVING`'s steps, without caveats (the samples are a model's
    values): where the optimum lies, found on 2,160 pairs. Every parameter the renderer's model has
    is free (a conductor's ``ks`` too, which a fit holds at 1 by default: the renderer's ``specular_reflectance``
    takes any value) but what ``holding`` holds (a renderer's range: ``{"ks": (0, 1)}``)."""
    model = get_model(model, **model_options)
    holding = _freed(model, holding)
    return fit_one(known.coarse, model, known.result.loss, solving=COARSE_SOLVING, holding=holding, caveats=False)


def refined(known: Reference, coarse: FitResult, holding: Holding = HOLDING_NOTHING) -> FitResult:
    """The :func:`coarse_refit` ``coarse`` solved again on the fine grid of ``known`` from its optimum (no start
    search; the search again where the optimum is one no start may be, ``fitting/single/fit.start_vector``), in float64
    (:data:`REFIT_SOLVING`)."""
    model = get_model(coarse.model, **coarse.model_options)
    holding = _freed(model, holding)
    loss = known.result.loss
    try:
        start_vector(model, coarse.params, len(coarse.channels))
    except BrdfInputError:  # a shape run off to where no fit moves (a conductor's eta of 10⁸): every start searched
        return fit_one(known.fine, model, loss, solving=REFIT_SOLVING, holding=holding, caveats=False)
    return fit_one(known.fine, model, loss, start=coarse.params, solving=REFIT_SOLVING, holding=holding, caveats=False)


def _freed(model: Model, holding: Holding) -> Holding:
    """``holding`` with every parameter the model holds by default (a conductor's ``ks``) freed, unless it holds it."""
    held = holding.fixed.keys() | holding.bounds.keys()
    freed = {name: None for name, _ in getattr(model, "held", ()) if name not in held}
    return Holding(fixed=freed | dict(holding.fixed), bounds=holding.bounds)


def _albedos(brdf: Callable[[np.ndarray, np.ndarray], np.ndarray], turns: int = 1, n: int = 128) -> np.ndarray:
    """Directional albedos (turns, incidences, C) of ``brdf`` by the fit caveats' quadrature (``caveats.py``), with
    the light at ``turns`` azimuths (:func:`turned`: an anisotropic BRDF's albedo depends on the light's azimuth)."""
    wi, wo = turned(albedo_directions(n), turns)
    values = np.asarray(brdf(wi, wo))
    return np.stack([albedo_quadrature(block, n)[0] for block in np.split(values, turns)])


#: A fitted BRDF that sends this many times more light back towards the light than into the mirror direction is a
#: retro-reflector. The renderers' models peak near the mirror direction: glTF's retro/mirror ratio is at most ~1.03
#: (θi = 60°, the dielectric's diffuse term dimmed by the mirror's larger Fresnel term); among Mitsuba's, principled's
#: Disney diffuse term (its retro-reflection, F_D90 = 0.5 + 2·roughness·cos²θd) comes nearest, ~1.1 at θi = 60° by a
#: hand estimate, a lobe about the half vector beside a Lambertian term well below 1.
RETRO_RATIO = 1.1
RETRO_INCIDENCE = (30.0, 60.0)


def retro_reflection_note(result: FitResult, renderers_model: str, none_of_its: str) -> list[str]:
    """A note when ``result`` reflects more light back towards the light than into the mirror direction by
    :data:`RETRO_RATIO` or more at an incidence of :data:`RETRO_INCIDENCE`, in every channel: the renderer's model
    (``renderers_model``, "glTF's BRDF") peaks near the mirror direction, so ``none_of_its`` ("no glTF material")
    reproduces it."""
    theta = np.radians(np.array(RETRO_INCIDENCE))
    wi = spherical_to_direction(theta, np.zeros_like(theta))
    retro = np.asarray(result.predict(wi, wi))
    mirror = np.asarray(result.predict(wi, mirror_direction(wi)))
    ratio = (retro / np.maximum(mirror, 1e-300)).min(axis=1)
    worst = int(np.argmax(ratio))
    if ratio[worst] < RETRO_RATIO:
        return []
    return [
        f"the fitted BRDF is retro-reflective (at θi = {RETRO_INCIDENCE[worst]:g}° it sends {ratio[worst]:.3g} times"
        f" more light back towards the light than into the mirror direction); {renderers_model} peaks near the mirror"
        f" direction, so {none_of_its} can reproduce it: the export is only the closest one in the loss"
    ]
