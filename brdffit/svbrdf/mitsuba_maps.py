"""The maps of a fit whose Mitsuba 3 export is exact as a Mitsuba BSDF with ``bitmap`` textures, and a scene that
renders the sample as the capture photographed it.

A model whose Mitsuba export is exact (``export/mitsuba.py``) exports texel by texel where Mitsuba takes a texture for
a parameter: every map of the BSDF that varies over the fitted texels becomes a ``bitmap`` of its OpenEXR image (linear
float32; nearest-texel lookup, so a texel is its own value), the others stay numbers.

* Mitsuba's own ``principled`` and ``roughplastic``: the same plugin with the same numbers. Some parameters Mitsuba
  takes as one number only (:data:`TEXTURED` lists the others): ``roughplastic``'s ``alpha``, ``principled``'s
  ``specular``. Maps where one of those varies are not exported (``maps.json`` says why): hold it
  (``fixed={"specular": 0.5}``, ``--fix specular=0.5``) to export them.
* ``lambert``: a ``diffuse`` BSDF, ``reflectance`` the map of ``rho_d``.
* ``cook-torrance`` with Smith shadowing (and a conductor, dielectric or no Fresnel term): the ``export/mitsuba.py``
  mapping texel by texel, a ``roughconductor`` (``alpha``, or ``alpha_u`` and ``alpha_v``; ``eta`` and ``k``) and a
  ``diffuse`` joined by a ``blendbsdf`` whose ``weight`` is a map too: each texel's ``w = max ks / (max kd + max
  ks)``, ``reflectance = kd/(1 − w)``, ``specular_reflectance = ks/w``. Mitsuba's reflectances are at most 1, so
  every texel must have ``max kd + max ks ≤ 1`` (a metal's ``ks`` held at 1 with ``kd`` held at 0); maps beyond it
  are not exported, as maps of a model Mitsuba does not have (Ward, Lafortune, the V-groove shadowing) are not:
  ``maps.json`` says why. Mitsuba's anisotropic ``alpha_u`` lies along the rectangle's ``dp/du``, the capture's
  ``+x``: an anisotropic fit exports where every texel's tangent lies along ``x`` or ``y`` (``phi_t`` 0 or 90°,
  ``fixed={"phi_t": 0}``), its two roughnesses exchanged where it lies along ``y``.

``MAPS/mitsuba/`` then holds:

* ``bsdf.xml``: the BSDF (``<bsdf type="principled" id="material">``, or the model's), its textures named relative to
  it;
* ``<parameter>.exr``: those textures, named by the BSDF's parameter, a texel that was not fitted as 0;
* ``scene.xml``: the sample (a ``rectangle`` the plane's size, in mm, its texture coordinates turned so that
  texel (0, 0) is the top left seen from +z), lit by a point light and seen by a perspective camera looking straight
  down at its centre, whose field of view is the sample's width: its image is the capture's rectified image for a
  camera above the sample's centre (texels must be square: the film's pixels are). The light's position and
  intensity (``"r, g, b"``), the camera's height and the samples per pixel are the scene's parameters
  (``mitsuba.load_file(path, light_x=…, light_y=…, light_z=…, intensity=…, camera_z=…, spp=…)``), by default the
  capture's first photograph's light and its camera's height (not its x and y: the scene's camera is above the
  centre).
"""

import os
from pathlib import Path
from typing import Any

import numpy as np

from .._files import write_text_atomic
from ..errors import Argument, BrdfInputError
from ..fitting.single.result import FitResult
from ..physics.models.registry import get_model
from .images import write_exr
from .maps import Maps

FOLDER = "mitsuba"
#: The models whose maps export, and the Mitsuba parameters each takes as a texture (None: all of them).
TEXTURED: dict[str, frozenset[str] | None] = {
    "lambert": None,
    "cook-torrance": None,  # with Smith shadowing: export/mitsuba.py's exact mapping
    "principled": frozenset(
        {
            "base_color",
            "roughness",
            "metallic",
            "spec_tint",
            "anisotropic",
            "sheen",
            "sheen_tint",
            "clearcoat",
            "clearcoat_gloss",
        }
    ),  # not its specular (Mitsuba 3.9: a float)
    "roughplastic": frozenset({"diffuse_reflectance", "specular_reflectance"}),
}
#: Parameters Mitsuba takes as a colour (an RGB bitmap); the others are numbers (one-channel bitmaps, ``raw``).
COLOURS = ("base_color", "diffuse_reflectance", "specular_reflectance", "reflectance")
#: How far above 1 a texel's largest reflectance may lie and still be 1 (the blend's division rounds).
RANGE_TOLERANCE = 1e-9
#: How far (degrees) an anisotropic texel's tangent may lie from the capture's x or y axis and still lie along it.
AXIS_TOLERANCE = 1e-9
XML_VERSION = "3.0.0"


def mitsuba_bsdf_of_maps(maps: Maps) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The Mitsuba BSDF (the dictionary ``mitsuba.load_dict`` takes, textures named ``<parameter>.exr``) of
    ``maps`` and its textures, each parameter's map (H, W) or (H, W, 3) (module docstring); one line where it
    cannot be made."""
    from ..export.mitsuba import exact_bsdf

    if maps.model not in TEXTURED:
        raise BrdfInputError(
            f"the maps of a {maps.model} fit have no Mitsuba texture export: fit the capture with a model whose"
            f" Mitsuba export is exact ({', '.join(TEXTURED)})"
        )
    fitted = maps.fitted
    if not fitted.any():
        raise BrdfInputError("no texel was fitted: there is no material to export")
    if len(maps.channels) not in (1, 3):
        raise BrdfInputError(f"Mitsuba's textures are RGB; these maps have {len(maps.channels)} channels")
    row, column = (int(index[0]) for index in np.nonzero(fitted))
    first = FitResult(  # one texel's parameters: the BSDF's keys and the numbers of the parameters that do not vary
        model=maps.model,
        model_options=maps.model_options,
        channels=maps.channels,
        params=maps.texel_params(row, column),
        loss=maps.loss,
        cost=0.0,
        rmse=0.0,
        n_samples=0,
        n_steps=0,
        converged=True,
    )
    bsdf = exact_bsdf(first)
    if bsdf is None:
        options = get_model(maps.model, **maps.model_options).model_options
        raise BrdfInputError(
            f"the maps of this {maps.model} fit (shadowing {options['shadowing']}, fresnel {options['fresnel']}) have"
            " no Mitsuba counterpart: Mitsuba's roughconductor has Smith shadowing and a conductor, dielectric or no"
            " Fresnel term"
        )
    textures: dict[str, np.ndarray] = {}
    if maps.model in ("lambert", "cook-torrance"):
        return _texturised(_mapped(maps), fitted, textures), textures
    allowed = TEXTURED[maps.model]
    for name, array in maps.params.items():
        values = array[fitted]
        if name not in bsdf or np.all(values == values[0]):
            continue
        if allowed is not None and name not in allowed:
            raise BrdfInputError(
                f"the maps' {name} varies ({np.nanmin(values):.4g}–{np.nanmax(values):.4g}), and Mitsuba's"
                f" {maps.model} takes one number for it: hold it (",
                Argument("fixed", f"{name}=…"),
                ") to export",
            )
        bsdf[name] = _bitmap(name)
        textures[name] = _rgb(array) if name in COLOURS else array
    return bsdf, textures


def _bitmap(name: str) -> dict[str, Any]:
    """The ``bitmap`` texture of parameter ``name``: a colour as stored, any other number ``raw``."""
    return {"type": "bitmap", "filename": f"{name}.exr", "filter_type": "nearest"} | (
        {} if name in COLOURS else {"raw": True}
    )


def _mapped(maps: Maps) -> dict[str, Any]:
    """The Mitsuba BSDF of ``lambert`` or Smith ``cook-torrance`` maps with each texel's value, (H, W) or (H, W, 3),
    at its leaves: ``export/mitsuba.py``'s exact mapping texel by texel (module docstring); a one-line error where a
    texel lies beyond Mitsuba's reflectances or an anisotropic tangent off the capture's axes."""
    from ..export.mitsuba import blend_split

    params, fitted = maps.params, maps.fitted
    if maps.model == "lambert":
        reflectance = _rgb(params["rho_d"])
        _within_range(np.max(reflectance, axis=-1), fitted, "rho_d")
        return {"type": "diffuse", "reflectance": reflectance}
    options = get_model(maps.model, **maps.model_options).model_options
    kd, ks = _rgb(params["kd"]), _rgb(params["ks"])
    specular: dict[str, Any] = {"type": "roughconductor", "distribution": options["distribution"]}
    if options["anisotropic"]:
        specular["alpha_u"], specular["alpha_v"] = _along_the_axes(params, fitted)
    else:
        specular["alpha"] = params["m"]
    if options["fresnel"] == "none":
        specular["material"] = "none"
    elif options["fresnel"] == "conductor":
        specular["eta"], specular["k"] = _rgb(params["eta"]), _rgb(params["k"])
    else:
        specular["eta"], specular["k"] = params["eta"], 0.0
    largest_kd, largest_ks = np.max(kd, axis=-1), np.max(ks, axis=-1)
    _within_range(largest_kd + largest_ks, fitted, "max kd + max ks")
    if not np.any(largest_kd[fitted] > 0):
        return specular | {"specular_reflectance": np.minimum(ks, 1.0)}
    if not np.any(largest_ks[fitted] > 0):
        return {"type": "diffuse", "reflectance": np.minimum(kd, 1.0)}
    weight, reflectance, specular_reflectance = blend_split(kd, ks)  # each texel as a single fit's export splits it
    specular["specular_reflectance"] = np.minimum(specular_reflectance, 1.0)
    diffuse = {"type": "diffuse", "reflectance": np.minimum(reflectance, 1.0)}
    return {"type": "blendbsdf", "weight": weight, "diffuse": diffuse, "specular": specular}


def _within_range(largest: np.ndarray, fitted: np.ndarray, what: str) -> None:
    """One line where a fitted texel's ``largest`` reflectance (H, W) lies above Mitsuba's 1."""
    beyond = fitted & (largest > 1.0 + RANGE_TOLERANCE)
    if beyond.any():
        raise BrdfInputError(
            f"{int(beyond.sum())} of {int(fitted.sum())} texels have {what} above 1"
            f" (up to {largest[beyond].max():.4g}), beyond Mitsuba's reflectances: fit with the albedos held within"
            " them (a metal's kd held at 0)"
        )


def _along_the_axes(params: dict[str, np.ndarray], fitted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``alpha_u`` and ``alpha_v`` along the capture's ``x`` and ``y`` (Mitsuba's ``dp/du`` and ``dp/dv`` on the
    scene's rectangle): a texel's two exchanged where its tangent lies along ``y`` (``phi_t`` 90°); one line where a
    fitted texel's tangent lies along neither."""
    alpha_u, alpha_v, phi_t = params["alpha_u"], params["alpha_v"], params["phi_t"]
    along_y = np.abs(np.abs(phi_t) - 90.0) <= AXIS_TOLERANCE
    off = fitted & ~along_y & ~(np.abs(phi_t) <= AXIS_TOLERANCE)
    if off.any():
        raise BrdfInputError(
            f"{int(off.sum())} of {int(fitted.sum())} texels have their tangent at phi_t = {phi_t[off][0]:.4g}°, and"
            " Mitsuba's anisotropic roughconductor stretches alpha_u along the capture's x: hold phi_t at 0 to export"
        )
    return np.where(along_y, alpha_v, alpha_u), np.where(along_y, alpha_u, alpha_v)


def _texturised(node: dict[str, Any], fitted: np.ndarray, textures: dict[str, np.ndarray]) -> dict[str, Any]:
    """The BSDF ``node`` (:func:`_mapped`) with each map that varies over the ``fitted`` texels a :func:`_bitmap`
    (added to ``textures``) and each other one its number (a colour as ``rgb``)."""
    done: dict[str, Any] = {}
    for key, value in node.items():
        if isinstance(value, dict):
            done[key] = _texturised(value, fitted, textures)
        elif not isinstance(value, np.ndarray):
            done[key] = value
        elif np.all(value[fitted] == value[fitted][0]):
            first = value[fitted][0]
            done[key] = {"type": "rgb", "value": [float(v) for v in first]} if value.ndim == 3 else float(first)
        else:
            done[key], textures[key] = _bitmap(key), value
    return done


def write_mitsuba_maps(folder: str | os.PathLike, maps: Maps, light_mm, intensity, camera_mm) -> dict[str, Any]:
    """``MAPS/mitsuba/`` (module docstring) for ``maps`` written into ``folder``, the scene's defaults those of a
    light at ``light_mm`` of ``intensity`` (per channel: one, or r, g, b) and a camera at the height of
    ``camera_mm``; what ``maps.json`` says of it (the files), or why nothing was written."""
    try:
        bsdf, textures = mitsuba_bsdf_of_maps(maps)
    except BrdfInputError as error:
        return {"folder": None, "not_written": str(error)}
    out = Path(folder) / FOLDER
    out.mkdir(parents=True, exist_ok=True)
    textured = list(textures)
    for name, image in textures.items():
        write_exr(out / f"{name}.exr", np.nan_to_num(np.where(_fitted(maps, image), image, 0.0), nan=0.0))
    write_text_atomic(out / "bsdf.xml", "\n".join(_bsdf_xml(bsdf, "", version=XML_VERSION, id_="material")) + "\n")
    write_text_atomic(out / "scene.xml", _scene_xml(maps, light_mm, intensity, camera_mm))
    files = ["bsdf.xml", "scene.xml", *(f"{n}.exr" for n in textured)]
    return {"folder": FOLDER, "textured": textured, "files": files, "notes": _notes(maps, textures)}


def _notes(maps: Maps, textures: dict[str, np.ndarray]) -> list[str]:
    """What a user of the Mitsuba maps must know: where an anisotropic BSDF's tangent lies, and that raw colour
    textures (a conductor's index per channel) load in Mitsuba's RGB variants only."""
    notes = []
    raw_colours = [name for name, image in textures.items() if image.ndim == 3 and name not in COLOURS]
    if raw_colours:
        notes.append(
            f"{' and '.join(f'{name}.exr' for name in raw_colours)} hold one value per RGB channel, as the fit does"
            " (raw textures): render in an RGB variant of Mitsuba (scalar_rgb, llvm_ad_rgb); its spectral variants"
            " refuse raw colour textures"
        )
    if maps.model == "cook-torrance" and get_model(maps.model, **maps.model_options).model_options["anisotropic"]:
        notes.append(
            "anisotropic: Mitsuba's alpha_u lies along the shape's dp/du, on the scene's rectangle the capture's +x;"
            " on another mesh its u direction must lie where the capture's +x lay"
        )
    return notes


def _fitted(maps: Maps, image: np.ndarray) -> np.ndarray:
    """Which texels of ``image`` (H, W) or (H, W, C) were fitted, broadcast to its shape."""
    return maps.fitted if image.ndim == 2 else maps.fitted[..., None]


def _rgb(array: np.ndarray) -> np.ndarray:
    """A colour map as RGB: one channel as grey."""
    return np.repeat(array, 3, axis=-1) if array.shape[-1] == 1 else array


def _bsdf_xml(node: dict[str, Any], indent: str, version: str | None = None, id_: str | None = None) -> list[str]:
    """The XML lines of a BSDF dictionary with ``rgb`` values and ``bitmap`` textures."""
    attributes = (f' version="{version}"' if version else "") + f' type="{node["type"]}"'
    attributes += f' id="{id_}"' if id_ else ""
    lines, inner = [f"{indent}<bsdf{attributes}>"], indent + "    "
    for key, value in node.items():
        if key == "type":
            continue
        if isinstance(value, dict) and value.get("type") not in ("rgb", "bitmap"):  # a nested BSDF (a blend's)
            lines += _bsdf_xml(value, inner)
        elif isinstance(value, dict) and value.get("type") == "rgb":
            lines.append(f'{inner}<rgb name="{key}" value="{", ".join(repr(float(v)) for v in value["value"])}"/>')
        elif isinstance(value, dict) and value.get("type") == "bitmap":
            lines += [
                f'{inner}<texture type="bitmap" name="{key}">',
                f'{inner}    <string name="filename" value="{value["filename"]}"/>',
                f'{inner}    <string name="filter_type" value="nearest"/>',
                *([f'{inner}    <boolean name="raw" value="true"/>'] if value.get("raw") else []),
                f'{inner}    <transform name="to_uv"><scale x="1" y="-1"/><translate y="1"/></transform>',
                f"{inner}</texture>",
            ]
        elif isinstance(value, str):
            lines.append(f'{inner}<string name="{key}" value="{value}"/>')
        else:
            lines.append(f'{inner}<float name="{key}" value="{float(value)!r}"/>')
    return [*lines, f"{indent}</bsdf>"]


def _rgb_text(intensity) -> str:
    """A light's intensity (one number, or one per channel) as Mitsuba's ``rgb`` value: ``r, g, b``."""
    values = (
        np.broadcast_to(np.asarray(intensity, dtype=float).ravel()[:3], (3,))
        if np.size(intensity) in (1, 3)
        else [float(np.max(intensity))] * 3
    )
    return ", ".join(repr(float(value)) for value in values)


def _scene_xml(maps: Maps, light_mm, intensity, camera_mm) -> str:
    """The scene of the module docstring, its defaults the given light and camera."""
    light = [float(value) for value in light_mm]
    rows, columns = maps.shape
    height = float(camera_mm[2])
    fov = float(np.degrees(2.0 * np.arctan(maps.width_mm / 2.0 / height)))
    return f"""<scene version="{XML_VERSION}">
    <!-- brdffit's maps of a {maps.model} fit: the sample as the capture photographed it (mm) -->
    <default name="light_x" value="{light[0]!r}"/>
    <default name="light_y" value="{light[1]!r}"/>
    <default name="light_z" value="{light[2]!r}"/>
    <default name="intensity" value="{_rgb_text(intensity)}"/>
    <default name="camera_z" value="{height!r}"/>
    <default name="spp" value="64"/>
    <integrator type="direct"/>
    <sensor type="perspective">
        <float name="fov" value="{fov!r}"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world"><lookat origin="0, 0, $camera_z" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="{columns}"/>
            <integer name="height" value="{rows}"/>
            <rfilter type="box"/>
        </film>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    </sensor>
    <include filename="bsdf.xml"/>
    <shape type="rectangle">
        <transform name="to_world"><scale x="{maps.width_mm / 2!r}" y="{maps.height_mm / 2!r}" z="1"/></transform>
        <ref id="material"/>
    </shape>
    <emitter type="point">
        <point name="position" x="$light_x" y="$light_y" z="$light_z"/>
        <rgb name="intensity" value="$intensity"/>
    </emitter>
</scene>
"""
