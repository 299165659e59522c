"""A capture's photographs as BRDF samples: the geometry and the value of a sample by hand, what is dropped, the
texel's own frame under a normal map, and an unrectified photograph rectified by its camera's matrix."""

import json

import numpy as np
import pytest

from brdffit import BrdfInputError
from brdffit.svbrdf import read_capture
from brdffit.svbrdf.images import read_image, read_rows
from brdffit.svbrdf.texels import read_photographs, rectified, texel_samples

#: The photographs are held as float32: a value read back lies within 2⁻²⁴ (relative) of the file's, ~6e-8.
FLOAT32 = 1e-7


def _capture(folder, images, **extra):
    """A one-texel capture of a 10 × 10 mm plane (its centre at the origin) with ``images``: (value (C,), light,
    intensity, camera) each."""
    entries = []
    for index, (value, light, intensity, camera) in enumerate(images):
        np.save(folder / f"i{index}.npy", np.array(value, dtype=float).reshape(1, 1, -1))
        entries.append(
            {
                "file": f"i{index}.npy",
                "light": {"position_mm": light, "intensity": intensity},
                "camera": {"position_mm": camera},
            }
        )
    document = {"brdffit_capture": 1, "plane": {"width_mm": 10.0, "height_mm": 10.0, "texels": [1, 1]}}
    (folder / "capture.json").write_text(json.dumps(document | {"images": entries} | extra))
    return read_capture(folder)


def test_a_samples_value_by_hand(tmp_path):
    """A light at (30, 0, 40) mm is 50 mm from the texel at cos θi = 0.8; a radiance of 0.2 under an intensity of 2
    is f = L·d²/(I·cos θi) = 0.2 · 2500 / (2 · 0.8) = 312.5 1/sr, with wi = (0.6, 0, 0.8) and wo the camera's +z."""
    capture = _capture(tmp_path, [([0.2], [30.0, 0.0, 40.0], [2.0], [0.0, 0.0, 100.0])])
    run = texel_samples(read_photographs(capture), np.array([0]))
    assert capture.channels == ("value",)
    np.testing.assert_allclose(run.values[0, 0], [312.5], rtol=FLOAT32)
    np.testing.assert_allclose(run.wi[0, 0], [0.6, 0.0, 0.8], atol=1e-15)
    np.testing.assert_allclose(run.wo[0, 0], [0.0, 0.0, 1.0], atol=1e-15)
    assert run.kept.tolist() == [[True]]


def test_saturated_missing_and_negative_values(tmp_path):
    """A pixel at the saturation level is dropped, as is a NaN; a negative one (noise below the black level) is 0."""
    above = [0.0, 0.0, 100.0]
    images = [([0.5, 0.1, 0.1], [0, 0, 50.0], [1, 1, 1], above), ([0.1, 0.99, 0.1], [0, 10, 50.0], [1, 1, 1], above)]
    images += [
        ([np.nan, 0.1, 0.1], [10, 0, 50.0], [1, 1, 1], above),
        ([-0.01, 0.1, 0.1], [0, -10, 50.0], [1, 1, 1], above),
    ]
    capture = _capture(tmp_path, images, saturation=0.99)
    run = texel_samples(read_photographs(capture), np.array([0]))
    assert run.kept.tolist() == [[True, False, False, True]]
    assert run.values[0, 3, 0] == 0.0 and np.all(run.values[0, 3, 1:] > 0)
    samples = run.samples(0, capture.channels, "texel")
    assert samples.n_samples == 2 and np.all(np.isfinite(samples.values))


def test_a_normal_map_turns_the_directions_into_the_texels_frame(tmp_path):
    """A texel tilted by 30° about y (normal (sin 30°, 0, cos 30°)) lit along its normal has wi = +z in its frame
    (f then divides by cos θi = 1); the plane's x, made perpendicular to the normal, is its tangent."""
    tilt = np.radians(30.0)
    normal = np.array([np.sin(tilt), 0.0, np.cos(tilt)])
    np.save(tmp_path / "normals.npy", normal.reshape(1, 1, 3))
    capture = _capture(tmp_path, [([0.3], (100 * normal).tolist(), [1.0], [0, 0, 100.0])], normal_map="normals.npy")
    run = texel_samples(read_photographs(capture), np.array([0]))
    np.testing.assert_allclose(run.wi[0, 0], [0.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(run.wo[0, 0], [-np.sin(tilt), 0.0, np.cos(tilt)], atol=1e-12)
    np.testing.assert_allclose(run.values[0, 0], [0.3 * 100.0**2], rtol=FLOAT32)


def test_a_mask_leaves_texels_out(tmp_path):
    capture = _capture(tmp_path, [([0.3], [0, 0, 50.0], [1.0], [0, 0, 100.0])])
    np.save(tmp_path / "mask.npy", np.zeros((1, 1)))
    document = json.loads((tmp_path / "capture.json").read_text()) | {"mask": "mask.npy"}
    (tmp_path / "capture.json").write_text(json.dumps(document))
    run = texel_samples(read_photographs(read_capture(tmp_path)), np.array([0]))
    assert not run.kept.any() and capture.mask is None


def _looking_down(height_mm, pitch_mm, shape):
    """The 3 × 4 OpenCV projection of a camera at (0, 0, height) looking down -z whose pixel (u = c, v = r) is texel
    (r, c) of a grid of ``shape`` and pitch ``pitch_mm``: R = diag(1, −1, −1) (the image's v runs down its rows,
    towards −y), t = −R·C, f = height/pitch, principal point at the grid's middle."""
    rows, columns = shape
    intrinsic = np.array(
        [[height_mm / pitch_mm, 0, columns / 2 - 0.5], [0, height_mm / pitch_mm, rows / 2 - 0.5], [0, 0, 1]]
    )
    rotation = np.diag([1.0, -1.0, -1.0])
    translation = -rotation @ np.array([0.0, 0.0, height_mm])
    return intrinsic @ np.hstack([rotation, translation[:, None]])


def test_an_unrectified_photograph_is_rectified_by_its_cameras_matrix(tmp_path):
    """A camera looking straight down whose pixels fall on the texels' centres gives the photograph back as it is
    (to rounding); its position, derived from the matrix, is the camera's; outside the photograph is NaN."""
    rng = np.random.default_rng(0)
    image = rng.uniform(0.1, 1.0, (4, 6, 3))
    matrix = _looking_down(400.0, 2.0, (4, 6))
    centres = np.array([[-5.0, 3.0, 0.0], [5.0, -3.0, 0.0], [-4.0, 3.0, 0.0], [100.0, 0.0, 0.0]])
    values = rectified(image, matrix, centres)
    np.testing.assert_allclose(values[0], image[0, 0], rtol=1e-12)  # texel (0, 0) of the 4 × 6 grid at pitch 2
    np.testing.assert_allclose(values[1], image[3, 5], rtol=1e-12)
    np.testing.assert_allclose(values[2], (image[0, 0] + image[0, 1]) / 2, rtol=1e-12)  # half a pixel: bilinear
    assert np.all(np.isnan(values[3]))
    np.save(tmp_path / "raw.npy", image)
    document = {
        "brdffit_capture": 1,
        "plane": {"width_mm": 12.0, "height_mm": 8.0, "texels": [4, 6]},
        "images": [{"file": "raw.npy", "light": {"position_mm": [0, 0, 300], "intensity": 1},
                    "camera": {"matrix": matrix.tolist()}}],
    }  # fmt: skip
    (tmp_path / "capture.json").write_text(json.dumps(document))
    capture = read_capture(tmp_path)
    np.testing.assert_allclose(capture.shots[0].camera_mm, [0.0, 0.0, 400.0], atol=1e-9)
    np.testing.assert_allclose(read_photographs(capture).radiance[0].reshape(4, 6, 3), image, rtol=1e-6)  # float32


def test_photographs_read_at_some_texels_give_those_texels_samples(tmp_path):
    """A Dask worker reads the photographs at its own texels alone (``read_photographs(capture, texels)``; a .npy's
    rows that hold them alone): their samples are those of the photographs read whole, for a rectified photograph and
    a raw one, under a mask and a normal map, the texels in any order; read at no texel, every photograph is still
    checked."""
    rng = np.random.default_rng(1)
    shape = (4, 6)
    np.save(tmp_path / "flat.npy", rng.uniform(0.1, 1.0, (*shape, 3)))
    np.save(tmp_path / "raw.npy", rng.uniform(0.1, 1.0, (*shape, 3)))
    normals = np.dstack([rng.normal(0.0, 0.2, (*shape, 2)), np.ones(shape)])
    np.save(tmp_path / "normals.npy", normals)
    mask = np.ones(shape)
    mask[1, 2] = 0.0
    np.save(tmp_path / "mask.npy", mask)
    document = {
        "brdffit_capture": 1,
        "plane": {"width_mm": 12.0, "height_mm": 8.0, "texels": list(shape)},
        "mask": "mask.npy",
        "normal_map": "normals.npy",
        "images": [
            {"file": "flat.npy", "light": {"position_mm": [30, 10, 300], "intensity": 1},
             "camera": {"position_mm": [0, 0, 400]}},
            {"file": "raw.npy", "light": {"position_mm": [-50, 20, 250], "intensity": 1},
             "camera": {"matrix": _looking_down(400.0, 2.0, shape).tolist()}},
        ],
    }  # fmt: skip
    (tmp_path / "capture.json").write_text(json.dumps(document))
    capture = read_capture(tmp_path)
    texels = np.array([13, 0, 8, 23, 13])  # texel (1, 2), 8, masked; 13 twice
    whole, some = read_photographs(capture), read_photographs(capture, texels)
    assert some.radiance.shape == (2, 4, 3)
    with pytest.raises(ValueError, match=r"texels \[1, 24\] were not read"):
        some.positions(np.array([0, 1, 24]))
    ours, theirs = texel_samples(some, texels), texel_samples(whole, texels)
    for name in ("wi", "wo", "values"):
        np.testing.assert_allclose(getattr(ours, name), getattr(theirs, name), rtol=1e-12, atol=0)
    np.testing.assert_array_equal(ours.kept, theirs.kept)
    assert not ours.kept[2].any() and ours.kept[[0, 1, 3, 4]].all()
    later = np.array([23, 14, 13])  # rows 2 and 3 alone: the .npy's rows read from row 2
    ours, theirs = texel_samples(read_photographs(capture, later), later), texel_samples(whole, later)
    np.testing.assert_allclose(ours.values, theirs.values, rtol=1e-12, atol=0)
    rows, shape = read_rows(tmp_path / "flat.npy", rows=slice(2, 4))
    assert shape == (4, 6, 3) and np.array_equal(rows, np.load(tmp_path / "flat.npy")[2:4])
    whole_image = read_image(tmp_path / "flat.npy")
    for read in (rows, whole_image):  # arrays of their own, as a decoded image is: not views of the mapped file
        assert read.flags.owndata and read.flags.writeable and not isinstance(read, np.memmap)
    np.save(tmp_path / "flat.npy", np.ones((3, 6, 3)))
    with pytest.raises(BrdfInputError, match=r"flat\.npy: 3 × 6 pixels; the capture's plane has 4 × 6 texels"):
        read_photographs(capture, np.array([], dtype=int))


@pytest.mark.parametrize("suffix", [".png", ".tif"])
def test_sixteen_bit_images_are_read_with_the_captures_scale(tmp_path, suffix):
    """A 16-bit image's 65,535 stands for the capture's scale; an 8-bit one is refused."""
    from brdffit.errors import BrdfInputError
    from brdffit.svbrdf.images import read_image

    pixels = np.array([[[0, 65535, 32768]]], dtype=np.uint16)
    path = tmp_path / f"i{suffix}"
    if suffix == ".png":
        png = pytest.importorskip("png", reason="pypng (the svbrdf extra) is not installed")
        png.from_array(pixels.reshape(1, 3), "RGB;16").save(path)
    else:
        tifffile = pytest.importorskip("tifffile", reason="tifffile (the svbrdf extra) is not installed")
        tifffile.imwrite(path, pixels)
    np.testing.assert_allclose(read_image(path, scale=2.0), [[[0.0, 2.0, 2.0 * 32768 / 65535]]], rtol=1e-12)
    from PIL import Image

    Image.fromarray(np.zeros((2, 2, 3), dtype=np.uint8)).save(tmp_path / f"eight{suffix}")
    with pytest.raises(BrdfInputError, match="an image of 8 bits; a capture's PNG and TIFF images must be 16-bit"):
        read_image(tmp_path / f"eight{suffix}")
