"""``brdffit export`` and ``brdffit render`` end to end: every target written, what it says, bad input refused."""

import builtins
import json
import re

import numpy as np
import pytest
from gltf_validator import assert_valid, needs_validator
from paths import EXAMPLE

from brdffit import data_synth, fit, load_samples, save_samples
from brdffit.cli import main

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A Cook-Torrance fit Mitsuba expresses exactly, and a Ward fit it does not; one channel each."""
    folder = tmp_path_factory.mktemp("export")
    geometry = data_synth.hemisphere_grid(6, 9, 12)
    options = {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"}
    params = {"kd": [0.1], "ks": [0.6], "m": 0.2, "eta": 0.2, "k": 3.9}
    metal = data_synth.synthesize("cook-torrance", params, *geometry, **options)
    fit(metal, "cook-torrance", fixed={"ks": None}, **options).save(folder / "metal.json")  # ks 0.6: freed
    ward = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}
    ward_data = data_synth.synthesize("ward", ward, *geometry, noise=0.01, seed=2)
    save_samples(ward_data, folder / "ward.csv")
    fit(ward_data, "ward").save(folder / "ward.json")
    return folder


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.slow
def test_mitsuba_xml_and_dict(results, tmp_path, capsys, monkeypatch):
    mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    mi.set_variant("scalar_rgb")
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["export", results / "metal.json", "--to", "mitsuba"], capsys)
    assert status == 0, err
    assert out.splitlines()[:2] == [
        "wrote metal.xml: a Mitsuba 3 BSDF of " + str(results / "metal.json"),
        "  exact",
    ]
    assert "one channel" in out  # grey: the same value in r, g and b
    mi.load_file(str(tmp_path / "metal.xml"))
    status, out, _ = run(["export", results / "ward.json", "--to", "mitsuba", "--format", "dict"], capsys)
    assert status == 0 and "approximate:" in out and "rmse" in out
    namespace: dict = {}
    exec((tmp_path / "ward.mitsuba.py").read_text(), namespace)
    mi.load_dict(namespace["bsdf"])
    assert namespace["approximation"]["rmse"] > 0


def test_merl_of_one_channel_is_grey(results, tmp_path, capsys):
    output = tmp_path / "ward.binary"
    status, out, err = run(["export", results / "ward.json", "--to", "merl", "-o", output], capsys)
    assert status == 0, err
    assert "one channel: written as grey" in out
    merl = load_samples(output, subsample=2000, seed=1)
    assert merl.channels == ("r", "g", "b")
    # Grey: one value in r, g and b, up to the rounding of MERL's per-channel scale factors.
    np.testing.assert_allclose(merl.values[:, 1:], merl.values[:, :1].repeat(2, axis=1), rtol=1e-12)


def test_render_writes_a_png(results, tmp_path, capsys):
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    output = tmp_path / "sphere.png"
    status, out, err = run(["render", results / "metal.json", "-o", output, "--size", 32, "--spp", 4], capsys)
    assert status == 0, err
    assert output.read_bytes().startswith(PNG) and out.startswith(f"wrote {output}: Mitsuba 3 rendered a sphere")


@pytest.mark.slow
def test_render_beside_the_data(results, tmp_path, capsys):
    """``--samples``: the render beside the fit's sphere and the data's, at one exposure, and the export's error at
    the data's directions; an .exr holds one image, so it is refused with the data, before any work."""
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    import matplotlib.image

    output = tmp_path / "beside.png"
    argv = ["render", results / "ward.json", "--samples", results / "ward.csv", "--size", 32, "--spp", 4]
    status, out, err = run([*argv, "-o", output], capsys)
    assert status == 0, err
    assert re.search(r"at the data's [0-9,]+ directions \(ward.csv\), evaluated by Mitsuba", out), out
    image = matplotlib.image.imread(output)
    assert image.shape[1] > 2 * image.shape[0]  # three panels side by side
    status, out, err = run([*argv, "-o", tmp_path / "beside.exr"], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1 and "an .exr holds one image" in err, err
    assert not (tmp_path / "beside.exr").exists()


def test_renders_share_one_exposure_so_that_they_compare(tmp_path):
    """Two Lambertian fits, one half as bright as the other: at the default exposure the dimmer renders half as
    bright (in the EXR's radiance and the PNG's decoded values), where each image exposed on its own looks alike."""
    mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    from brdffit import FitResult
    from brdffit.export.mitsuba_render import render_sphere

    def lambertian(albedo):
        return FitResult("lambert", {}, ("r", "g", "b"), {"rho_d": [albedo] * 3}, "log", 0.0, 0.0, 1, 1, True)

    def png_linear(path):  # the PNG's values, sRGB-decoded (IEC 61966-2-1)
        value = matplotlib.image.imread(path)[..., :3].astype(float)
        return np.where(value <= 0.04045, value / 12.92, ((value + 0.055) / 1.055) ** 2.4)

    import matplotlib.image

    mean = {}
    for albedo in (0.8, 0.4):
        render_sphere(lambertian(albedo), tmp_path / f"{albedo}.exr", size=32, spp=4)
        mean[albedo, "exr"] = float(np.mean(np.asarray(mi.Bitmap(str(tmp_path / f"{albedo}.exr")))))
        for exposure in ("default", "auto"):
            chosen = {} if exposure == "default" else {"exposure": exposure}
            render_sphere(lambertian(albedo), tmp_path / f"{albedo}.png", size=32, spp=4, **chosen)
            mean[albedo, exposure] = float(np.mean(png_linear(tmp_path / f"{albedo}.png")))
    # The same sample positions (Mitsuba's seeded sampler): radiance exactly proportional to the albedo.
    assert mean[0.4, "exr"] / mean[0.8, "exr"] == pytest.approx(0.5, rel=1e-5)
    # The PNG: 8-bit rounding of each pixel (~0.2% of a mid-grey value), averaged: a percent is ample.
    assert mean[0.4, "default"] / mean[0.8, "default"] == pytest.approx(0.5, rel=0.01)
    assert mean[0.4, "auto"] / mean[0.8, "auto"] == pytest.approx(1.0, rel=0.01)  # what it hid


@pytest.mark.parametrize("value", ["0", "-1", "bright", "inf"])
def test_a_bad_exposure_is_one_line_and_writes_nothing(results, tmp_path, capsys, value):
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    status, out, err = run(["render", results / "metal.json", "-o", tmp_path / "s.png", "--exposure", value], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1, err
    assert f"--exposure '{value}' must be a number > 0, or 'auto'" in err
    assert list(tmp_path.iterdir()) == []


def test_render_without_mitsuba_names_the_extra(results, tmp_path, capsys, monkeypatch):
    real_import = builtins.__import__

    def no_mitsuba(name, *args, **kwargs):
        if name == "mitsuba":
            raise ImportError("No module named 'mitsuba'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_mitsuba)
    status, out, err = run(["render", results / "metal.json", "-o", tmp_path / "s.png"], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1
    assert "needs Mitsuba 3, which is not installed: pip install 'brdffit[render]'" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["export", "{m}", "--to", "blender"], "--to 'blender' is not allowed; choose one of: mitsuba, gltf, merl"),
        (["export", "{m}", "--to", "merl", "--format", "xml"], "--format xml does not apply to target merl"),
        (["export", "{m}", "--to", "mitsuba", "-o", "{m}"], "is the input"),
        (["export", "{t}/none.json", "--to", "mitsuba", "-o", "{t}/x.xml"], "none.json: no such file"),
        (["export", "{m}", "--to", "gltf", "--format", "glb", "-o", "{t}/s.gltf"], "--format glb writes .glb files"),
        # a name without the target's suffix: XML in a .json file would read as a broken result everywhere else
        (["export", "{m}", "--to", "mitsuba", "-o", "{t}/x.json"], "-o {t}/x.json: a mitsuba export is written to a"),
        (["export", "{m}", "--to", "merl", "-o", "{t}/x.csv"], "a merl export is written to a .binary (binary) file"),
        (["export", "{m}", "--to", "gltf", "-o", "{t}/x"], "a gltf export is written to a .gltf (gltf) or .glb (glb)"),
        (["export", "{m}", "--to", "merl", "--samples", "{t}/no.csv", "-o", "{t}/x.binary"], "no.csv: no such file"),
        (["export", "{m}", "--to", "merl", "--samples", "{m}", "-o", "{m}"], "is the input"),
        (["render", "{m}", "-o", "{t}/s.jpg"], "-o {t}/s.jpg: the image must end in .png or .exr"),
        (["render", "{m}", "--spp", "0", "-o", "{t}/s.png"], "--spp 0 is not allowed"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(results, tmp_path, capsys, argv, message):
    where = {"m": results / "metal.json", "t": tmp_path}
    before = (results / "metal.json").read_bytes()
    status, out, err = run([part.format(**where) for part in argv], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1, err
    assert message.format(**where) in err
    assert list(tmp_path.iterdir()) == [] and (results / "metal.json").read_bytes() == before
    json.loads(before)


@pytest.mark.slow
def test_gltf_says_how_far_it_lies(results, tmp_path, capsys):
    output = tmp_path / "metal.gltf"
    status, out, err = run(["export", results / "metal.json", "--to", "gltf", "-o", output], capsys)
    assert status == 0, err
    assert out.splitlines()[1].startswith("  approximate: the glTF BRDF fitted to it, rmse ")
    document = json.loads(output.read_text())
    assert document["asset"]["version"] == "2.0"
    material = document["materials"][0]
    assert len(material["pbrMetallicRoughness"]["baseColorFactor"]) == 4
    assert material["extras"]["brdffit"]["approximation"]["rmse"] > 0


@pytest.mark.slow
def test_an_exact_gltf_export_never_says_approximate(tmp_path, capsys):
    """A ``gltf`` fit's export writes its numbers unchanged: "exact", then how far the written material lies from
    the fit (rounding alone), never "approximate" (it once said both)."""
    result = tmp_path / "gltf.json"
    assert run(["fit", EXAMPLE, "--model", "gltf", "-o", result], capsys)[0] == 0
    status, out, err = run(["export", result, "--to", "gltf", "-o", tmp_path / "gltf.gltf"], capsys)
    lines = out.splitlines()
    assert status == 0 and "approximate" not in out, err
    assert lines[1] == "  exact: the fitted glTF material, its numbers unchanged", out
    assert lines[2].startswith("  the written material against the fit: rmse "), out


@needs_validator
def test_gltf_and_glb_open_in_a_viewer(results, tmp_path, capsys, monkeypatch):
    # A material alone shows nothing in a viewer: both files hold it on a preview sphere, and the Khronos validator
    # finds no error and no warning in either. The -o suffix picks the format; --format glb names it.
    monkeypatch.chdir(tmp_path)
    for argv in (["-o", "ward.gltf"], ["-o", "named.glb"], ["--format", "glb"]):
        status, _, err = run(["export", results / "ward.json", "--to", "gltf", *argv], capsys)
        assert status == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["named.glb", "ward.glb", "ward.gltf"]
    assert json.loads((tmp_path / "ward.gltf").read_text())["meshes"]
    for path in sorted(tmp_path.iterdir()):
        assert path.suffix == ".gltf" or path.read_bytes()[:4] == b"glTF"
        assert_valid(path)


def test_samples_say_how_far_the_export_lies_from_the_data(results, tmp_path, capsys):
    output = tmp_path / "ward.gltf"
    argv = ["export", results / "ward.json", "--to", "gltf", "--samples", results / "ward.csv", "-o", output]
    status, out, err = run(argv, capsys)
    assert status == 0, err
    said = out.splitlines()[2]
    assert said.startswith("  at the data's 648 directions (ward.csv), evaluated by the glTF specification's BRDF")
    assert "the fit itself: median error" in said
    stored = json.loads(output.read_text())["materials"][0]["extras"]["brdffit"]["at_data"]
    assert stored["n_pairs"] == 648 and f"median error {stored['median_error']:.2%}" in said


def test_a_comparison_file_exports_its_best_model(results, tmp_path, capsys):
    """``export`` and ``render`` take ``compare -o``'s file as well as a result: its best model, read with the quantity
    and angle limit the comparison fitted (kept in the file), so that ``--samples`` reads the data as it did."""
    data = results / "ward.csv"
    status, _, err = run(["compare", data, "--models", "lambert,ward", "-o", tmp_path / "cmp.json"], capsys)
    assert status == 0, err
    comparison = json.loads((tmp_path / "cmp.json").read_text())
    assert comparison["best"] == "ward" and comparison["quantity"] == "brdf"
    out_path = tmp_path / "best.gltf"
    status, out, err = run(["export", tmp_path / "cmp.json", "--to", "gltf", "-o", out_path, "--samples", data], capsys)
    assert status == 0, err
    stored = json.loads(out_path.read_text())["materials"][0]["extras"]["brdffit"]
    assert stored["source"]["model"] == "ward" and "at the data's" in out


def test_render_of_an_exported_file_is_the_render_of_its_result(results, tmp_path, capsys):
    """``render BSDF.xml`` renders the exported file as it is, nothing fitted again: the same image as ``render
    RESULT.json`` (Mitsuba's sampler has a fixed seed), and the export's lines (how far it lies) printed
    from the file's comments."""
    xml, from_file, from_result = tmp_path / "ward.xml", tmp_path / "file.exr", tmp_path / "result.exr"
    assert run(["export", results / "ward.json", "--to", "mitsuba", "-o", xml], capsys)[0] == 0
    status, out, err = run(["render", xml, "-o", from_file, "--size", 32, "--spp", 4], capsys)
    assert status == 0 and err == "" and out.startswith(f"wrote {from_file}: Mitsuba 3 rendered a sphere of {xml}")
    assert "approximate: cook-torrance" in out  # the export's own line, read back from the file
    assert run(["render", results / "ward.json", "-o", from_result, "--size", 32, "--spp", 4], capsys)[0] == 0
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    one, other = (np.asarray(mi.Bitmap(str(path))) for path in (from_file, from_result))
    # The same image to float32's rounding: Mitsuba reads the file's numbers and the dictionary's floats into float32
    # by different roads (measured: 19 of 3,072 values differ, by at most 1.4e-7 of themselves).
    assert one.shape == (32, 32, 3) and np.max(one) > 0
    np.testing.assert_allclose(one, other, rtol=1e-6, atol=0.0)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("<bsdf", "not a file Mitsuba 3 loads (["),
        ('<scene version="3.0.0"/>', "holds a Mitsuba Scene, not a BSDF"),
    ],
)
def test_render_refuses_a_file_that_is_no_bsdf(tmp_path, capsys, content, message):
    pytest.importorskip("mitsuba")
    bad, image = tmp_path / "bad.xml", tmp_path / "s.png"
    bad.write_text(content)
    status, _, err = run(["render", bad, "-o", image], capsys)
    assert status == 2 and message in err and len(err.strip().splitlines()) == 1 and not image.exists()


def test_render_of_a_bsdf_file_refuses_samples(results, tmp_path, capsys):
    """The render beside the data needs the fit, which a BSDF file does not hold: one line, nothing written."""
    pytest.importorskip("mitsuba")
    xml, image = tmp_path / "ward.xml", tmp_path / "s.png"
    run(["export", results / "ward.json", "--to", "mitsuba", "-o", xml], capsys)
    status, _, err = run(["render", xml, "--samples", results / "ward.csv", "-o", image], capsys)
    assert status == 2 and "--samples" in err and "give the result file" in err and not image.exists()
