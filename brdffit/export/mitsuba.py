"""A fit as a Mitsuba 3 BSDF: exact where Mitsuba has the model, else Mitsuba's model fitted to it, with the error.

Mitsuba 3's ``roughconductor`` (Jakob et al., Mitsuba 3 documentation, "Rough conductor material") is
``specular_reflectance · F(cos β) · D · G / (4 ci co)`` with GGX or Beckmann ``D``, separable Smith ``G`` and the
exact conductor Fresnel term of a complex index ``eta + i k`` (``material="none"``: ``F = 1``); ``diffuse`` is
``reflectance / π``. So brdffit's Cook-Torrance with ``shadowing="smith"`` maps exactly:

==============================  ==================================================================================
brdffit                         Mitsuba 3
==============================  ==================================================================================
``distribution``                ``distribution`` (``beckmann``, ``ggx``); ``m`` is ``alpha``
``fresnel="conductor"``         ``eta``, ``k``
``fresnel="dielectric"``        ``eta``, ``k = 0`` (the conductor formula with ``k = 0`` is the dielectric one)
``fresnel="none"``              ``material="none"``
``ks``, ``kd``                  ``specular_reflectance``, ``diffuse.reflectance``, joined by ``blendbsdf``
``anisotropic=True``            ``alpha_u``, ``alpha_v``; the tangent is the shape's ``dp/du`` (see below)
==============================  ==================================================================================

Mitsuba's BSDFs have no tangent rotation: an anisotropic ``roughconductor``'s ``alpha_u`` lies along the shape's
``dp/du``. The export of an anisotropic fit is therefore exact in the frame turned by ``phi_t``: with the mesh's
tangent (its UVs' ``u``) along the fit's tangent, at ``phi_t`` from the data's ``+x``. The note and the file's
comment say so, and ``export --samples`` evaluates Mitsuba at the data's directions turned by ``−phi_t``: the error
a user gets with the tangent so aligned.

Mitsuba's ``blendbsdf`` averages: ``(1 − w)·first + w·second``. The export divides the albedos by the weights,
``reflectance = kd/(1 − w)`` and ``specular_reflectance = ks/w``, with ``w = max ks / (max kd + max ks)`` over the
channels, which keeps both within [0, 1] whenever ``max kd + max ks ≤ 1``; Mitsuba refuses RGB reflectances above 1
("Invalid RGB reflectance value … must be in the range [0, 1]"), so a fit beyond that is never scaled into range
(which would darken the material quietly): Mitsuba's model is refitted to the fitted BRDF with its albedos held
within the range, as an approximation is, and its error said. Mitsuba's Beckmann ``G1`` is Walter et al.'s
rational approximation (2007, eq. 27), within 0.5% of the exact ``erf`` form brdffit uses.

Every other model (Ward, Phong, Lafortune, the V-groove and height-correlated shadowing, Schlick's Fresnel) has no
Mitsuba counterpart: the export fits Mitsuba's model (GGX and Beckmann ``roughconductor`` with a diffuse term,
anisotropic where the fit is, the better of the two; one whose coarse fit lies :data:`CANNOT_WIN` times farther than
the other's is not refined) to the fitted BRDF (``approximate.py``) and reports how far it lies.
"""

import dataclasses
import pprint
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jax import float64
from .._version import __version__
from ..errors import Argument, BrdfInputError
from ..fitting.options import Holding
from ..fitting.single.result import FitResult
from ..physics.geometry import in_turned_frame
from ..physics.models.model import LobeModel
from ..physics.models.registry import MODELS, get_model
from ..physics.models.specs import spec_of

if TYPE_CHECKING:
    from ..data.samples import Samples
    from .approximate import Approximation, Reference
    from .at_data import DataError

#: The Mitsuba 3 scene-description version the XML declares.
XML_VERSION = "3.0.0"
#: The models that stand in for one Mitsuba cannot express: Cook-Torrance as ``roughconductor`` plus ``diffuse``.
STAND_INS = (
    {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"},
    {"fresnel": "conductor", "distribution": "beckmann", "shadowing": "smith"},
)
#: The stand-ins of an anisotropic BRDF (``approximate.isotropic``): the same, anisotropic (``alpha_u``, ``alpha_v``
#: and the tangent's azimuth ``phi_t``, which the export's note says where to put).
ANISOTROPIC_STAND_INS = tuple(options | {"anisotropic": True} for options in STAND_INS)


@dataclass(frozen=True)
class MitsubaExport:
    """A Mitsuba 3 BSDF as ``mitsuba.load_dict`` takes it (``bsdf``), the fit it was made from (``source``, a model
    spec), the fit it expresses exactly (``exported``: the source itself, or the Mitsuba model fitted to it), how far
    that lies from the source (``approximation``, None when exact) and what a user must know (``notes``);
    ``at_data``: how far the BSDF lies from the data at its directions, when given (``at_data.py``); ``change``: what
    an export of the fitted model itself left out (a negligible diffuse albedo), when it did."""

    bsdf: dict[str, Any]
    source: str
    exported: FitResult
    approximation: "Approximation | None" = None
    notes: list[str] = field(default_factory=list)
    at_data: "DataError | None" = None
    change: str | None = None

    @property
    def exact(self) -> bool:
        return self.approximation is None

    def brdf(self, wi, wo) -> np.ndarray:
        """The BSDF's BRDF (N, C) in 1/sr, by brdffit's model of it: the exported fit's."""
        return np.asarray(self.exported.predict(wi, wo))

    @property
    def tangent_azimuth(self) -> float | None:
        """The azimuth (degrees from the data's ``+x``) at which the BSDF's tangent, Mitsuba's ``dp/du``, must lie:
        an anisotropic fit's ``phi_t`` (0 for ``principled``, whose tangent is the data's ``+x``); None for an isotropic
        BSDF."""
        return float(self.exported.params.get("phi_t", 0.0)) if _anisotropic(self.exported) else None

    def compared_with(self, result: FitResult, samples: "Samples") -> "MitsubaExport":
        """This export of ``result`` with :attr:`at_data` measured on ``samples`` (``at_data.data_for``'s data):
        evaluated by Mitsuba itself where it is installed (at the data's directions in the frame of the BSDF's
        tangent, :attr:`tangent_azimuth`), else by :meth:`brdf`."""
        from .at_data import data_error
        from .mitsuba_eval import mitsuba_brdf, mitsuba_version

        version = mitsuba_version()
        if version is None:
            error = data_error(result, samples, self.brdf, "brdffit's model of the BSDF (Mitsuba is not installed)")
        else:
            turn = np.radians(self.tangent_azimuth or 0.0)
            error = data_error(
                result,
                samples,
                lambda wi, wo: mitsuba_brdf(self.bsdf, in_turned_frame(wi, turn), in_turned_frame(wo, turn)),
                f"Mitsuba {version}",
            )
        return dataclasses.replace(self, at_data=error)

    def to_xml(self) -> str:
        """Mitsuba 3 XML of the BSDF (``mitsuba.load_string`` takes it), with a comment on where it came from."""
        lines = [f"<!-- {_commented(line).replace('--', '- -')} -->" for line in self.comment_lines()]
        lines += _xml(self.bsdf, indent="", version=XML_VERSION)
        return "\n".join(lines) + "\n"

    def to_python(self) -> str:
        """A Python module: ``bsdf``, the dictionary ``mitsuba.load_dict(bsdf)`` takes, and ``approximation``."""
        comment = "".join(f"# {_commented(line)}\n" for line in self.comment_lines())
        approximation = None if self.approximation is None else self.approximation.to_dict()
        at_data = None if self.at_data is None else self.at_data.to_dict()
        return (
            f"{comment}bsdf = {pprint.pformat(self.bsdf, sort_dicts=False)}\n"
            f"approximation = {pprint.pformat(approximation, sort_dicts=False)}\n"
            f"at_data = {pprint.pformat(at_data, sort_dicts=False)}\n"
        )

    def comment_lines(self) -> list[str]:
        made = f"brdffit {__version__}: Mitsuba 3 BSDF of a {self.source} fit"
        if self.exact:
            beckmann = self.exported.model_options.get("distribution") == "beckmann"
            how = "exact" + (" but for Mitsuba's Beckmann G1 (Walter's approximation, within 0.5%)" if beckmann else "")
        else:
            assert self.approximation is not None  # every export but an exact one says how far it lies
            if self.change:
                how = f"exact but for {self.change}: {self.approximation.line()}"
            else:
                how = f"approximate: {spec_of(self.exported.model, self.exported.model_options)} fitted to it, "
                how += self.approximation.line()
        at_data = [] if self.at_data is None else [self.at_data.line()]
        return [made, how, *at_data, *self.notes]


def mitsuba_bsdf(result: FitResult) -> MitsubaExport:
    """The Mitsuba 3 BSDF of ``result`` (module docstring): exact where Mitsuba has the model and its albedos lie in
    Mitsuba's range, else the better of Mitsuba's GGX and Beckmann ``roughconductor`` (with ``diffuse``) fitted to the
    fitted BRDF, within that range. An exact export maps parameters only (no JAX is imported); the others fit
    (``approximate.py``). Nothing is ever scaled: a material Mitsuba cannot hold is refitted, and the error said."""
    source = spec_of(result.model, result.model_options)
    notes = _channel_notes(result)
    exact = exact_bsdf(result)
    if exact is not None and _in_range(result):
        return MitsubaExport(exact, source, result, None, notes + _tangent_notes(result))
    from .approximate import approximation_error, reference, refit, retro_reflection_note

    if exact is not None and (without := _without_negligible_diffuse(result)) is not None:
        diffuse = _albedo_maxima(result)[0]
        change = f"its diffuse albedo (at most {diffuse:.2g}), left out"
        notes.append(
            f"its diffuse albedo (at most {diffuse:.2g}) is left out: Mitsuba's blend of diffuse and roughconductor"
            f" cannot hold it beside a specular albedo of {_albedo_maxima(result)[1]:.3g}"
        )
        approximation = approximation_error(result, without.predict)
        bsdf = exact_bsdf_of(without)
        return MitsubaExport(bsdf, source, without, approximation, notes + _tangent_notes(result), change=change)

    known = reference(result)
    if exact is not None:  # the model Mitsuba has, refitted within its range
        notes.append(
            f"its albedos exceed what Mitsuba's RGB reflectances hold ({_range_text(result)}): Mitsuba's model"
            " refitted within that range, not scaled"
        )
        model = get_model(result.model, **result.model_options)
        exported, approximation = refit(result, model, _range_holding(result), known)
    else:
        exported, approximation = _best_stand_in(known)
    notes += _tangent_notes(exported) + approximation.warnings("Mitsuba's microfacet model")
    notes += retro_reflection_note(result, "Mitsuba's microfacet model", "no Mitsuba BSDF brdffit writes")
    return MitsubaExport(exact_bsdf_of(exported), source, exported, approximation, notes)


#: A stand-in whose coarse fit lies farther from the fitted BRDF than this many times the best one's (rmse over the
#: error grid) cannot win and is not refined: refining moves an rmse by a few percent (measured on the oak example's
#: fits: at most 3%), while the two stand-ins lie 1.1 to 2.2 times apart.
CANNOT_WIN = 1.25


def _best_stand_in(known: "Reference") -> "tuple[FitResult, Approximation]":
    """The stand-in of :data:`STAND_INS` (:data:`ANISOTROPIC_STAND_INS` for an anisotropic fit, whose grids have the
    light at several azimuths) that lies nearest the fit of ``known`` (``approximate.Reference``), within Mitsuba's
    range, and how far it lies: each fitted on the coarse grid (``approximate.coarse_refit``; refitted within the range
    where it ends beyond it; the stand-ins in two threads), and those that can win (:data:`CANNOT_WIN`) refined on the
    fine one."""
    from .approximate import approximation_error, coarse_refit, grid_rmse, refined

    def coarse_fit(options):
        fitted, holding = coarse_refit(known, "cook-torrance", **options), Holding()
        if not _in_range(fitted):
            holding = _range_holding(fitted)
            fitted = coarse_refit(known, "cook-torrance", holding, **options)
        return fitted, holding

    # Side by side: each one's programs load while the other computes (a ward-aniso fit's warm export 3.7 → 3.3 s).
    pool = ThreadPoolExecutor(2, thread_name_prefix="brdffit-stand-in")
    try:  # JAX's float64 switch is per thread
        coarse = list(pool.map(float64(coarse_fit), STAND_INS if known.turns == 1 else ANISOTROPIC_STAND_INS))
    except BaseException:  # a failed stand-in, or Ctrl-C: the other one is not waited for
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()
    rmse = [grid_rmse(known, fitted.predict) for fitted, _ in coarse]
    chosen = [pair for pair, error in zip(coarse, rmse, strict=True) if error <= CANNOT_WIN * min(rmse)]
    candidates = []
    for fitted, holding in chosen:
        fine = refined(known, fitted, holding)
        if not _in_range(fine):  # the fine grid pulled it beyond the range: held within it there too
            holding = _range_holding(fine)
            fine = refined(known, coarse_refit(known, fine.model, holding, **fine.model_options), holding)
        candidates.append((fine, approximation_error(known.result, fine.predict, known)))
    return min(candidates, key=lambda pair: pair[1].rmse)


def _albedo_maxima(result: FitResult) -> tuple[float, float]:
    """The largest diffuse and specular albedo of ``result`` over the channels (0 for a model without lobes)."""
    model = get_model(result.model, **result.model_options)
    params = model.dictionary.to_params(result.params)
    return float(np.max(params.diffuse)), float(np.max(params.specular, initial=0.0))


#: How far inside Mitsuba's range a refit's albedos are held: their sum within it after the blend's division.
_RANGE_MARGIN = 1e-9


#: A diffuse albedo at most this is left out of an export rather than refitting the material (a metal's fit holds
#: ks at 1, and noise leaves a kd of 1e-8 to 1e-5 beside it: at most 3·10⁻⁵ 1/sr, which the error reported shows).
NEGLIGIBLE_DIFFUSE = 1e-4


def _without_negligible_diffuse(result: FitResult) -> FitResult | None:
    """``result`` with its diffuse albedo set to 0 where that is at most :data:`NEGLIGIBLE_DIFFUSE` and what is left
    lies in Mitsuba's range; else None."""
    diffuse, specular = _albedo_maxima(result)
    if not (0.0 < diffuse <= NEGLIGIBLE_DIFFUSE and specular <= 1.0):
        return None
    name = _lobe_model(result).diffuse_name
    return dataclasses.replace(result, params=result.params | {name: [0.0] * len(result.channels)})


def _in_range(result: FitResult) -> bool:
    """Whether Mitsuba holds ``result``'s albedos as they are: ``max kd + max ks ≤ 1`` (module docstring); a
    renderer's own model (a whole-lobe one: ``principled``) keeps its parameters within the renderer's ranges."""
    if getattr(get_model(result.model, **result.model_options), "whole", False):
        return True
    return sum(_albedo_maxima(result)) <= 1.0


def _range_text(result: FitResult) -> str:
    model = _lobe_model(result)
    names = model.diffuse_name + (f" + {model.specular_name}" if model.n_lobes else "")
    return f"{names} up to {sum(_albedo_maxima(result)):.3g}, at most 1"


def _range_holding(result: FitResult) -> Holding:
    """Bounds that keep a refit of ``result``'s model within Mitsuba's range: the diffuse and specular albedos
    share it as ``result``'s largest ones do (``max kd + max ks ≤ 1``); an albedo that is 0 stays 0."""
    model = _lobe_model(result)
    diffuse, specular = _albedo_maxima(result)
    top = 1.0 - _RANGE_MARGIN
    if not model.n_lobes:
        return Holding(bounds={model.diffuse_name: (0.0, top)})
    share = specular / (diffuse + specular)
    if share >= 1.0 - _RANGE_MARGIN:
        return Holding(fixed={model.diffuse_name: 0.0}, bounds={model.specular_name: (0.0, top)})
    if share <= _RANGE_MARGIN:
        return Holding(fixed={model.specular_name: 0.0}, bounds={model.diffuse_name: (0.0, top)})
    return Holding(bounds={model.diffuse_name: (0.0, (1.0 - share) * top), model.specular_name: (0.0, share * top)})


def exact_bsdf(result: FitResult) -> dict[str, Any] | None:
    """The BSDF of ``result`` by its model's exact mapping onto Mitsuba (its registry entry's ``exports``); None where
    the model, or these options of it, have no exact counterpart."""
    mapping = MODELS[result.model].exact_export("mitsuba") if result.model in MODELS else None
    return None if mapping is None else mapping(result)


def exact_bsdf_of(result: FitResult) -> dict[str, Any]:
    """:func:`exact_bsdf` of a result whose model has an exact mapping (Mitsuba's own, or one of the model's)."""
    bsdf = exact_bsdf(result)
    assert bsdf is not None, f"no exact Mitsuba BSDF for {result.model}"
    return bsdf


def _lobe_model(result: FitResult) -> LobeModel:
    """``result``'s model, a lobe model: only those have exact exports to Mitsuba, whose albedos these functions
    weigh."""
    model = get_model(result.model, **result.model_options)
    assert isinstance(model, LobeModel), f"{result.model} is not a lobe model"
    return model


def _anisotropic(result: FitResult) -> bool:
    if result.model == "principled":  # its tangent along the data's +x
        return float(result.params["anisotropic"]) > 0.0
    return result.model == "cook-torrance" and bool(result.model_options.get("anisotropic", False))


def _tangent_notes(result: FitResult) -> list[str]:
    """Where an anisotropic BSDF's tangent must lie for the export to be the fit (module docstring)."""
    if not _anisotropic(result):
        return []
    phi_t = float(result.params.get("phi_t", 0.0))
    where = "along the data's +x" if phi_t == 0.0 else f"at phi_t = {phi_t:.6g}° from the data's +x"
    return [
        f"anisotropic: Mitsuba's alpha_u lies along the shape's tangent (dp/du), which must lie {where}"
        + ("" if phi_t == 0.0 else f" (turn the mesh's UVs, or its tangent, by {phi_t:.6g}°)")
        + "; the BSDF is the fit in that frame"
    ]


def _rgb(values) -> list[float]:
    """Albedos as Mitsuba's linear RGB: three channels as they are, one as grey."""
    values = [float(value) for value in values]
    return values * 3 if len(values) == 1 else values


def _channel_notes(result: FitResult) -> list[str]:
    channels = tuple(result.channels)
    if len(channels) == 1:
        return [f"one channel ({channels[0]}): written as grey, the same value in r, g and b"]
    if len(channels) != 3:
        raise BrdfInputError(
            f"a Mitsuba BSDF holds RGB albedos; this fit has {len(channels)} channels ({', '.join(channels)}):"
            " fit samples of 1 or 3 channels (spectral ones read with ",
            Argument("spectral_to", "rgb"),
            ")",
        )
    if channels == ("x", "y", "z"):
        raise BrdfInputError(
            "this fit's channels are CIE XYZ; Mitsuba's scalar_rgb takes linear sRGB: fit the samples read with ",
            Argument("spectral_to", "rgb"),
        )
    return []


def lambert_bsdf(result: FitResult) -> dict[str, Any]:
    """The Mitsuba ``diffuse`` BSDF of a Lambertian ``result`` (albedos at most 1, :func:`mitsuba_bsdf` sees to it):
    the ``lambert`` model's exact export."""
    return {"type": "diffuse", "reflectance": _rgb_value(np.asarray(_rgb(result.params["rho_d"])))}


def cook_torrance_bsdf(result: FitResult) -> dict[str, Any] | None:
    """The Mitsuba dictionary of a Cook-Torrance ``result`` with Smith shadowing and a conductor, dielectric or no
    Fresnel term (``roughconductor``, with ``diffuse`` in a ``blendbsdf``; ``max kd + max ks ≤ 1``,
    :func:`mitsuba_bsdf` sees to it; a conductor's ``eta`` and ``k`` per channel as ``rgb`` values); None for other
    options (the ``cook-torrance`` model's exact export)."""
    params, options = result.params, get_model(result.model, **result.model_options).model_options
    if options["shadowing"] != "smith" or options["fresnel"] not in ("conductor", "dielectric", "none"):
        return None
    kd, ks = np.asarray(_rgb(params["kd"])), np.asarray(_rgb(params["ks"]))
    specular: dict[str, Any] = {"type": "roughconductor", "distribution": options["distribution"]}
    if options["anisotropic"]:  # along the tangent and the bitangent; the tangent's azimuth: _tangent_notes
        specular["alpha_u"], specular["alpha_v"] = float(params["alpha_u"]), float(params["alpha_v"])
    else:
        specular["alpha"] = float(params["m"])
    if options["fresnel"] == "none":
        specular["material"] = "none"
    elif options["fresnel"] == "conductor":  # one complex index per channel, as Mitsuba's RGB textures
        specular["eta"] = _rgb_value(np.asarray(_rgb(np.atleast_1d(params["eta"]))))
        specular["k"] = _rgb_value(np.asarray(_rgb(np.atleast_1d(params["k"]))))
    else:
        specular["eta"] = float(params["eta"])
        specular["k"] = 0.0
    weight, reflectance, specular_reflectance = blend_split(kd, ks)
    if weight >= 1.0 or kd.max() == 0.0:
        return specular | {"specular_reflectance": _rgb_value(ks)}
    diffuse = {"type": "diffuse", "reflectance": _rgb_value(reflectance)}
    if weight == 0.0:
        return diffuse
    specular["specular_reflectance"] = _rgb_value(specular_reflectance)
    return {"type": "blendbsdf", "weight": float(weight), "diffuse": diffuse, "specular": specular}


def blend_split(kd: np.ndarray, ks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's ``blendbsdf`` of a diffuse albedo ``kd`` and a specular one ``ks`` (…, C), numpy over any leading
    axes (a texel's maps): the ``weight`` (…) ``w = max ks / (max kd + max ks)`` over the channels (0 where both are
    0), the diffuse's ``reflectance = kd/(1 − w)`` (0 where w is 1) and the specular's ``ks/w`` (0 where w is 0): all
    within [0, 1] where ``max kd + max ks ≤ 1`` (module docstring)."""
    largest_kd, largest_ks = np.max(kd, axis=-1), np.max(ks, axis=-1)
    total = largest_kd + largest_ks
    with np.errstate(invalid="ignore", divide="ignore"):
        weight = np.where(total > 0, largest_ks / total, 0.0)
        reflectance = np.where((weight < 1)[..., None], kd / (1.0 - weight)[..., None], 0.0)
        specular = np.where((weight > 0)[..., None], ks / weight[..., None], 0.0)
    return weight, reflectance, specular


def principled_bsdf(result: FitResult) -> dict[str, Any]:
    """The Mitsuba ``principled`` BSDF of a ``principled`` ``result``: its parameters unchanged (the model is
    Mitsuba's own, ``physics/renderers/principled.py``), ``base_color`` as an ``rgb`` value (one channel as grey)."""
    params = result.params
    scalars = {name: float(value) for name, value in params.items() if name != "base_color"}
    return {"type": "principled", "base_color": _rgb_value(np.asarray(_rgb(params["base_color"])))} | scalars


def roughplastic_bsdf(result: FitResult) -> dict[str, Any]:
    """The Mitsuba ``roughplastic`` BSDF of a ``roughplastic`` ``result``: its parameters and options unchanged (the
    model is Mitsuba's own, ``physics/renderers/roughplastic.py``), the reflectances as ``rgb`` values."""
    params, options = result.params, get_model(result.model, **result.model_options).model_options
    return {
        "type": "roughplastic",
        "distribution": options["distribution"],
        "alpha": float(params["alpha"]),
        "int_ior": float(options["int_ior"]),
        "diffuse_reflectance": _rgb_value(np.asarray(_rgb(params["diffuse_reflectance"]))),
        "specular_reflectance": _rgb_value(np.asarray(_rgb(params["specular_reflectance"]))),
    }


def _commented(line: str) -> str:
    """``line`` safe inside a comment of Python or XML: every character that is not printable (a line break in a
    channel name a result file carries, which would end a Python comment and start code) written as its escape, as
    ``repr`` writes it; XML's ``--`` is the caller's."""
    return "".join(character if character.isprintable() else repr(character)[1:-1] for character in line)


def _rgb_value(values: np.ndarray) -> dict[str, Any]:
    """Mitsuba's ``rgb`` texture of three numbers (plain floats: the Python form writes them as such)."""
    return {"type": "rgb", "value": [float(value) for value in values]}


def _xml(node: dict[str, Any], indent: str, version: str | None = None, name: str | None = None) -> list[str]:
    """The XML lines of a Mitsuba dictionary node (a BSDF, its nested BSDFs and their properties)."""
    attributes = f' version="{version}"' if version else ""
    attributes += f' type="{node["type"]}"'
    attributes += f' name="{name}"' if name else ""
    lines = [f"{indent}<bsdf{attributes}>"]
    inner = indent + "    "
    for key, value in node.items():
        if key == "type":
            continue
        if isinstance(value, dict) and value.get("type") == "rgb":
            rgb = ", ".join(repr(float(v)) for v in value["value"])
            lines.append(f'{inner}<rgb name="{key}" value="{rgb}"/>')
        elif isinstance(value, dict):
            lines += _xml(value, inner, name=key)
        elif isinstance(value, str):
            lines.append(f'{inner}<string name="{key}" value="{value}"/>')
        else:
            lines.append(f'{inner}<float name="{key}" value="{float(value)!r}"/>')
    lines.append(f"{indent}</bsdf>")
    return lines
