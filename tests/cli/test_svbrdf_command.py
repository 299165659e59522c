"""``brdffit synth capture``, ``brdffit svbrdf fit`` and ``brdffit svbrdf render`` end to end: what each writes and
says, and bad input refused in one line before anything is written."""

import json
import subprocess
import sys

import numpy as np
import pytest

from brdffit.cli import main
from brdffit.svbrdf.images import read_image

PNG = b"\x89PNG\r\n\x1a\n"


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def one_line_error(status, err, piece):
    assert status == 2 and err.startswith("brdffit: error: ") and err.count("\n") == 1, err
    assert piece in err, err


@pytest.fixture(scope="module")
def capture(tmp_path_factory):
    """An 8 × 8-texel Ward capture of 16 OpenEXR photographs, made by the command line."""
    folder = tmp_path_factory.mktemp("cli-capture") / "capture"
    status = main(["synth", "capture", str(folder), "--texels", "8,8", "--images", "16", "--seed", "3"])
    assert status == 0
    return folder


def test_synth_capture_writes_a_capture(capture):
    document = json.loads((capture / "capture.json").read_text())
    assert document["plane"]["texels"] == [8, 8] and len(document["images"]) == 16
    assert read_image(capture / "img_000.exr").shape == (8, 8, 3)
    with np.load(capture / "truth.npz") as truth:
        assert sorted(truth.files) == ["alpha", "rho_d", "rho_s"]


def test_fit_then_render(capture, tmp_path, capsys):
    maps = tmp_path / "maps"
    status, out, err = run(["svbrdf", "fit", capture, "-o", maps], capsys)
    assert status == 0, err
    assert out.startswith(f"wrote {maps}/: ward maps of 8 × 8 texels from 16 images (64 fitted, 64 converged;")
    assert "rho_d[r]" in out and "alpha" in out
    assert sorted(path.name for path in maps.iterdir()) == ["maps.json", "params.npz", "textures"]
    for suffix in (".exr", ".png", ".npy"):
        image = tmp_path / f"relit{suffix}"
        status, out, err = run(
            ["svbrdf", "render", maps, "--light", "20,-60,250", "--camera", "0,0,400", "-o", image], capsys
        )
        assert status == 0 and out.startswith(f"wrote {image}: 8 × 8 image of {maps}"), err
    assert (tmp_path / "relit.png").read_bytes().startswith(PNG)
    np.testing.assert_allclose(read_image(tmp_path / "relit.exr"), np.load(tmp_path / "relit.npy"), rtol=1e-7)
    # -o -: the PNG on standard output, as every command that writes an image (refused before; found trying the tool
    # as a new user), byte for byte the file's
    argv = [sys.executable, "-m", "brdffit", "svbrdf", "render", maps, "--light", "20,-60,250", "--camera", "0,0,400"]
    done = subprocess.run([*map(str, argv), "-o", "-"], capture_output=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0 and done.stdout == (tmp_path / "relit.png").read_bytes(), done.stderr
    assert done.stderr.decode().startswith("wrote -: 8 × 8 image of")
    status, out, err = run(["-q", "svbrdf", "fit", capture, "--no-textures", "-o", tmp_path / "quiet"], capsys)
    assert status == 0 and out == "" and err == "" and not (tmp_path / "quiet" / "textures").exists()


def test_caveats_are_summed_up_in_one_warning(capture, tmp_path, capsys):
    """The log loss's residuals scale with the signal: Laplace's robust errors are reported for some texels, and the
    command says so once, naming a texel, instead of once per texel."""
    status, _, err = run(
        ["svbrdf", "fit", capture, "--loss", "log", "--uncertainty", "laplace", "-o", tmp_path / "m"], capsys
    )
    assert status == 0 and err.count("brdffit: warning: ") == 1 and "texels have caveats" in err, err
    with np.load(tmp_path / "m" / "params.npz") as maps:
        assert maps["n_caveats"].sum() > 0 and maps["alpha_stderr"].shape == (8, 8)


def test_bad_input_is_one_line_and_writes_nothing(capture, tmp_path, capsys):
    broken = tmp_path / "broken"
    broken.mkdir()
    document = json.loads((capture / "capture.json").read_text())
    document["images"][0]["light"]["position_mm"][2] = -1.0
    document["images"] = [
        image | {"file": str(capture / image["file"])} for image in document["images"]
    ]  # the photographs where they are
    (broken / "capture.json").write_text(json.dumps(document))
    maps = tmp_path / "maps"
    status, _, err = run(["svbrdf", "fit", broken, "-o", maps], capsys)
    one_line_error(status, err, "images[0].light.position_mm: z = -1 mm: the light must be above the sample's plane")
    assert not maps.exists()
    (tmp_path / "file").write_text("x")
    status, _, err = run(["svbrdf", "fit", capture, "-o", tmp_path / "file"], capsys)
    one_line_error(status, err, "is a file; give a folder to write the maps into")
    status, _, err = run(["svbrdf", "fit", capture, "--uncertainty", "mcmc", "-o", maps], capsys)
    one_line_error(status, err, "mcmc")
    assert not maps.exists()
    status, _, err = run(["svbrdf", "render", capture, "--light", "0,0,1", "--camera", "0,0,1", "-o", "x.exr"], capsys)
    one_line_error(status, err, "maps.json: no such file")
    for flag, value, piece in [
        ("--light", "0,0", "--light 0,0: give X,Y,Z"),
        ("--light", "0,0,-3", "--light: [0.0, 0.0, -3.0] must be finite and above the sample's plane"),
        ("--camera", "a,b,c", "give comma-separated numbers"),
    ]:
        argv = ["svbrdf", "render", tmp_path, "--light", "0,0,9", "--camera", "0,0,9", flag, value]
        status, _, err = run([*argv, "-o", tmp_path / "x.exr"], capsys)
        one_line_error(status, err, piece)
    status, _, err = run(["svbrdf", "render", tmp_path, "--light", "0,0,9", "--camera", "0,0,9", "-o", "x.jpg"], capsys)
    one_line_error(status, err, "-o x.jpg: write .exr, .png, .npy")
    status, _, err = run(["synth", "capture", tmp_path / "c", "--texels", "8"], capsys)
    one_line_error(status, err, "--texels 8: give ROWS,COLUMNS")


def test_render_never_replaces_a_maps_file_and_takes_maps_json(capture, tmp_path, capsys):
    maps = tmp_path / "maps"
    assert run(["-q", "svbrdf", "fit", capture, "-o", maps], capsys)[0] == 0
    texture = maps / "textures" / "alpha.exr"
    before = texture.read_bytes()
    status, _, err = run(["svbrdf", "render", maps, "--light", "0,0,300", "--camera", "0,0,400", "-o", texture], capsys)
    one_line_error(status, err, "is the input")
    assert texture.read_bytes() == before
    status, _, err = run(
        ["svbrdf", "render", maps / "maps.json", "--light", "0,0,300", "--camera", "0,0,400", "-o", tmp_path / "r.npy"],
        capsys,
    )
    assert status == 0, err
    argv = ["svbrdf", "render", maps, "--light", "0,0,300", "--camera", "0,0,400", "--exposure", "2"]
    status, _, err = run([*argv, "-o", tmp_path / "r.exr"], capsys)
    one_line_error(status, err, "--exposure exposes a .png; .exr holds the radiance itself")


def test_synth_capture_refuses_a_folder_that_is_not_empty(capture, capsys):
    status, _, err = run(["synth", "capture", capture, "--texels", "2,2", "--images", "2"], capsys)
    one_line_error(status, err, "is not empty; give a new or empty folder")
