"""``brdffit plot`` end to end: every kind written where asked, bad input refused before any figure."""

import json

import pytest

from brdffit import data_synth, fit, save_samples
from brdffit.cli import main

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plot")
    samples = data_synth.synthesize(
        "ward", {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}, *data_synth.hemisphere_grid(4, 9, 12), noise=0.01
    )
    save_samples(samples, folder / "ward.csv")
    for model in ("ward", "lambert"):
        fit(samples, model).save(folder / f"{model}.json")
    rgb = data_synth.synthesize("lambert", {"rho_d": [0.2, 0.3, 0.4]}, *data_synth.hemisphere_grid(4, 9, 12))
    save_samples(rgb, folder / "rgb.csv")
    return folder


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_every_kind_into_a_folder(files, tmp_path, capsys):
    out_folder = tmp_path / "figures"
    status, out, err = run(
        ["plot", files / "ward.json", files / "lambert.json", files / "ward.csv", "-o", f"{out_folder}/"], capsys
    )
    assert status == 0, err
    names = sorted(path.name for path in out_folder.iterdir())
    assert names == [
        "ward.polar.png",
        "ward.residuals.lambert.png",
        "ward.residuals.ward.png",
        "ward.slices.png",
        "ward.sphere.png",
    ]
    assert all((out_folder / name).read_bytes().startswith(PNG) for name in names)
    assert out.startswith("wrote ") and out.count(".png") == 5


def test_one_kind_to_a_file_and_a_comparison_as_input(files, tmp_path, capsys):
    comparison = tmp_path / "compare.json"
    assert (
        main(["compare", str(files / "ward.csv"), "--models", "lambert,ward", "--folds", "2", "-o", str(comparison)])
        == 0
    )
    capsys.readouterr()
    assert json.loads(comparison.read_text())["best"] == "ward"
    status, _, err = run(["plot", comparison, files / "ward.csv", "--kind", "slices", "-o", tmp_path / "s.svg"], capsys)
    assert status == 0, err
    assert (tmp_path / "s.svg").read_text().lstrip().startswith("<?xml")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["{w}", "{s}", "--kind", "slice"],
            "--kind 'slice' is not allowed; choose one of: slices, polar, residuals, sphere, all",
        ),
        (["{w}", "{s}", "-o", "{t}/one.png"], "-o {t}/one.png: 4 figures need a folder; give OUTDIR/"),
        (["{w}", "{s}", "--kind", "polar", "-o", "{t}/x.jpg"], "-o {t}/x.jpg: the file must end in .png, .pdf, .svg"),
        (["{w}", "{s}", "--kind", "polar", "-o", "{w}"], "is the input"),
        (["{s}"], "give one or more result files, then the samples file they were fitted to"),
        (
            ["{w}", "{r}", "--kind", "slices", "-o", "{t}/c.png"],
            "{w}: its fit (ward) has channels value but {r} has r, g, b",
        ),
        (
            ["{w}", "{s}", "--incidences", "a,b", "--kind", "slices", "-o", "{t}/i.png"],
            "--incidences a,b: give light zeniths",
        ),
        (["{w}", "{s}", "--kind", "sphere", "--lights", "sun", "-o", "{t}/l.png"], "--lights 'sun' is not allowed"),
        (["{w}", "{s}", "--kind", "slices", "--lights", "sun", "-o", "{t}/l.png"], "--lights 'sun' is not allowed"),
        (["{w}", "{s}", "--lights", "sun", "-o", "{t}/all/"], "--lights 'sun' is not allowed"),
        (["{w}", "{s}", "--incidences", "200", "--kind", "slices"], "--incidences 200: give light zeniths in degrees"),
        (["{w}", "{w}"], "ward.json is a result file, not samples; the samples file comes last"),
        (["{s}", "{w}"], "ward.json is a result file, not samples; the samples file comes last"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(files, tmp_path, capsys, argv, message):
    where = {"w": files / "ward.json", "s": files / "ward.csv", "r": files / "rgb.csv", "t": tmp_path}
    before = (files / "ward.json").read_bytes()
    status, out, err = run(["plot", *(part.format(**where) for part in argv)], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1, err
    assert message.format(**where) in err
    assert list(tmp_path.iterdir()) == [] and (files / "ward.json").read_bytes() == before


def test_the_samples_are_read_as_the_fit_read_them(tmp_path, capsys):
    """The tape's fit records that it read the values as cosine-weighted-out; plot reads them so again unless told
    otherwise, and says so when told otherwise."""
    from paths import TAPE

    result = tmp_path / "tape.json"
    assert main(["fit", str(TAPE), "--model", "lambert", "--quantity", "cosine-weighted-out", "-o", str(result)]) == 0
    assert json.loads(result.read_text())["fit"]["quantity"] == "cosine-weighted-out"
    capsys.readouterr()
    status, _, err = run(["plot", result, TAPE, "--kind", "residuals", "-o", tmp_path / "r.png"], capsys)
    assert status == 0 and "warning" not in err
    status, _, err = run(
        ["plot", result, TAPE, "--kind", "residuals", "--quantity", "brdf", "-o", tmp_path / "b.png"], capsys
    )
    assert status == 0
    assert (
        f"brdffit: warning: {result} was fitted to samples read as cosine-weighted-out; {TAPE} is read as brdf" in err
    )


def test_the_samples_are_read_with_the_options_the_fit_read_them_with(files, tmp_path, capsys, monkeypatch):
    """A fit of a CSV whose angles are radians records ``fit.reading = {"angles": "radians"}``; plot reads the file
    so again without being told (read in degrees, every direction would lie within 1.6° of the normal, and the
    figures would compare the fit with other data), and says so when told otherwise."""
    from conftest import save_in_radians

    from brdffit import load_samples

    radians = save_in_radians(load_samples(files / "ward.csv"), tmp_path / "radians.csv")
    result = tmp_path / "radians.json"
    assert main(["fit", str(radians), "--model", "ward", "--angles", "radians", "-q", "-o", str(result)]) == 0
    assert json.loads(result.read_text())["fit"]["reading"] == {"angles": "radians"}
    capsys.readouterr()
    import brdffit.cli.plot

    read = []
    monkeypatch.setattr(brdffit.cli.plot, "load", lambda *a: read.append(brdffit.cli.arguments.load(*a)) or read[-1])
    status, _, err = run(["plot", result, radians, "--kind", "residuals", "-o", tmp_path / "r.png"], capsys)
    assert status == 0 and err == "", err
    assert read[0].wi.tolist() == load_samples(radians, angles="radians").wi.tolist()
    # told the default: read so, and said
    read.clear()
    status, _, err = run(
        ["plot", result, radians, "--kind", "residuals", "--angles", "degrees", "-o", tmp_path / "g.png"], capsys
    )
    assert status == 0
    assert f"{result} was fitted to samples read with --angles radians; {radians} is read with --angles degrees" in err
    assert read[0].wi.tolist() != load_samples(radians, angles="radians").wi.tolist()
    # the other way round: a fit of degrees, the file read in radians as told
    status, _, err = run(
        ["plot", files / "ward.json", radians, "--kind", "residuals", "--angles", "radians", "-o", tmp_path / "d.png"],
        capsys,
    )
    assert status == 0
    assert f"{files / 'ward.json'} was fitted to samples read with --angles degrees; {radians} is read with" in err


def test_a_file_the_fits_reading_cannot_read_says_the_reading_came_from_the_fit(files, tmp_path, capsys):
    from paths import TAPE

    result = tmp_path / "csv.json"
    assert main(["fit", str(files / "ward.csv"), "--model", "lambert", "--format", "csv", "-q", "-o", str(result)]) == 0
    capsys.readouterr()
    status, out, err = run(["plot", result, TAPE, "-o", f"{tmp_path}/figures/"], capsys)
    assert (status, out, err.count("\n")) == (2, "", 1), err
    assert f"{TAPE}: read as the fits read their samples (their fit.reading: format=csv): " in err
    assert not (tmp_path / "figures").exists()


def test_an_existing_file_is_no_folder(files, tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("")
    status, _, err = run(["plot", files / "ward.json", files / "ward.csv", "-o", f"{afile}/"], capsys)
    assert status == 2 and f"-o {afile}/: {afile} is a file; give a folder (OUTDIR/)" in err


def test_a_result_whose_options_hold_a_path_writes_nothing_anywhere(files, tmp_path, capsys):
    """Issue 29: a figure's name came from the result's model options, so ``fresnel = "a/../../x"`` made ``plot``
    create folders outside ``-o``'s before it refused the model. The options are checked as the file is read, before
    any name or folder is made."""
    content = json.loads((files / "ward.json").read_text())
    content.update(model="cook-torrance", model_options={"fresnel": "a/../../../escaped"})
    hostile = tmp_path / "inputs" / "hostile.json"
    hostile.parent.mkdir()
    hostile.write_text(json.dumps(content))
    status, out, err = run(
        ["plot", hostile, files / "lambert.json", files / "ward.csv", "--kind", "residuals", "-o", f"{tmp_path}/o/"],
        capsys,
    )
    assert status == 2 and out == "" and err.count("\n") == 1, err
    assert f"{hostile}: " in err and "is not known" in err
    assert sorted(path.name for path in tmp_path.rglob("*")) == ["hostile.json", "inputs"]


@pytest.mark.parametrize(
    ("label", "part"),
    [
        ("ward", "ward"),
        ("cook-torrance:fresnel=conductor", "cook-torrance-fresnel=conductor"),
        ("lafortune:lobes=2", "lafortune-lobes=2"),
        ("x:a=/../../b", "x-a=-..-..-b"),
        ("..", "-."),
        ("x:a=b\\c d\n", "x-a=b-c-d-"),
    ],
)
def test_a_fits_label_is_one_file_name_component(label, part):
    """Whatever a result file says, the part of a figure's name it gives is one component: no separator, never ``..``
    or hidden."""
    from brdffit.cli.plot import file_name_part

    assert file_name_part(label) == part
