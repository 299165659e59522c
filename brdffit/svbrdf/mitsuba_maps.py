"""The maps of a fit of one of Mitsuba 3's own models as a Mitsuba BSDF with ``bitmap`` textures, and a scene that
renders the sample as the capture photographed it.

A model whose Mitsuba export is exact (``principled``, ``roughplastic``: the same plugin with the same numbers,
``export/mitsuba.py``) exports texel by texel where Mitsuba takes a texture for a parameter: every map that varies
over the fitted texels becomes a ``bitmap`` of its OpenEXR image (linear float32; nearest-texel lookup, so a texel is
its own value), the others stay numbers. Some parameters Mitsuba takes as one number only (:data:`TEXTURED` lists the
others): ``roughplastic``'s ``alpha``, ``principled``'s ``specular``. Maps where one of those varies are not exported
(``maps.json`` says why): hold it (``fixed={"specular": 0.5}``, ``--fix specular=0.5``) to export them.

``MAPS/mitsuba/`` then holds:

* ``bsdf.xml``: the BSDF (``<bsdf type="principled" id="material">``), its textures named relative to it;
* ``<parameter>.exr``: those textures, a texel that was not fitted as 0;
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
from .images import write_exr
from .maps import Maps

FOLDER = "mitsuba"
#: The models whose maps export, and the Mitsuba parameters each takes as a texture (None: all of them).
TEXTURED: dict[str, frozenset[str] | None] = {
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
COLOURS = ("base_color", "diffuse_reflectance", "specular_reflectance")
XML_VERSION = "3.0.0"


def mitsuba_bsdf_of_maps(maps: Maps) -> tuple[dict[str, Any], list[str]]:
    """The Mitsuba BSDF (the dictionary ``mitsuba.load_dict`` takes, textures named ``<parameter>.exr``) of
    ``maps`` and the names of its textured parameters (module docstring); one line where it cannot be made."""
    from ..export.mitsuba import exact_bsdf_of

    if maps.model not in TEXTURED:
        raise BrdfInputError(
            f"the maps of a {maps.model} fit have no Mitsuba texture export: fit the capture with one of Mitsuba's"
            f" own models ({', '.join(TEXTURED)})"
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
    bsdf = exact_bsdf_of(first)
    allowed = TEXTURED[maps.model]
    textured = []
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
        bsdf[name] = {"type": "bitmap", "filename": f"{name}.exr", "filter_type": "nearest"} | (
            {} if name in COLOURS else {"raw": True}
        )
        textured.append(name)
    return bsdf, textured


def write_mitsuba_maps(folder: str | os.PathLike, maps: Maps, light_mm, intensity, camera_mm) -> dict[str, Any]:
    """``MAPS/mitsuba/`` (module docstring) for ``maps`` written into ``folder``, the scene's defaults those of a
    light at ``light_mm`` of ``intensity`` (per channel: one, or r, g, b) and a camera at the height of
    ``camera_mm``; what ``maps.json`` says of it (the files), or why nothing was written."""
    try:
        bsdf, textured = mitsuba_bsdf_of_maps(maps)
    except BrdfInputError as error:
        return {"folder": None, "not_written": str(error)}
    out = Path(folder) / FOLDER
    out.mkdir(parents=True, exist_ok=True)
    for name in textured:
        array = maps.params[name]
        image = array if array.ndim == 2 or name not in COLOURS else _rgb(array)
        write_exr(out / f"{name}.exr", np.nan_to_num(image, nan=0.0))
    write_text_atomic(out / "bsdf.xml", "\n".join(_bsdf_xml(bsdf, "", version=XML_VERSION, id_="material")) + "\n")
    write_text_atomic(out / "scene.xml", _scene_xml(maps, light_mm, intensity, camera_mm))
    return {"folder": FOLDER, "textured": textured, "files": ["bsdf.xml", "scene.xml", *(f"{n}.exr" for n in textured)]}


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
        if isinstance(value, dict) and value.get("type") == "rgb":
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
