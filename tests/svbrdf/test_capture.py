"""A capture's file read and checked: its plane, lights and cameras, and a one-line error for each thing wrong."""

import json
import shutil

import numpy as np
import pytest

from brdffit.errors import BrdfInputError
from brdffit.svbrdf import read_capture
from brdffit.svbrdf.capture import texel_centres
from brdffit.svbrdf.texels import read_photographs


def test_a_synthetic_capture_reads_back(noiseless_capture):
    folder, _ = noiseless_capture
    capture = read_capture(folder)
    assert capture.shape == (6, 8) and capture.channels == ("r", "g", "b") and len(capture.shots) == 12
    again = read_capture(folder / "capture.json")
    assert capture.file == again.file == folder / "capture.json" and again.shape == capture.shape
    assert all(shot.light_mm[2] > 0 and shot.camera_mm.tolist() == [0.0, 0.0, 400.0] for shot in capture.shots)


def test_texel_centres_follow_the_convention():
    """Texel (r, c) of H × W sits at x = (c + ½)·width/W − width/2, y = height/2 − (r + ½)·height/H: row 0 at the
    top (largest y), column 0 at the left (smallest x); values by hand for a 100 × 50 mm plane of 2 × 4 texels."""
    centres = texel_centres(100.0, 50.0, (2, 4)).reshape(2, 4, 3)
    np.testing.assert_allclose(centres[0, 0], [-37.5, 12.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(centres[1, 3], [37.5, -12.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(centres[0, 2], [12.5, 12.5, 0.0], atol=1e-12)


def _broken(folder, tmp_path, change):
    """A copy of the capture in ``folder`` whose capture.json ``change`` edited."""
    copy = tmp_path / "capture"
    shutil.copytree(folder, copy)
    document = json.loads((copy / "capture.json").read_text())
    change(document)
    (copy / "capture.json").write_text(json.dumps(document))
    return copy


def _set(path, value):
    def change(document):
        *parents, last = path
        target = document
        for key in parents:
            target = target[key]
        target[last] = value

    return change


BROKEN = [
    (_set(["images", 1, "light", "position_mm"], [0, 0, -5]), "images[1].light.position_mm: z = -5 mm: the light must"),
    (_set(["images", 1, "light", "intensity"], [1, 1]), "images[1].light.intensity: 2 values for 3 channels"),
    (_set(["images", 0, "file"], "nope.exr"), "images[0].file: "),
    (_set(["images", 2, "camera", "position_mm"], [0, 0, 0]), "images[2].camera: z = 0 mm: the camera must be above"),
    (_set(["plane", "texels"], [6]), "plane.texels: [6]: must be [rows, columns]"),
    (_set(["plane", "width_mm"], -1), "plane.width_mm: -1: must be a number > 0"),
    (_set(["plane", "texel"], 3), "plane.texel: unknown key; allowed: height_mm, texels, width_mm"),
    (_set(["brdffit_capture"], 2), "brdffit_capture: 2: this brdffit reads version 1"),
    (_set(["images"], []), "images: must be a list of at least one image"),
    (_set(["images", 0, "camera", "matrix"], [[1, 0, 0], [0, 1, 0]]), "images[0].camera.matrix: must be a 3 × 4"),
    (_set(["channels"], ["r", "g"]), "channels: 2 channels, but images[0].light.intensity has 3 values"),
    (_set(["saturation"], 0), "saturation: 0: must be a number > 0"),
]


@pytest.mark.parametrize(("change", "piece"), BROKEN, ids=[piece.split(":")[0] for _, piece in BROKEN])
def test_a_bad_capture_is_one_line_naming_the_file_and_the_key(noiseless_capture, tmp_path, change, piece):
    folder, _ = noiseless_capture
    broken = _broken(folder, tmp_path, change)
    with pytest.raises(BrdfInputError) as error:
        read_capture(broken)
    message = str(error.value)
    assert message.startswith(f"{broken / 'capture.json'}: ") and "\n" not in message, message
    assert piece in message, message
    if "nope.exr" in piece or "file" in piece:
        assert "no such file" in message


def test_not_a_capture_is_one_line(tmp_path):
    (tmp_path / "capture.json").write_text("{not json")
    with pytest.raises(BrdfInputError, match=r"capture\.json: not a capture file"):
        read_capture(tmp_path)
    (tmp_path / "capture.json").write_text('{"images": []}')
    with pytest.raises(BrdfInputError, match='no "brdffit_capture" key'):
        read_capture(tmp_path)
    with pytest.raises(BrdfInputError, match="no such file"):
        read_capture(tmp_path / "elsewhere")


def test_an_image_of_the_wrong_size_is_named_before_any_fit(noiseless_capture, tmp_path):
    folder, _ = noiseless_capture
    broken = _broken(folder, tmp_path, lambda document: None)
    np.save(broken / "small.npy", np.zeros((3, 4, 3)))
    document = json.loads((broken / "capture.json").read_text())
    document["images"][3]["file"] = "small.npy"
    (broken / "capture.json").write_text(json.dumps(document))
    with pytest.raises(BrdfInputError, match=r"small.npy: 3 × 4 pixels; the capture's plane has 6 × 8 texels"):
        read_photographs(read_capture(broken))
    np.save(broken / "small.npy", np.zeros((6, 8, 2)))
    with pytest.raises(BrdfInputError, match=r"small.npy: 2 channels; the capture has 3"):
        read_photographs(read_capture(broken))
