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
==============================  ==================================================================================

Mitsuba's ``blendbsdf`` averages: ``(1 − w)·first + w·second``. The export divides the albedos by the weights,
``reflectance = kd/(1 − w)`` and ``specular_reflectance = ks/w``, with ``w = max ks / (max kd + max ks)`` over the
channels, which keeps both within [0, 1] whenever ``max kd + max ks ≤ 1``; Mitsuba refuses RGB reflectances above 1
("Invalid RGB reflectance value … must be in the range [0, 1]"), so a fit beyond that is scaled into range and the
error said. Mitsuba's Beckmann ``G1`` is Walter et al.'s rational approximation (2007, eq. 27), within 0.5% of
the exact ``erf`` form brdffit uses.

Every other model (Ward, Phong, Lafortune, the V-groove and height-correlated shadowing, Schlick's Fresnel) has no
Mitsuba counterpart: the export fits Mitsuba's model (GGX and Beckmann ``roughconductor`` with a diffuse term,
the better of the two) to the fitted BRDF (``approximate.py``) and reports how far it lies.
"""

import dataclasses
import pprint
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._version import __version__
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from ..physics.models.registry import MODELS, get_model
from ..physics.models.specs import spec_of

if TYPE_CHECKING:
    from ..data.samples import Samples
    from .approximate import Approximation
    from .at_data import DataError

#: The Mitsuba 3 scene-description version the XML declares.
XML_VERSION = "3.0.0"
#: The models that stand in for one Mitsuba cannot express: Cook-Torrance as ``roughconductor`` plus ``diffuse``.
STAND_INS = (
    {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"},
    {"fresnel": "conductor", "distribution": "beckmann", "shadowing": "smith"},
)


@dataclass(frozen=True)
class MitsubaExport:
    """A Mitsuba 3 BSDF as ``mitsuba.load_dict`` takes it (``bsdf``), the fit it was made from (``source``, a model
    spec), the fit it expresses exactly (``exported``: the source itself, or the Mitsuba model fitted to it,
    ``refitted``), how far that lies from the source (``approximation``, None when exact) and what a user must know
    (``notes``); ``scale``: the factor the exported fit's albedos were scaled by into Mitsuba's range (the BSDF is
    ``scale`` times ``exported``); ``at_data``: how far the BSDF lies from the data at its directions, when given
    (``at_data.py``)."""

    bsdf: dict[str, Any]
    source: str
    exported: FitResult
    approximation: "Approximation | None" = None
    notes: list[str] = field(default_factory=list)
    refitted: bool = False
    scale: float = 1.0
    at_data: "DataError | None" = None

    @property
    def exact(self) -> bool:
        return self.approximation is None

    def brdf(self, wi, wo) -> np.ndarray:
        """The BSDF's BRDF (N, C) in 1/sr, by brdffit's model of it: ``scale`` times the exported fit's."""
        return self.scale * np.asarray(self.exported.predict(wi, wo))

    def compared_with(self, result: FitResult, samples: "Samples") -> "MitsubaExport":
        """This export of ``result`` with :attr:`at_data` measured on ``samples`` (``at_data.data_for``'s data):
        evaluated by Mitsuba itself where it is installed, else by :meth:`brdf`."""
        from .at_data import data_error
        from .mitsuba_eval import mitsuba_brdf, mitsuba_version

        version = mitsuba_version()
        if version is None:
            error = data_error(result, samples, self.brdf, "brdffit's model of the BSDF (Mitsuba is not installed)")
        else:
            error = data_error(result, samples, lambda wi, wo: mitsuba_brdf(self.bsdf, wi, wo), f"Mitsuba {version}")
        return dataclasses.replace(self, at_data=error)

    def to_xml(self) -> str:
        """Mitsuba 3 XML of the BSDF (``mitsuba.load_string`` takes it), with a comment on where it came from."""
        lines = [f"<!-- {line} -->" for line in self.comment_lines()]
        lines += _xml(self.bsdf, indent="", version=XML_VERSION)
        return "\n".join(lines) + "\n"

    def to_python(self) -> str:
        """A Python module: ``bsdf``, the dictionary ``mitsuba.load_dict(bsdf)`` takes, and ``approximation``."""
        comment = "".join(f"# {line}\n" for line in self.comment_lines())
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
        elif not self.refitted:
            how = f"exact but for the scale into Mitsuba's range: {self.approximation.line()}"
        else:
            how = f"approximate: {spec_of(self.exported.model, self.exported.model_options)} fitted to it, "
            how += self.approximation.line()
        at_data = [] if self.at_data is None else [self.at_data.line()]
        return [made, how, *at_data, *self.notes]


def mitsuba_bsdf(result: FitResult) -> MitsubaExport:
    """The Mitsuba 3 BSDF of ``result`` (module docstring): exact where Mitsuba has the model, else the better of
    Mitsuba's GGX and Beckmann ``roughconductor`` (with ``diffuse``) fitted to the fitted BRDF. An exact export
    maps parameters only (no JAX is imported); the others fit (``approximate.py``)."""
    source = spec_of(result.model, result.model_options)
    notes = _channel_notes(result)
    exact = _exact_bsdf(result)
    if exact is not None:
        bsdf, scale = exact
        if scale == 1.0:
            return MitsubaExport(bsdf, source, result, None, notes)
        from .approximate import approximation_error

        notes.append(
            f"its albedos exceed what Mitsuba's RGB reflectances hold (kd + ks up to {1 / scale:.3g}):"
            f" scaled by {scale:.3g}"
        )
        approximation = approximation_error(result, _scaled(result, scale))
        return MitsubaExport(bsdf, source, result, approximation, notes, scale=scale)
    from .approximate import approximation_error, refit

    candidates = [refit(result, "cook-torrance", **options) for options in STAND_INS]
    exported, _ = min(candidates, key=lambda pair: pair[1].rmse)
    bsdf, scale = cook_torrance_bsdf(exported)
    if scale != 1.0:
        notes.append(f"the Mitsuba model's albedos exceed Mitsuba's RGB range: scaled by {scale:.3g}")
    approximation = approximation_error(result, _scaled(exported, scale))
    notes += approximation.warnings("Mitsuba's microfacet model")
    return MitsubaExport(bsdf, source, exported, approximation, notes, refitted=True, scale=scale)


def _exact_bsdf(result: FitResult) -> tuple[dict[str, Any], float] | None:
    """The BSDF of ``result`` by its model's exact mapping onto Mitsuba (its registry entry's ``exports``), with the
    factor its albedos were scaled by; None where the model, or these options of it, have no exact counterpart."""
    mapping = MODELS[result.model].exact_export("mitsuba") if result.model in MODELS else None
    return None if mapping is None else mapping(result)


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


def lambert_bsdf(result: FitResult) -> tuple[dict[str, Any], float]:
    """The Mitsuba ``diffuse`` BSDF of a Lambertian ``result``, and the factor its albedo was scaled by (1 unless
    Mitsuba's [0, 1] range forced it): the ``lambert`` model's exact export."""
    diffuse = np.asarray(_rgb(result.params["rho_d"]))
    scale = min(1.0, 1.0 / max(diffuse.max(), 1e-300))
    return {"type": "diffuse", "reflectance": _rgb_value(diffuse * scale)}, scale


def cook_torrance_bsdf(result: FitResult) -> tuple[dict[str, Any], float] | None:
    """The Mitsuba dictionary of a Cook-Torrance ``result`` with Smith shadowing and a conductor, dielectric or no
    Fresnel term (``roughconductor``, with ``diffuse`` in a ``blendbsdf``; a conductor's ``eta`` and ``k`` per
    channel as ``rgb`` values), and the factor its albedos were scaled by
    (1 unless Mitsuba's [0, 1] range forced it); None for other options (the ``cook-torrance`` model's exact
    export)."""
    params, options = result.params, get_model(result.model, **result.model_options).model_options
    if options["shadowing"] != "smith" or options["fresnel"] not in ("conductor", "dielectric", "none"):
        return None
    kd, ks = np.asarray(_rgb(params["kd"])), np.asarray(_rgb(params["ks"]))
    specular: dict[str, Any] = {"type": "roughconductor", "distribution": options["distribution"]}
    specular["alpha"] = float(params["m"])
    if options["fresnel"] == "none":
        specular["material"] = "none"
    elif options["fresnel"] == "conductor":  # one complex index per channel, as Mitsuba's RGB textures
        specular["eta"] = _rgb_value(np.asarray(_rgb(np.atleast_1d(params["eta"]))))
        specular["k"] = _rgb_value(np.asarray(_rgb(np.atleast_1d(params["k"]))))
    else:
        specular["eta"] = float(params["eta"])
        specular["k"] = 0.0
    total = kd.max() + ks.max()
    scale = min(1.0, 1.0 / max(total, 1e-300))
    kd, ks = kd * scale, ks * scale
    weight = ks.max() / max(kd.max() + ks.max(), 1e-300)
    if weight >= 1.0 or kd.max() == 0.0:
        return specular | {"specular_reflectance": _rgb_value(ks)}, scale
    diffuse = {"type": "diffuse", "reflectance": _rgb_value(kd / (1.0 - weight))}
    if weight == 0.0:
        return diffuse, scale
    specular["specular_reflectance"] = _rgb_value(ks / weight)
    return {"type": "blendbsdf", "weight": float(weight), "diffuse": diffuse, "specular": specular}, scale


def _rgb_value(values: np.ndarray) -> dict[str, Any]:
    """Mitsuba's ``rgb`` texture of three numbers (plain floats: the Python form writes them as such)."""
    return {"type": "rgb", "value": [float(value) for value in values]}


def _scaled(result: FitResult, scale: float):
    """``result``'s BRDF times ``scale``, as ``brdf(wi, wo)``."""
    return lambda wi, wo: scale * result.predict(wi, wo)


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
