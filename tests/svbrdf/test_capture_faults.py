"""What a new user ran into, each kept from coming back: a capture of one channel written whole, a pixel clipped to 0
dropped rather than outweighing a texel, a maps folder that holds one fit, the capture's folder and files never
written into, nothing written on a bad photograph, clipped 16-bit pixels dropped, 8-bit masks read."""

import json
import shutil
import warnings

import numpy as np
import pytest

import brdffit.svbrdf as svbrdf
from brdffit.data_synth.capture import light_positions, write_capture
from brdffit.errors import BrdfInputError, FitWarning
from brdffit.svbrdf.images import read_image


def _grey(folder, shape=(4, 4), images=12, **options):
    """A one-channel Lambert capture (albedo 0.5, f = 0.5/π), its light intensities ``[1.0]``."""
    write_capture(folder, lambda wi, wo: np.full((len(wi), 1), 0.5 / np.pi), light_positions(images), shape=shape,
                  **options)  # fmt: skip
    return folder


def test_a_capture_of_one_channel_is_fitted_and_written_whole(tmp_path):
    capture = _grey(tmp_path / "capture")
    assert json.loads((capture / "capture.json").read_text())["images"][0]["light"]["intensity"] == [1.0]
    maps = svbrdf.fit(capture, "lambert", output=tmp_path / "maps", progress=False)
    assert maps.channels == ("value",) and maps.params["rho_d"].shape == (4, 4, 1)
    np.testing.assert_allclose(read_image(tmp_path / "maps" / "textures" / "rho_d.exr"), maps.params["rho_d"][..., 0])
    np.testing.assert_allclose(maps.params["rho_d"], 0.5, rtol=0.03)
    assert (tmp_path / "maps" / "textures" / "rho_d.png").exists()


def test_a_pixel_clipped_to_zero_is_dropped_by_the_relative_loss(ward_capture, tmp_path):
    """One pixel of one photograph at −1 (read as 0): with the relative loss, which divides by the value, that
    sample is dropped (23 of 24 left) and the texel is fitted from the others, within 3% of the truth."""
    folder, truth = ward_capture
    copy = tmp_path / "capture"
    shutil.copytree(folder, copy)
    image = np.load(copy / "img_003.npy")
    image[0, 0, 1] = -1.0
    np.save(copy / "img_003.npy", image)
    maps = svbrdf.fit(copy, "ward", progress=False, tile_texels=16)
    assert maps.fit["n_samples"][0, 0] == 23 and maps.fit["n_samples"][0, 1] == 24
    for name in ("rho_d", "alpha"):
        np.testing.assert_allclose(maps.params[name][0, 0], truth[name][0, 0], rtol=0.03)


def test_a_maps_folder_holds_one_fit(ward_capture, tmp_path):
    """A second fit into the same folder removes what the first wrote and it does not: another model's textures."""
    folder, _ = ward_capture
    output = tmp_path / "maps"
    svbrdf.fit(folder, "ward", output=output, progress=False, tile_texels=64)
    assert (output / "textures" / "alpha.exr").exists()
    svbrdf.fit(folder, "lambert", output=output, progress=False, tile_texels=64)
    assert sorted(path.name for path in (output / "textures").iterdir()) == ["rho_d.exr", "rho_d.png"]
    svbrdf.fit(folder, "lambert", output=output, progress=False, textures=False, tile_texels=64)
    assert list((output / "textures").iterdir()) == []


def test_the_capture_s_folder_is_never_written_into(ward_capture):
    folder, _ = ward_capture
    with pytest.raises(BrdfInputError, match="is the capture's folder; give another folder for the maps"):
        svbrdf.fit(folder, "ward", output=folder, progress=False)
    with pytest.raises(BrdfInputError, match="not a folder"):
        svbrdf.fit(folder, "ward", output=folder / "img_000.npy", progress=False)


def test_a_bad_photograph_writes_nothing(ward_capture, tmp_path):
    folder, _ = ward_capture
    copy = tmp_path / "capture"
    shutil.copytree(folder, copy)
    np.save(copy / "img_005.npy", np.zeros((3, 3, 3)))
    with pytest.raises(BrdfInputError, match=r"img_005\.npy: 3 × 3 pixels"):
        svbrdf.fit(copy, "ward", output=tmp_path / "maps", progress=False)
    assert not (tmp_path / "maps").exists()


def test_a_clipped_sixteen_bit_pixel_is_saturated(tmp_path):
    """A 16-bit image's 65,535 is a clipped pixel: dropped without a ``saturation`` key; ``saturation`` is in the
    file's own integers, whatever the ``scale``."""
    tifffile = pytest.importorskip("tifffile", reason="tifffile (the svbrdf extra) is not installed")
    capture = _grey(tmp_path / "capture", shape=(2, 2), images=6)
    document = json.loads((capture / "capture.json").read_text())
    for index, image in enumerate(document["images"]):
        values = np.load(capture / image["file"])
        pixels = np.round(values / values.max() * 40000).astype(np.uint16)
        if index == 2:
            pixels[0, 0] = 65535
        tifffile.imwrite(capture / f"img_{index}.tif", pixels[..., 0])
        image["file"] = f"img_{index}.tif"
    (capture / "capture.json").write_text(json.dumps(document | {"scale": 3.0}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # values of another scale than the relative loss's floor
        maps = svbrdf.fit(capture, "lambert", progress=False)
        assert maps.fit["n_samples"][0, 0] == 5 and maps.fit["n_samples"][0, 1] == 6
        (capture / "capture.json").write_text(json.dumps(document | {"scale": 3.0, "saturation": 39000}))
        assert svbrdf.fit(capture, "lambert", progress=False).fit["n_samples"][0, 1] < 6


def test_an_eight_bit_mask_is_read(ward_capture, tmp_path):
    from PIL import Image

    folder, _ = ward_capture
    copy = tmp_path / "capture"
    shutil.copytree(folder, copy)
    mask = np.full((16, 16), 255, dtype=np.uint8)
    mask[:2] = 0
    Image.fromarray(mask).save(copy / "mask.png")
    document = json.loads((copy / "capture.json").read_text())
    (copy / "capture.json").write_text(json.dumps(document | {"mask": "mask.png"}))
    maps = svbrdf.fit(copy, "lambert", progress=False)
    assert maps.summary()["fitted"] == 14 * 16
