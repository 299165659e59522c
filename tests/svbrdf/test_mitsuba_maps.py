"""The maps of fits whose Mitsuba export is exact (``principled``; ``lambert`` and Smith ``cook-torrance``) as a
Mitsuba BSDF with bitmap textures and a scene: Mitsuba renders the scene at a capture's own light as the photograph it
took (the issue's acceptance), its BSDF is the maps' model texel by texel, and maps Mitsuba cannot hold say why. Also
the neighbour starts: texels whose start search ended in a local minimum are fitted again from a neighbour's
parameters, and every texel of noise-free photographs ends at the truth's cost."""

import json

import numpy as np
import pytest

import brdffit.svbrdf as svbrdf
from brdffit.data_synth.capture import synth_capture
from brdffit.errors import BrdfInputError
from brdffit.physics.models.registry import get_model
from brdffit.svbrdf.images import read_image
from brdffit.svbrdf.mitsuba_maps import mitsuba_bsdf_of_maps, write_mitsuba_maps
from brdffit.svbrdf.relight import stacked_params, texel_brdf
from brdffit.svbrdf.texels import point_light

pytestmark = pytest.mark.slow  # its module fixture fits a whole capture: ~30 s

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install 'brdffit[render]')")

#: Held: a coat the photographs cannot determine, and the specular level Mitsuba's principled takes as one number.
HELD = {"clearcoat": 0.0, "specular": 0.5}


@pytest.fixture(scope="module")
def principled(tmp_path_factory):
    """An 8 × 8 capture of Mitsuba's principled (a rough red blended into a rougher blue), no noise, fitted."""
    folder = tmp_path_factory.mktemp("principled")
    truth = synth_capture(folder / "capture", "principled", shape=(8, 8), n_images=24, noise=0.0, seed=0)
    maps = svbrdf.fit(folder / "capture", "principled", output=folder / "maps", progress=False, fixed=HELD)
    return folder, maps, truth


def test_every_texel_reaches_the_truths_cost_with_neighbour_starts(principled):
    """Noise-free photographs: the truth's cost is rounding (~4e-14); the start search alone left 37 of 64 texels
    of the same capture in local minima (costs 0.01–0.09); their neighbours' parameters take them to the truth."""
    _, maps, truth = principled
    assert maps.neighbour_starts["improved"] > 0
    assert np.max(maps.fit["cost"]) < 1e-9
    for name in ("base_color", "roughness"):
        np.testing.assert_allclose(maps.params[name], truth[name], rtol=1e-5)


def test_mitsuba_renders_the_exported_scene_as_the_capture_photographed_it(principled):
    folder, _, _ = principled
    described = json.loads((folder / "maps" / "maps.json").read_text())["mitsuba"]
    assert described["textured"] == ["roughness", "clearcoat_gloss", "base_color"]
    capture = svbrdf.read_capture(folder / "capture")
    mi.set_variant("scalar_rgb")
    for shot in capture.shots[::11]:
        x, y, z = (float(value) for value in shot.light_mm)
        scene = mi.load_file(str(folder / "maps" / "mitsuba" / "scene.xml"), light_x=x, light_y=y, light_z=z, spp=64)
        rendered, photographed = np.array(mi.render(scene)), read_image(shot.file)
        error = np.median(np.abs(rendered - photographed) / photographed)
        assert error < 0.03, error  # measured 0.1–0.2%: the pixels' footprints, Mitsuba's float32


def test_a_map_mitsuba_takes_as_one_number_is_not_exported(principled):
    _, maps, _ = principled
    varied = svbrdf.Maps(
        maps.model, maps.model_options, maps.loss, maps.channels,
        maps.params | {"specular": maps.params["roughness"]}, maps.fit, maps.width_mm, maps.height_mm,
    )  # fmt: skip
    with pytest.raises(BrdfInputError, match=r"the maps' specular varies .* Mitsuba's principled takes one number"):
        mitsuba_bsdf_of_maps(varied)
    ward = svbrdf.Maps("ward", {}, "relative", ("r", "g", "b"), {}, {"n_samples": np.ones((2, 2))}, 10.0, 10.0)
    with pytest.raises(BrdfInputError, match="the maps of a ward fit have no Mitsuba texture export"):
        mitsuba_bsdf_of_maps(ward)


#: Materials of captures whose maps Mitsuba's own BSDFs hold exactly: (model, options, first, second).
EXACT_CAPTURES = {
    "lambert": ("lambert", {}, None, None),
    "blended-ggx": (
        "cook-torrance",
        {"distribution": "ggx", "shadowing": "smith", "fresnel": "dielectric"},
        {"kd": [0.3, 0.2, 0.1], "ks": [0.4, 0.4, 0.4], "m": 0.15, "eta": 1.5},
        {"kd": [0.1, 0.2, 0.35], "ks": [0.5, 0.5, 0.5], "m": 0.35, "eta": 1.6},
    ),
    "metal-beckmann": (
        "cook-torrance",
        {"distribution": "beckmann", "shadowing": "smith", "fresnel": "conductor"},
        {"kd": [0.0, 0.0, 0.0], "ks": [1.0, 1.0, 1.0], "m": 0.2, "eta": [0.2, 0.4, 1.4], "k": [3.9, 2.4, 1.8]},
        {"kd": [0.0, 0.0, 0.0], "ks": [1.0, 1.0, 1.0], "m": 0.4, "eta": [1.6, 1.0, 0.9], "k": [2.9, 2.8, 2.6]},
    ),
    "brushed-ggx": (
        "cook-torrance",
        {"distribution": "ggx", "shadowing": "smith", "fresnel": "conductor", "anisotropic": True},
        {"kd": [0.1, 0.1, 0.1], "ks": [0.8, 0.8, 0.8], "alpha_u": 0.08, "alpha_v": 0.3, "phi_t": 0.0,
         "eta": [0.2, 0.4, 1.4], "k": [3.9, 2.4, 1.8]},
        {"kd": [0.2, 0.1, 0.05], "ks": [0.7, 0.7, 0.7], "alpha_u": 0.15, "alpha_v": 0.5, "phi_t": 0.0,
         "eta": [1.6, 1.0, 0.9], "k": [2.9, 2.8, 2.6]},
    ),
}  # fmt: skip


def _true_maps(folder, name: str) -> svbrdf.Maps:
    """The true maps of a 6 × 6 capture of ``EXACT_CAPTURES[name]`` without noise, written in ``folder/capture``."""
    model, options, first, second = EXACT_CAPTURES[name]
    truth = synth_capture(folder / "capture", model, first, second, shape=(6, 6), n_images=12, noise=0.0, **options)
    fit = {"n_samples": np.full((6, 6), 12)}
    return svbrdf.Maps(model, options, "relative", ("r", "g", "b"), dict(truth), fit, 100.0, 100.0)


def _written(folder, name: str, edited: bool = False) -> tuple[svbrdf.Maps, object, dict]:
    """:func:`_true_maps` of ``name`` (the anisotropic one with its tangent along y in every other texel, its
    roughnesses exchanged: the same lobes, which Mitsuba's alpha_u along x holds only so), written to Mitsuba in
    ``folder/maps``; the capture; what maps.json says of them. ``edited``: texel (5, 5) not fitted and, for a blend,
    the first row without a diffuse albedo and texel (1, 0) without a specular one (a blend's weight of 1 and 0)."""
    maps = _true_maps(folder, name)
    if edited:
        maps.fit["n_samples"][5, 5] = 0
        for values in maps.params.values():
            values[5, 5] = np.nan
        if "kd" in maps.params and np.any(maps.params["kd"] > 0):
            maps.params["kd"][0] = 0.0
            maps.params["ks"][1, 0] = 0.0
    if name == "brushed-ggx":
        along_y = (np.arange(36).reshape(6, 6) % 2).astype(bool)
        u, v = maps.params["alpha_u"].copy(), maps.params["alpha_v"].copy()
        maps.params["alpha_u"], maps.params["alpha_v"] = np.where(along_y, v, u), np.where(along_y, u, v)
        maps.params["phi_t"] = np.where(along_y, 90.0, 0.0)
    capture = svbrdf.read_capture(folder / "capture")
    first = capture.shots[0]
    described = write_mitsuba_maps(folder / "maps", maps, first.light_mm, first.intensity, first.camera_mm)
    assert described.get("folder") == "mitsuba", described
    return maps, capture, described


#: How far Mitsuba's BSDF may lie from the maps' model (relative): float32 textures and arithmetic for GGX; for
#: Beckmann, Mitsuba's G1 is Walter et al.'s rational approximation, within 0.5% of the erf form (export/mitsuba.py).
MITSUBA_AGREES = {"ggx": 1e-4, "beckmann": 5e-3}


@pytest.mark.parametrize("name", list(EXACT_CAPTURES))
def test_mitsubas_bsdf_of_exact_maps_is_the_maps_model_at_every_texel(tmp_path, name):
    """The maps of models whose Mitsuba export is exact (``lambert``; ``cook-torrance`` with Smith shadowing: a blend
    of a diffuse and a roughconductor whose weight is a map too, a metal's roughconductor alone, an anisotropic one)
    evaluated by Mitsuba at each texel (its texture coordinates on the scene's rectangle) and the capture's
    directions there: the model's BRDF at the texel's parameters."""
    maps, capture, described = _written(tmp_path, name, edited=True)
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_file(str(tmp_path / "maps" / "mitsuba" / "bsdf.xml"))
    for texture in described["textured"]:  # a texel not fitted is 0
        assert np.all(read_image(tmp_path / "maps" / "mitsuba" / f"{texture}.exr")[5, 5] == 0.0)
    model = get_model(maps.model, **maps.model_options)
    rows, columns = maps.shape
    texels = np.arange(rows * columns)
    flat = {key: value.reshape(rows * columns, *value.shape[2:]) for key, value in maps.params.items()}
    lights = np.stack([shot.light_mm for shot in capture.shots])
    cameras = np.stack([shot.camera_mm for shot in capture.shots])
    wi, wo, _ = point_light(capture.texel_centres(), lights, cameras)
    fitted = texels[maps.fitted.ravel()]
    stacked = stacked_params(model, flat, fitted)
    expected = np.full((len(texels), len(lights), 3), np.nan)
    for k in range(len(lights)):
        expected[fitted, k] = texel_brdf(model, stacked, wi[fitted, k], wo[fitted, k])
    tolerance = MITSUBA_AGREES[maps.model_options.get("distribution", "ggx")]
    for texel in texels[maps.fitted.ravel()]:
        row, column = divmod(int(texel), columns)
        interaction = mi.SurfaceInteraction3f()
        interaction.uv = mi.Point2f((column + 0.5) / columns, 1.0 - (row + 0.5) / rows)  # the rectangle's
        for light, viewer, value in zip(wi[texel], wo[texel], expected[texel], strict=True):
            interaction.wi = mi.Vector3f(*viewer)
            evaluated = bsdf.eval(mi.BSDFContext(), interaction, mi.Vector3f(*light))
            got = np.array([evaluated[0], evaluated[1], evaluated[2]]) / light[2]
            np.testing.assert_allclose(got, value, rtol=tolerance, err_msg=f"texel ({row}, {column})")


def test_mitsuba_renders_exact_cook_torrance_maps_as_photographed(tmp_path):
    """Mitsuba's render of the exported scene (a blend whose weight is a map) at the capture's lights is the
    noise-free photograph, within 1% (median; measured 0.26–0.41%: each pixel averages the BRDF over its 17 mm
    footprint, where the photograph holds the value at the texel's centre: 2.6% for the anisotropic capture's narrow
    lobes, whose BSDF the test above checks texel by texel)."""
    _, capture, _ = _written(tmp_path, "blended-ggx")
    mi.set_variant("scalar_rgb")
    errors = []
    for shot in capture.shots[::3]:
        x, y, z = (float(value) for value in shot.light_mm)
        scene = mi.load_file(str(tmp_path / "maps" / "mitsuba" / "scene.xml"), light_x=x, light_y=y, light_z=z)
        rendered, photographed = np.array(mi.render(scene)), read_image(shot.file)
        errors.append(np.median(np.abs(rendered - photographed) / photographed))
    assert max(errors) < 0.01, errors


def test_maps_mitsuba_cannot_hold_say_why(tmp_path):
    """Reflectances above 1, an anisotropic tangent off the capture's axes and the V-groove shadowing each refuse the
    export in one line that says what to hold or choose."""
    maps = _true_maps(tmp_path, "blended-ggx")
    bright = svbrdf.Maps(**{**vars(maps), "params": maps.params | {"ks": maps.params["ks"] + 0.6}})
    with pytest.raises(BrdfInputError, match=r"36 of 36 texels have max kd \+ max ks above 1 .* albedos held within"):
        mitsuba_bsdf_of_maps(bright)
    vgroove = svbrdf.Maps(**{**vars(maps), "model_options": {"fresnel": "dielectric"}})
    with pytest.raises(BrdfInputError, match=r"\(shadowing v-groove, fresnel dielectric\) have no Mitsuba counterpart"):
        mitsuba_bsdf_of_maps(vgroove)
    brushed = _true_maps(tmp_path / "brushed", "brushed-ggx")
    turned = svbrdf.Maps(**{**vars(brushed), "params": brushed.params | {"phi_t": np.full((6, 6), 30.0)}})
    with pytest.raises(BrdfInputError, match=r"36 of 36 texels have their tangent at phi_t = 30°"):
        mitsuba_bsdf_of_maps(turned)


def test_the_notes_say_where_the_tangent_lies_and_which_variants_load_an_index_per_channel(tmp_path):
    _, _, described = _written(tmp_path, "brushed-ggx")
    notes = " ".join(described["notes"])
    assert "eta.exr and k.exr hold one value per RGB channel" in notes and "RGB variant" in notes
    assert "alpha_u lies along the shape's dp/du" in notes
    _, _, described = _written(tmp_path / "blend", "blended-ggx")
    assert described["notes"] == []  # a dielectric's one index: a number; isotropic
