"""A fitted BRDF as a glTF 2.0 material: the glTF metallic-roughness BRDF (``gltf_material.py``) fitted to it, and the
``.gltf`` or ``.glb`` file.

**The fit** (:func:`fit_gltf`): the fitted BRDF is tabulated on :func:`~brdffit.export.approximate.fitting_grid`
(:func:`~brdffit.export.approximate.reference`: half the dense grid where the fit is mirror-symmetric, and a coarse
subset of it the starts are ranked on) and the glTF parameters are fitted to it with the fit's own loss
(residual ``T(f) − T(y)``, ``fitting/objective/losses.py``) by Levenberg-Marquardt (``optimistix.least_squares`` with
brdffit's solver, ``fitting/solver/levenberg_marquardt.py``: :func:`_solve` says why not optimistix's own), in
unconstrained coordinates (logistic maps onto [0, 1]), from a few starts; then again with the extensions' parameters
free. The extensions are kept only when they lower the grid rmse by :data:`EXTENSION_GAIN` or more. How far the material
lies from the fitted BRDF is an :class:`~brdffit.export.approximate.Approximation`.

**The file** (:func:`write_gltf`): ``.gltf`` (JSON) or ``.glb`` (binary), the material on a preview sphere
(``gltf_preview.py``).
"""

import dataclasses
import math
import os
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import Any, NamedTuple, cast

import jax
import jax.numpy as jnp
import numpy as np

from .._files import atomic_path, write_text_atomic
from .._jax import float64
from .._programs import jit
from .._version import __version__
from ..data.samples import Samples
from ..errors import Argument, BrdfInputError
from ..fitting.objective.losses import get_loss
from ..fitting.options import MAX_STEPS, Holding
from ..fitting.single.result import FitResult, json_text
from ..fitting.solver.compiled import TOLERANCES
from ..physics.models.registry import MODELS
from ..physics.renderers.gltf import DEFAULT_F0, DEFAULT_IOR, ior_f0, material_brdf
from ..views.render import display_rgb
from .approximate import (
    Approximation,
    Reference,
    approximation_error,
    coarse_refit,
    reference,
    refined,
    retro_reflection_note,
)
from .at_data import data_error
from .gltf_material import GltfMaterial
from .gltf_material import gltf_brdf as gltf_brdf  # the BRDF's name where the documentation once gave it

#: The extensions are kept only when they lower the rmse over the grid by at least this fraction: a material with
#: extensions renders only where a renderer supports them, so they must earn their place.
EXTENSION_GAIN = 0.05
#: A core fit whose grid rmse is below this fraction of the values' rms is exact: nothing is left to improve. (A
#: renderer holds the values in float32, 6e-8 apart; where the stopping test ends an exact fit, 1e-12 to 1e-8 of the
#: rms, is rounding's choice, and a 5% gain there is none.)
EXACT_FIT = 1e-6
#: The largest index of refraction written; a dielectric ``f0`` beyond its ``((ior − 1)/(ior + 1))² = 0.36`` is written
#: with ``ior = 0`` (``f0 = 1``) and the specular colour (:func:`_material_of`); diamond's 2.42 gives 0.17.
MAX_IOR = 4.0
#: How many starts go on to the fine grid, those whose solves end lowest on the coarse one (``fit_material``'s
#: ``search``), each solved from the start itself: glTF's loss has several valleys, and a solve on the fine grid from
#: the coarse grid's optimum can stay in the wrong one (the oak example's Cook-Torrance fit: cost 4.66 where its starts
#: reach 4.42). On the oak example's Ward, Cook-Torrance and 2-lobe Lafortune fits the start that ends lowest on the
#: coarse grid ends lowest on the fine one, in both stages: the materials are those of every start solved on the fine
#: grid, to 8 digits.
SEARCH_WINNERS = 1
#: A fitted factor this close to 0 or 1 is written as 0 or 1 (the logistic reaches its ends only at infinity).
EDGE = 1e-6
#: Starting roughnesses; each is tried as a dielectric (metallic ≈ 0) and as a metal (metallic ≈ 1).
START_ROUGHNESS = (0.15, 0.4, 0.75)
START_METALLIC = (0.02, 0.98)
#: Extra starts with the extensions free, at each of :data:`START_ROUGHNESS`: a dielectric with a weak specular
#: layer (``specular`` weight 0.1) whose Fresnel term is nearly flat (``f0`` 0.9): a lobe without glTF's rise
#: towards grazing angles (Ward, Phong, Lafortune), which the core model's ``f0 = 0.04`` cannot give.
START_FLAT_FRESNEL = (0.1, 0.9)
#: What evaluates a glTF material at the data's directions: no viewer runs in Python, so the BRDF the specification
#: defines, as the Khronos Sample Viewer implements it (``gltf_material.py``).
EVALUATED_BY = "the glTF specification's BRDF (Khronos Sample Viewer form)"


# ---------------------------------------------------------------------- the fit
def _logistic(u):
    return jax.nn.sigmoid(u)


def _logit(p: float) -> float:
    return math.log(p / (1.0 - p))


def _parameters(theta, n_channels: int, extended: bool):
    """Physical parameters of the unconstrained vector ``theta``: base colour (C), metallic, roughness, and, when
    ``extended``, the specular weight and the dielectric's ``f0`` (C); else weight 1 and ``f0`` 0.04."""
    base = _logistic(theta[:n_channels])
    metallic = _logistic(theta[n_channels])
    roughness = _logistic(theta[n_channels + 1])
    if extended:
        weight = _logistic(theta[n_channels + 2])
        reflectance = _logistic(theta[n_channels + 3 : 2 * n_channels + 3])
    else:
        weight = jnp.ones((), theta.dtype)
        reflectance = jnp.full((n_channels,), DEFAULT_F0, theta.dtype)
    return base, metallic, roughness, weight, reflectance


def _model_values(theta, wi, wo, n_channels: int, extended: bool):
    base, metallic, roughness, weight, reflectance = _parameters(theta, n_channels, extended)
    # One channel is grey: the same base colour and f0 in r, g and b; the BRDF's r channel is the value.
    values = material_brdf(
        jnp.broadcast_to(base, (3,)),
        metallic,
        roughness,
        weight,
        jnp.broadcast_to(reflectance, (3,)),
        wi,
        wo,
    )
    return values[:, :n_channels]


@jit(static_argnums=(4, 5, 6))  # positional, so that a later process runs the stored program (``_programs/jit.py``)
def _solve(theta, wi, wo, measured, loss_name: str, n_channels: int, extended: bool):
    """Levenberg-Marquardt from ``theta`` on the residuals ``T(f) − T(y)`` (N, C) of the loss ``loss_name``: the
    optimum, its sum of squared residuals ``Σ r²``, the step count and whether the solver met its tolerances.

    The solver is the fit's (``fitting/solver/levenberg_marquardt.least_squares``): optimistix's ``least_squares`` loop
    with Marquardt's scaled damping, MINPACK's trust-region thresholds and stopping tests, at the fits' float64
    tolerances (``fitting/solver/compiled.py``), with the descent's guards off (below). optimistix's own
    ``LevenbergMarquardt`` damps with ``λ I``: a logistic coordinate whose factor heads for 0 or 1 (metallic 0 for a
    plastic, 1 for a metal) has a vanishing Jacobian column, gets vanishing steps and crawls; measured on exact glTF
    data of a metal, 200 steps left ``1 − metallic`` at 1e-5, and its Cauchy test (every parameter step small) never
    passed. Here such a column drops out of the step once it is below ``ε`` of the largest, and the fit stops on the
    cost's relative change.
    """
    import optimistix as optx  # 0.3 s to import: an export that runs the stored program never traces this

    from ..fitting.solver.levenberg_marquardt import ScaledTrustRegionDescent, least_squares

    ftol, gtol, atol = TOLERANCES["float64"]
    residual_fn = partial(_residuals, get_loss(loss_name).transform, n_channels, extended)
    solution = least_squares(
        residual_fn,
        theta,
        (wi, wo, measured),
        rtol=ftol,
        atol=atol,
        gtol=gtol,
        max_steps=MAX_STEPS,
        # The fit's descent without its guards: a colour whose logistic coordinate must travel far, to saturate
        # at 0 or 1, reaches it. With them, the coloured coat of the recovery tests stopped at a cost of 2e-5
        # (1e-16 without) and the flat-Fresnel material at 0.045 (2e-16); with MINPACK's running scale alone,
        # the coat's extended starts ran out of steps.
        descent=ScaledTrustRegionDescent(drop_negligible_columns=True, running_scale=False),
    )
    return (
        solution.value,
        2.0 * solution.state.f_info.f,
        solution.stats["num_steps"],
        solution.result == optx.RESULTS.successful,
    )


def _residuals(transform, n_channels: int, extended: bool, theta, data):
    """The glTF fit's residuals ``T(f) − T(y)`` (N, C) at ``theta``, ``data`` the pairs ``wi``, ``wo`` and the
    values ``y`` (N, C)."""
    wi, wo, measured = data
    cos_i = wi[:, 2:3]
    predicted = _model_values(theta, wi, wo, n_channels, extended)
    return transform(predicted, measured, cos_i) - transform(measured, measured, cos_i)


def _starts(values: np.ndarray) -> list[np.ndarray]:
    """Core starting points: each roughness of :data:`START_ROUGHNESS` as a dielectric and as a metal. A
    dielectric's base colour starts at π times the median value (mostly the diffuse term); a metal's at the
    median's colour, scaled to 0.9 in its brightest channel."""
    median = np.maximum(np.median(values, axis=0), 1e-6)
    dielectric_base = np.clip(np.pi * median, 0.02, 0.95)
    metal_base = np.clip(0.9 * median / median.max(), 0.02, 0.95)
    starts = []
    for metallic in START_METALLIC:
        base = dielectric_base if metallic < 0.5 else metal_base
        for roughness in START_ROUGHNESS:
            starts.append(np.array([*(_logit(b) for b in base), _logit(metallic), _logit(roughness)]))
    return starts


def _snapped(value: float) -> float:
    return 0.0 if value < EDGE else 1.0 if value > 1.0 - EDGE else value


def _material_of(theta: np.ndarray, n_channels: int, extended: bool) -> GltfMaterial:
    """The :class:`GltfMaterial` of a solution; the dielectric's fitted ``f0`` becomes ``specular_color`` and ``ior``.

    ``f0`` fixes only the product ``((1 − ior)/(1 + ior))² · specularColor``, which brdffit writes so that every
    factor stays in the ranges renderers expect (``specularColorFactor`` ≤ 1, an ``ior`` of a real dielectric):

    * every channel's ``f0`` at most 0.04: ``ior`` 1.5 (omitted), ``specularColor = f0/0.04``;
    * the largest ``f0max`` up to that of :data:`MAX_IOR`: ``specularColor = f0/f0max`` (1 in its largest
      channel) and ``ior = (1 + sqrt(f0max))/(1 − sqrt(f0max))``;
    * beyond: ``ior = 0``, which KHR_materials_ior allows for this (``f0 = 1``, "to support the
      specular-glossiness workflow"), and ``specularColor = f0``.
    """
    with float64():
        base, metallic, roughness, weight, reflectance = (
            np.asarray(p, dtype=float) for p in _parameters(jnp.asarray(theta), n_channels, extended)
        )
    base = np.broadcast_to(base, (3,))
    material: dict[str, Any] = {
        "base_color": tuple(_snapped(float(b)) for b in base),
        "metallic": _snapped(float(metallic)),
        "roughness": _snapped(float(roughness)),
    }
    if extended:
        reflectance = np.broadcast_to(reflectance, (3,))
        largest = float(reflectance.max())
        if largest <= DEFAULT_F0:
            specular_color, ior = reflectance / DEFAULT_F0, None
        elif largest <= ior_f0(MAX_IOR):
            root = math.sqrt(largest)
            specular_color, ior = reflectance / largest, (1.0 + root) / (1.0 - root)
        else:
            specular_color, ior = reflectance, 0.0
        material |= {
            "specular": _snapped(float(weight)),
            "specular_color": tuple(float(min(c, 1.0)) for c in specular_color),
            "ior": ior,
        }
    return GltfMaterial(**material)


def _grid_rmse(material: GltfMaterial, wi, wo, values: np.ndarray) -> float:
    predicted = material.brdf(wi, wo)[:, : values.shape[1]]
    return float(np.sqrt(np.mean((predicted - values) ** 2)))


@float64
def fit_material(wi, wo, values, loss: str = "log", search=None) -> tuple[GltfMaterial, list[str]]:
    """The glTF material whose BRDF fits ``values`` (N, 3: linear RGB, or N, 1: grey) at pairs ``wi``, ``wo`` (N, 3)
    best in ``loss`` (a name of ``brdffit.LOSSES``; residual ``T(f) − T(y)``), and notes on the choice (one line
    each).

    Levenberg-Marquardt (:func:`_solve`) in unconstrained coordinates (logistic maps onto [0, 1] for base colour,
    metallic and roughness) from the starts of :data:`START_ROUGHNESS` × :data:`START_METALLIC`, the best kept;
    then with ``KHR_materials_specular``'s weight and the dielectric's ``f0`` free as well (``f0`` per channel in
    (0, 1), written as specular colour and ``ior``: :func:`_material_of`), from the core optimum and from the
    dielectric starts with a nearly flat Fresnel term (:data:`START_FLAT_FRESNEL`). The extensions are kept
    only when they lower the rmse over the samples by :data:`EXTENSION_GAIN` or more. One channel is fitted as
    grey (the same base colour in r, g and b). ``search``: pairs and values ``(wi, wo, values)`` (a coarser grid of the
    same BRDF) the starts are solved on instead, each stage's best then solved again on ``wi``, ``wo`` from there.
    """
    loss_name = get_loss(loss).name
    wi, wo = np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] not in (1, 3) or values.shape[0] == 0:
        raise BrdfInputError(
            Argument("values"), f" has shape {values.shape}; give (N, 3) linear RGB or (N, 1) grey values"
        )
    if wi.shape != (len(values), 3) or wo.shape != (len(values), 3):
        raise BrdfInputError(
            Argument("wi"), f" and wo must have shape ({len(values)}, 3), got {wi.shape} and {wo.shape}"
        )
    if not np.all(np.isfinite(values)):
        raise BrdfInputError(Argument("values"), " must be finite")
    n_channels = values.shape[1]

    def solved(theta, extended: bool, pairs) -> _Solved:
        found = _solve(jnp.asarray(theta), *pairs, loss_name, n_channels, extended)
        return _Solved(np.asarray(found[0]), float(found[1]), int(found[2]), bool(found[3]))

    searched = (wi, wo, values) if search is None else tuple(np.asarray(a, dtype=np.float64) for a in search)

    def best(starts, extended: bool) -> _Solved:
        if search is not None:  # the starts ranked by where they end on the coarse grid; the best go on
            ends = [solved(theta, extended, searched).cost for theta in starts]
            starts = [starts[k] for k in np.argsort(ends, kind="stable")[:SEARCH_WINNERS]]
        return min((solved(theta, extended, (wi, wo, values)) for theta in starts), key=lambda one: one.cost)

    core = best(_starts(values), extended=False)
    core_material = _material_of(core.theta, n_channels, False)
    core_rmse = _grid_rmse(core_material, wi, wo, values)
    if core_rmse <= EXACT_FIT * float(np.sqrt(np.mean(values**2))):
        return core_material, _unconverged(core)
    from_core = np.concatenate([core.theta, [_logit(0.995)], np.full(n_channels, _logit(DEFAULT_F0))])
    weight, reflectance = START_FLAT_FRESNEL
    flat = [
        np.concatenate([start, [_logit(weight)], np.full(n_channels, _logit(reflectance))])
        for start in _starts(values)[: len(START_ROUGHNESS)]  # the dielectric starts come first
    ]
    extended = best([from_core, *flat], extended=True)
    extended_material = _material_of(extended.theta, n_channels, True)
    extended_rmse = _grid_rmse(extended_material, wi, wo, values)
    gain = 1.0 - extended_rmse / core_rmse
    if gain >= EXTENSION_GAIN:
        return extended_material, [
            f"{' and '.join(extended_material.extensions)} used: they lower the fitting grid's rmse from"
            f" {core_rmse:.4g} to {extended_rmse:.4g} 1/sr ({gain:.1%}, at least {EXTENSION_GAIN:.0%} asked)",
            *_unconverged(extended),
        ]
    if gain <= 0:  # the extended fit ended no better (a local optimum of more parameters): said as it is
        why = f"do not lower the fitting grid's rmse ({extended_rmse:.4g} 1/sr with them, {core_rmse:.4g} without)"
    else:
        why = (
            f"would lower the fitting grid's rmse by only {gain:.1%} (from {core_rmse:.4g} to {extended_rmse:.4g} 1/sr;"
            f" {EXTENSION_GAIN:.0%} asked)"
        )
    return core_material, [f"no extensions: KHR_materials_specular and KHR_materials_ior {why}", *_unconverged(core)]


class _Solved(NamedTuple):
    theta: np.ndarray  # the unconstrained parameters (_parameters)
    cost: float  # Σ r² of the loss
    n_steps: int
    converged: bool


def _unconverged(solved: _Solved) -> list[str]:
    if solved.converged:
        return []
    return [
        f"the glTF fit stopped after {solved.n_steps} steps without meeting its tolerances: the material may lie"
        " farther from the fitted BRDF than the best glTF material would"
    ]


# ---------------------------------------------------------------------- from a fit result
def _xyz_to_rgb_matrix() -> np.ndarray:
    """IEC 61966-2-1's XYZ → linear sRGB matrix, as ``views/render.display_rgb`` applies it (rows: r, g, b)."""
    return display_rgb(np.eye(3), ("x", "y", "z"))[0].T


def _channel_plan(channels: Sequence[str]) -> tuple[str, list[str]]:
    """How ``channels`` become glTF's linear RGB: ``rgb``, ``xyz`` or ``grey``, with the notes a user reads."""
    channels = tuple(channels)
    if len(channels) == 3 and channels == ("x", "y", "z"):
        return "xyz", ["channels x, y, z (CIE XYZ) converted to linear sRGB (IEC 61966-2-1) for the material"]
    if len(channels) == 3:
        notes = [] if channels == ("r", "g", "b") else [f"channels {', '.join(channels)} taken as r, g, b"]
        return "rgb", notes
    if len(channels) == 1:
        return "grey", [f"one channel ({channels[0]}): the material is grey (the same base colour in r, g and b)"]
    raise BrdfInputError(
        Argument("result"),
        f" has {len(channels)} channels ({', '.join(channels)}); a glTF material takes three (r, g, b, or x, y, z"
        " as CIE XYZ) or one (grey)",
    )


def _in_channels(material: GltfMaterial, plan: str):
    """The material's BRDF in the fit's channels, as ``brdf(wi, wo) -> (N, C)``: its RGB converted back to XYZ
    (``plan`` xyz), its r channel (grey), or its RGB."""
    if plan == "xyz":
        rgb_to_xyz = np.linalg.inv(_xyz_to_rgb_matrix())
        return lambda wi, wo: material.brdf(wi, wo) @ rgb_to_xyz.T
    if plan == "grey":
        return lambda wi, wo: material.brdf(wi, wo)[:, :1]
    return material.brdf


def gltf_of_gltf_fit(result: FitResult) -> GltfMaterial | None:
    """The material of a fit of the ``gltf`` model, its numbers unchanged (the model's exact export): ``ior`` as
    ``KHR_materials_ior`` where it is not glTF's 1.5, the coat as ``KHR_materials_clearcoat`` where ``clearcoat`` is
    not 0, the anisotropy as ``KHR_materials_anisotropy`` where ``anisotropy_strength`` is not 0 (its tangent the
    data's ``+x``: :func:`_tangent_notes`), the sheen as ``KHR_materials_sheen`` where ``sheen_color`` is not 0. None
    for channels a glTF material holds only converted (CIE XYZ); one channel is grey (its base and sheen colours)."""
    if _channel_plan(result.channels)[0] == "xyz":
        return None
    params = result.params
    base_color = [float(value) for value in params["base_color"]]
    sheen_color = [float(value) for value in params.get("sheen_color", [0.0])]  # none without gltf:sheen=true
    ior = float(params["ior"])
    return GltfMaterial(
        _rgb(base_color),
        float(params["metallic"]),
        float(params["roughness"]),
        ior=None if ior == DEFAULT_IOR else ior,
        clearcoat=float(params["clearcoat"]),
        clearcoat_roughness=float(params["clearcoat_roughness"]),
        anisotropy_strength=float(params["anisotropy_strength"]),
        anisotropy_rotation=float(params["anisotropy_rotation"]),
        sheen_color=_rgb(sheen_color),
        sheen_roughness=float(params.get("sheen_roughness", 0.0)),
    )


def _tangent_notes(material: GltfMaterial) -> list[str]:
    """Where an anisotropic material's tangent must lie for a viewer to show the fit: KHR_materials_anisotropy
    stretches the lobe along the mesh's tangent turned by anisotropyRotation, and the fit's tangent is the data's
    ``+x``."""
    if not material.needs_tangents:
        return []
    return [
        "anisotropic (KHR_materials_anisotropy): the lobe is stretched along the mesh's tangent turned by"
        f" anisotropyRotation = {material.anisotropy_rotation:.6g} rad, so a mesh needs tangents (glTF's TANGENT"
        " attribute, or a normal texture to derive them from) that lie where the data's +x lay on the sample; the"
        " preview sphere has them, along its lines of latitude"
    ]


def _rgb(values: list[float]) -> tuple[float, float, float]:
    """A colour of one channel (grey) or three (r, g, b) as glTF's three numbers."""
    return cast("tuple[float, float, float]", tuple(values * 3 if len(values) == 1 else values))


def _fit(result: FitResult) -> tuple[GltfMaterial, Approximation, list[str], str]:
    if not isinstance(result, FitResult):
        raise BrdfInputError(Argument("result"), f" must be a FitResult, not {type(result).__name__}")
    plan, notes = _channel_plan(result.channels)
    mapping = MODELS[result.model].exact_export("gltf") if result.model in MODELS else None
    exact = None if mapping is None else mapping(result)
    if exact is not None:  # the renderer's own model, fitted: its numbers as they are, the error measured all the same
        approximation = approximation_error(result, _in_channels(exact, plan))
        notes = [*notes, "exact: the fitted glTF material, its numbers unchanged", *_tangent_notes(exact)]
        return exact, approximation, notes, plan
    known = reference(result)
    rgb = _in_rgb(known) if plan == "xyz" else known
    if known.turns > 1:
        material, fit_notes = _anisotropic_material(rgb)
    else:
        fine, coarse = ((samples.wi, samples.wo, samples.values) for samples in rgb.grids())
        material, fit_notes = fit_material(*fine, result.loss, search=coarse)
    approximation = approximation_error(result, _in_channels(material, plan), known)
    warnings = approximation.warnings("glTF's metallic-roughness BRDF")
    retro = retro_reflection_note(result, "glTF's BRDF", "no glTF material")
    return material, approximation, notes + fit_notes + retro + warnings, plan


#: An anisotropic fit's glTF stand-in has no clear coat, as the isotropic one has none (:func:`fit_material`): a free
#: coat fitted to a grid (whose azimuths are bins' midpoints) turns into a mirror (roughness 6·10⁻⁴ on a Ward fit),
#: a spike between the grid's directions that costs the fit nothing and renders as a glint 10¹¹ times too bright.
NO_COAT = Holding(fixed={"clearcoat": 0.0})


def _anisotropic_material(known: Reference) -> tuple[GltfMaterial, list[str]]:
    """glTF's material fitted to an anisotropic fit (``known``, its grids with the light at several azimuths:
    ``approximate.isotropic``; in linear RGB or grey, :func:`_in_rgb`): brdffit's ``gltf`` model (the same BRDF,
    ``physics/renderers/gltf.py``, with ``KHR_materials_anisotropy``'s strength and rotation and ``KHR_materials_ior``'s
    index freed, no coat: :data:`NO_COAT`) refitted coarse to fine (``approximate.coarse_refit``,
    ``approximate.refined``), and the notes on it."""
    fitted = refined(known, coarse_refit(known, "gltf", NO_COAT), NO_COAT)
    notes = [
        "anisotropic: glTF's BRDF with KHR_materials_anisotropy fitted to it (brdffit's gltf model, its tangent found"
        " with the lobe)"
    ]
    material = gltf_of_gltf_fit(fitted)
    assert material is not None  # fitted in linear RGB or grey, which a glTF material holds
    return material, notes + _tangent_notes(material)


def _in_rgb(known: Reference) -> Reference:
    """``known`` (a fit in CIE XYZ) with its tabulated grids in linear sRGB (:func:`_xyz_to_rgb_matrix`), which glTF's
    material is fitted in; its error is still measured in XYZ (:func:`_in_channels`)."""
    to_rgb = _xyz_to_rgb_matrix().T

    def converted(samples: Samples) -> Samples:
        return Samples.from_arrays(
            samples.wi, samples.wo, samples.values @ to_rgb, channels=("r", "g", "b"), source=samples.source
        )

    fine, coarse = known.grids()
    return dataclasses.replace(known, fine=converted(fine), coarse=converted(coarse))


def fit_gltf(result: FitResult) -> tuple[GltfMaterial, Approximation]:
    """The glTF material closest to ``result``'s fitted BRDF, and how far it lies from it.

    The fitted BRDF is tabulated on ``export.approximate.fitting_grid`` and :func:`fit_material` fits glTF's BRDF to
    it with ``result``'s loss. Channels: r, g, b (any three) as they are; x, y, z (CIE XYZ) converted to linear
    sRGB first (``views/render.display_rgb``); one channel as grey; other counts are refused. The
    :class:`~brdffit.export.approximate.Approximation` compares the material with the fit in the fit's own
    channels (the material's RGB converted back to XYZ; its r channel for grey). :func:`write_gltf` also returns
    the notes on these choices.
    """
    material, approximation, _, _ = _fit(result)
    return material, approximation


def _plain(value):
    """``value`` with numpy scalars and arrays as Python numbers and lists (for JSON)."""
    if isinstance(value, dict):
        return {str(key): _plain(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    return value


def write_gltf(
    result: FitResult, path: str | os.PathLike, binary: bool | None = None, samples: "Samples | None" = None
) -> tuple[GltfMaterial, Approximation, list[str]]:
    """Fit a glTF material to ``result`` (:func:`fit_gltf`) and write it, atomically, as a ``.gltf`` file (JSON) or,
    with ``binary`` (default: when ``path`` ends in ``.glb``), as a binary ``.glb`` file.

    The file is a glTF 2.0 document showing the material on a preview sphere (:meth:`GltfMaterial.to_gltf`, named
    after the file), so that a viewer opens it; the material's ``extras.brdffit`` holds the approximation (``rmse``
    in 1/sr over the grid, the worst relative ``albedo_error`` and where), the notes, and the source fit's model,
    options, channels, loss and parameters; given ``samples`` (the data, as ``at_data.data_for`` returns them), also
    how far the material lies from them at their directions (``at_data``; :class:`~brdffit.export.at_data.DataError`,
    the first note). Returns the material, the approximation and the notes (one line each).
    """
    path = Path(path)
    if binary is None:
        binary = path.suffix.lower() == ".glb"
    if not path.parent.is_dir():
        raise BrdfInputError(f"{path}: the folder {path.parent} does not exist")
    material, approximation, notes, plan = _fit(result)
    at_data = {}
    if samples is not None:
        error = data_error(result, samples, _in_channels(material, plan), EVALUATED_BY)
        notes, at_data = [error.line(), *notes], {"at_data": error.to_dict()}
    extras = {
        "brdffit": {
            "version": __version__,
            "approximation": approximation.to_dict(),
            **at_data,
            "notes": notes,
            "source": {
                "model": result.model,
                "model_options": dict(result.model_options),
                "channels": list(result.channels),
                "loss": result.loss,
                "params": result.params,
            },
        }
    }
    if binary:
        with atomic_path(path) as temporary:
            temporary.write_bytes(material.to_glb(path.stem, extras=_plain(extras)))
    else:
        write_text_atomic(path, json_text(material.to_gltf(path.stem, extras=_plain(extras))) + "\n")
    return material, approximation, notes
