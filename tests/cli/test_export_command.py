"""``brdffit export`` and ``brdffit render`` end to end: every target written, what it says, bad input refused."""

import builtins
import json

import numpy as np
import pytest

import data_synth
from brdffit import fit, load_samples
from brdffit.cli import main

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A Cook-Torrance fit Mitsuba expresses exactly, and a Ward fit it does not; one channel each."""
    folder = tmp_path_factory.mktemp("export")
    geometry = data_synth.hemisphere_grid(6, 9, 12)
    options = {"fresnel": "conductor", "distribution": "ggx", "shadowing": "smith"}
    params = {"kd": [0.1], "ks": [0.6], "m": 0.2, "eta": 0.2, "k": 3.9}
    fit(data_synth.synthesize("cook-torrance", params, *geometry, **options), "cook-torrance", **options).save(
        folder / "metal.json"
    )
    ward = {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}
    fit(data_synth.synthesize("ward", ward, *geometry), "ward").save(folder / "ward.json")
    return folder


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


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
        (["render", "{m}", "-o", "{t}/s.jpg"], "-o {t}/s.jpg: the image must end in .png"),
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
