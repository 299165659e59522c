"""Formats through load_samples and the command line: detection, convert, info, the real retro-reflective tape."""

import json
from pathlib import Path

import numpy as np
import pytest
from catalogue import CASES
from paths import EXAMPLE, TAPE

from brdffit import BrdfInputError, data_synth, load_samples, save_samples
from brdffit.cli import main
from brdffit.data.load import detect_format

WARD = CASES[1][2]  # pickled oak (Ngan et al. 2005)


def run(argv, capsys):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def small(tmp_path):
    samples = data_synth.synthesize("ward", WARD, *data_synth.uniform_random(300, seed=3), noise=0.01, seed=4)
    path = tmp_path / "small.csv"
    save_samples(samples, path)
    return samples, path


def test_detection_by_extension_and_content(tmp_path):
    alta = tmp_path / "a.txt"
    alta.write_text("#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.1 0 0.2 3 0.5\n")
    astm = tmp_path / "b.txt"
    astm.write_text("NUM_POINTS 1\nVARS theta_i,phi_i,theta_s,phi_s,R,G,B\n10,0,20,180,0.1,0.1,0.1\n")
    csv = tmp_path / "c.txt"
    csv.write_text("theta_i,phi_i,theta_o,phi_o,value\n10,0,20,180,0.1\n")
    assert [detect_format(p) for p in (alta, astm, csv)] == ["alta", "astm", "csv"]
    assert detect_format(Path("x.binary")) == "merl" and detect_format(Path("x.csv")) == "csv"
    with pytest.raises(BrdfInputError, match=r"^format='hdf' is not allowed; choose one of: csv, merl, alta, astm"):
        detect_format(csv, "hdf")


@pytest.mark.parametrize("suffix", [".csv", ".dat", ".astm"])
def test_convert_round_trips_samples(suffix, small, tmp_path, capsys):
    samples, path = small
    out = tmp_path / f"converted{suffix}"
    status, stdout, err = run(["convert", path, out], capsys)
    assert status == 0, err and f"wrote 300 samples × 3 channel(s) to {out}" in stdout
    back = load_samples(out)
    np.testing.assert_allclose(back.values, samples.values, rtol=1e-12)
    np.testing.assert_allclose(back.wi, samples.wi, atol=1e-12)
    np.testing.assert_allclose(back.wo, samples.wo, atol=1e-12)
    assert back.channels == samples.channels


@pytest.mark.slow
def test_convert_a_result_to_merl_and_fit_it_back(tmp_path, capsys):
    result = tmp_path / "ward.json"
    fit_block = {"loss": "log", "cost": 0.0, "rmse": 0.0, "n_samples": 1, "n_steps": 0, "converged": True}
    result.write_text(json.dumps({"model": "ward", "channels": ["r", "g", "b"], "params": WARD, "fit": fit_block}))
    status, out, err = run(["convert", result, tmp_path / "ward.binary"], capsys)
    assert status == 0, err
    assert "ward tabulated on MERL's 90 × 90 × 180 grid" in out
    status, _out, err = run(
        ["fit", tmp_path / "ward.binary", "--subsample", 20000, "--model", "ward", "-o", tmp_path / "fit.json"], capsys
    )
    assert status == 0, err
    fitted = json.loads((tmp_path / "fit.json").read_text())["params"]
    for name, value in WARD.items():
        np.testing.assert_allclose(fitted[name], value, rtol=0.03)


def test_convert_errors(small, tmp_path, capsys):
    _, path = small
    status, _, err = run(["convert", path, tmp_path / "out.xyz"], capsys)
    assert status == 2 and "unknown output format; give one of: .csv (csv)" in err
    status, _, err = run(["convert", path, tmp_path / "out.binary"], capsys)
    assert status == 2 and "a MERL file tabulates a whole BRDF; convert a fit result (.json)" in err
    status, _, err = run(["fit", path, "--subsample", 10], capsys)
    assert status == 2 and "--subsample applies to MERL files" in err
    status, _, err = run(["fit", path, "--format", "alta"], capsys)
    assert status == 2 and err.startswith("brdffit: error: ") and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["small.csv"]


def test_info(capsys):
    status, out, err = run(["info", EXAMPLE], capsys)
    assert status == 0, err
    assert "csv, 10368 samples × 3 channel(s): r, g, b" in out
    assert "8 distinct light directions" in out and "(θh, θd) cells" in out


def test_spectral_csv_through_the_command_line(tmp_path, capsys):
    """A flat grey spectrum of albedo 0.4 is Y = 0.4 whatever the illuminant, so Lambert in XYZ fits y = 0.4."""
    wavelengths = np.arange(400, 701, 10)
    wi, wo = data_synth.uniform_random(200, seed=5)
    values = np.full((200, wavelengths.size), 0.4 / np.pi)
    path = tmp_path / "grey.csv"
    save_samples(
        load_samples_from_arrays(wi, wo, values, [str(w) for w in wavelengths]),
        path,
    )
    status, _out, err = run(
        ["fit", path, "--model", "lambert", "--spectral-to", "xyz", "-o", tmp_path / "r.json"], capsys
    )
    assert status == 0, err
    content = json.loads((tmp_path / "r.json").read_text())
    assert content["channels"] == ["x", "y", "z"]
    assert content["params"]["rho_d"][1] == pytest.approx(0.4, rel=1e-3)
    kept = load_samples(path)
    assert kept.n_channels == 31


def load_samples_from_arrays(wi, wo, values, channels):
    from brdffit import Samples

    return Samples.from_arrays(wi, wo, values, channels=channels)


@pytest.mark.slow
def test_retro_reflective_tape(tmp_path, capsys):
    """The real ALTA measurement: two Lafortune lobes find the retro-reflective one (cxy > 0) and fit several
    times better than Lambert (issue 5 acceptance)."""
    status, _out, err = run(
        ["fit", TAPE, "--model", "lafortune", "--lobes", 2, "-o", tmp_path / "lafortune.json"], capsys
    )
    assert status == 0, err
    status, _, err = run(["fit", TAPE, "--model", "lambert", "-o", tmp_path / "lambert.json"], capsys)
    assert status == 0, err
    lafortune = json.loads((tmp_path / "lafortune.json").read_text())
    lambert = json.loads((tmp_path / "lambert.json").read_text())
    retro = [lobe for lobe in lafortune["params"]["lobes"] if lobe["cxy"] > 0]
    assert retro, lafortune["params"]
    assert lafortune["fit"]["rmse"] * 3 < lambert["fit"]["rmse"], (lafortune["fit"]["rmse"], lambert["fit"]["rmse"])


@pytest.mark.parametrize(
    "name, content, piece",
    [
        ("short.binary", np.array([90, 90, 180], "<i4").tobytes() + b"\x00" * 100, "needs 34,992,012"),
        ("dims.binary", np.array([90, 90, 90], "<i4").tobytes() + b"\x00" * 64, "dimensions (90, 90, 90)"),
        ("param.dat", b"#DIM 2 1\n#PARAM_IN POLAR\n0.1 0.2 0.3\n", "POLAR"),
        ("columns.dat", b"#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.1 0 0.2\n", "line 3"),
        ("nan.dat", b"#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.1 0 0.2 3 nan\n", "line 3"),
        ("count.astm", b"NUM_POINTS 2\nVARS theta_i,phi_i,theta_s,phi_s,R\n0.1,0,0.2,3,0.5\n", "NUM_POINTS"),
    ],
)
def test_malformed_files_exit_2_with_one_line(name, content, piece, tmp_path, capsys):
    path = tmp_path / name
    path.write_bytes(content)
    status, out, err = run(["fit", path, "-o", tmp_path / "r.json"], capsys)
    assert status == 2 and out == ""
    assert err.startswith(f"brdffit: error: {path}") and err.count("\n") == 1 and piece in err, err
    assert "Traceback" not in err and sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_byte_order_mark_and_convert_messages(small, tmp_path, capsys):
    samples, path = small
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())  # as Excel writes UTF-8
    assert load_samples(bom).n_samples == 300
    with_sigma = tmp_path / "sigma.csv"
    save_samples(
        samples.__class__.from_arrays(
            samples.wi, samples.wo, samples.values, samples.channels, sigma=0.01 * samples.values
        ),
        with_sigma,
    )
    status, _, err = run(["convert", with_sigma, tmp_path / "sigma.dat"], capsys)
    assert status == 0 and "hold no sigma or weight columns; they are not written" in err
    result = tmp_path / "r.json"
    result.write_text("{}")
    status, _, err = run(["convert", result, tmp_path / "out.csv"], capsys)
    assert status == 2 and "a result file converts only to a MERL file (.binary)" in err


def test_several_inputs_need_a_folder(small, tmp_path, capsys):
    _, path = small
    status, _, err = run(["fit", path, path, "-o", tmp_path / "x.json"], capsys)
    assert status == 2 and "looks like a file; with several samples files give a folder (OUTDIR/)" in err
    assert not (tmp_path / "x.json").exists()


def test_a_pandas_data_frame_with_the_csvs_columns_is_read_as_the_csv_is():
    """``load_samples(DataFrame)``: the columns of a samples CSV (angles and values here; sigma and weight alike), read
    to the same directions and values as the file with the same table; bad cells name the frame's row by its index
    label; ``fit`` takes the frame as it takes a path."""
    pandas = pytest.importorskip("pandas", reason="pandas is not installed (the test extra has it)")
    from brdffit import fit

    table = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    frame = pandas.DataFrame(table, columns=["theta_i", "phi_i", "theta_o", "phi_o", "r", "g", "b"])
    from_frame, from_file = load_samples(frame), load_samples(EXAMPLE)
    for name in ("wi", "wo", "values"):
        np.testing.assert_array_equal(getattr(from_frame, name), getattr(from_file, name))
    assert from_frame.channels == from_file.channels and from_frame.source == "DataFrame"
    assert fit(frame.iloc[::20], "lambert").params["rho_d"] == pytest.approx(
        fit(from_file.select(np.arange(0, len(table), 20)), "lambert").params["rho_d"], rel=1e-12
    )
    bad = frame.iloc[:5].copy()
    bad.index = ["a", "b", "c", "d", "e"]
    bad.loc["c", "theta_o"] = 95.0
    with pytest.raises(BrdfInputError, match=r"^DataFrame: row 'c'.*theta_o.*95"):
        load_samples(bad)
    with pytest.raises(BrdfInputError, match=r"^DataFrame: columns: .*value"):
        load_samples(frame[["theta_i", "phi_i", "theta_o", "phi_o"]])
    with pytest.raises(BrdfInputError, match=r"^subsample applies to MERL files; the DataFrame is csv$"):
        load_samples(frame, subsample=5)  # as for a CSV file: an option it cannot take is refused, not ignored
    words = frame.iloc[:3].astype(object)
    words.loc[1, "r"] = "bright"
    with pytest.raises(BrdfInputError, match=r"^DataFrame: row 1, column 'r': 'bright' is not a number$"):
        load_samples(words)
