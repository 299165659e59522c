"""``brdffit report MAPS/``: one self-contained page with the maps, where the fits end badly, and the maps relit
beside photographs the fit did not see."""

import json
import re
import shutil

import pytest

from brdffit.cli import main
from brdffit.data_synth.capture import synth_capture

pytest.importorskip("matplotlib", reason="matplotlib (the plots extra) is not installed")


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """A 12 × 12 Ward capture of 28 photographs, 4 of them held back (their own capture.json), and its maps."""
    folder = tmp_path_factory.mktemp("report")
    synth_capture(folder / "all", "ward", shape=(12, 12), n_images=28, noise=0.01, seed=4)
    document = json.loads((folder / "all" / "capture.json").read_text())
    for name, keep in (("capture", lambda i: i % 7 != 3), ("held", lambda i: i % 7 == 3)):
        (folder / name).mkdir()
        images = [image for index, image in enumerate(document["images"]) if keep(index)]
        for image in images:
            shutil.copy(folder / "all" / image["file"], folder / name / image["file"])
        (folder / name / "capture.json").write_text(json.dumps(document | {"images": images}))
    assert main(["-q", "svbrdf", "fit", str(folder / "capture"), "-o", str(folder / "maps")]) == 0
    return folder


def test_a_maps_report_shows_the_maps_and_the_held_back_photographs(fitted, capsys):
    page = fitted / "maps.html"
    status = main(["report", str(fitted / "maps"), "--held-back", str(fitted / "held"), "-o", str(page)])
    out, err = capsys.readouterr()
    assert status == 0 and out == f"wrote {page}\n", err
    text = page.read_text()
    assert text.count("data:image/png;base64,") == 3 + 1 + 4  # rho_d, rho_s, alpha; the fits; 4 held-back photographs
    assert "which the fit did not see" in text and "144 texels fitted, 144 converged" in text
    medians = [float(value) for value in re.findall(r"median \|·\| ([0-9.]+)%\)\.</figcaption>", text)]
    assert len(medians) == 4 and max(medians) < 3.0  # the relit maps within 3% of photographs they did not see


def test_a_maps_report_without_held_back_photographs_says_so(fitted, capsys):
    page = fitted / "own.html"
    assert main(["report", str(fitted / "maps"), "-o", str(page)]) == 0
    assert "they saw these, so this shows the fit, not a prediction" in page.read_text()
    status = main(["report", str(fitted / "maps"), "--held-back", str(fitted / "nowhere"), "-o", str(page)])
    assert status == 2 and "no such file" in capsys.readouterr().err
