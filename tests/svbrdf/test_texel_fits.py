"""One fit per texel: the maps recover known maps, their Laplace errors are calibrated, an interrupted fit leaves no
maps and resumes where it stopped, the files read back, and the maps relight as the truth does."""

import json
import warnings

import numpy as np
import pytest

import brdffit.svbrdf as svbrdf
from brdffit.errors import BrdfInputError, FitWarning
from brdffit.svbrdf import texel_fits
from brdffit.svbrdf.images import read_image
from brdffit.svbrdf.maps import flat_params, nested_params

#: The issue's acceptance: every parameter map within 3% (median relative error) of the truth at 1% noise.
RECOVERED = 0.03
#: 68% intervals that cover 60–76% of the true values (the issue's acceptance); over 256 texels a binomial's 1-σ is
#: 2.9%, so the band is ±2.7σ about 68%.
COVERAGE = (0.60, 0.76)


@pytest.fixture(scope="module")
def fitted(ward_capture, tmp_path_factory):
    folder, truth = ward_capture
    output = tmp_path_factory.mktemp("maps") / "maps"
    with warnings.catch_warnings():  # one texel's robust error is 2.1× its Gauss-Newton one: a caveat, said once
        warnings.simplefilter("ignore", FitWarning)
        maps = svbrdf.fit(folder, "ward", output=output, uncertainty="laplace", progress=False)
    return maps, truth, output


@pytest.mark.slow
def test_the_maps_recover_the_truth(fitted):
    maps, truth, _ = fitted
    assert maps.summary()["fitted"] == maps.summary()["converged"] == 256
    for name, true in truth.items():
        error = np.median(np.abs(maps.params[name] - true) / true)
        assert error < RECOVERED, (name, error)  # measured 0.18–0.63%


def test_the_laplace_maps_are_calibrated(fitted):
    """The relative loss's residuals share one scatter under multiplicative noise, so the Gauss-Newton errors hold:
    each parameter's 68% interval covers its true value in 60–76% of the texels (measured 68–70%)."""
    maps, truth, _ = fitted
    for name, true in truth.items():
        covered = np.mean(np.abs(maps.params[name] - true) <= maps.stderr[name])
        assert COVERAGE[0] <= covered <= COVERAGE[1], (name, covered)


def test_the_files_read_back(fitted):
    maps, _, output = fitted
    again = svbrdf.read_maps(output)
    assert (again.model, again.loss, again.channels, again.shape) == ("ward", "relative", ("r", "g", "b"), (16, 16))
    for name in maps.params:
        np.testing.assert_array_equal(again.params[name], maps.params[name])
        np.testing.assert_array_equal(again.stderr[name], maps.stderr[name])
    described = json.loads((output / "maps.json").read_text())
    assert described["fitted"] == 256 and described["uncertainty"] == "laplace"
    np.testing.assert_allclose(read_image(output / "textures" / "rho_d.exr"), maps.params["rho_d"], rtol=1e-7)
    assert read_image(output / "textures" / "alpha.exr").shape == (16, 16)
    assert (output / "textures" / "rho_d.png").stat().st_size > 0 and not (output / ".tiles").exists()
    assert again.texel_params(3, 4) == {name: np.asarray(a[3, 4]).tolist() for name, a in maps.params.items()}


def test_the_maps_relight_as_the_truth_does(fitted):
    """At a light the capture did not have, the fitted maps' image lies within 3% (median) of the true maps'."""
    maps, truth, _ = fitted
    light, camera = [60.0, -120.0, 260.0], [20.0, 10.0, 380.0]
    true_maps = svbrdf.Maps("ward", {}, "relative", maps.channels, truth, maps.fit, maps.width_mm, maps.height_mm)
    relit, expected = svbrdf.render(maps, light, camera), svbrdf.render(true_maps, light, camera)
    error = np.median(np.abs(relit - expected) / expected)
    assert error < 0.03, error  # measured 0.2%


def test_the_truth_relights_to_the_capture_s_own_photographs(noiseless_capture):
    """The true maps relit at a capture's own light and camera give its photograph (float32 files: 1e-6)."""
    folder, truth = noiseless_capture
    capture = svbrdf.read_capture(folder)
    maps = svbrdf.Maps("ward", {}, "log", capture.channels, truth, {"n_samples": np.ones((6, 8))}, 100.0, 100.0)
    for shot in capture.shots[::5]:
        image = svbrdf.render(maps, shot.light_mm, shot.camera_mm, shot.intensity)
        np.testing.assert_allclose(image, read_image(shot.file), rtol=1e-6)


def test_an_interrupted_fit_leaves_no_maps_and_resumes(ward_capture, tmp_path, monkeypatch):
    """Ctrl-C after the first of three tiles: no params.npz, the finished tile kept; resumed, only the other two are
    fitted, and the maps are those of a fit that was never interrupted."""
    folder, _ = ward_capture
    fit_tile, calls = texel_fits._fit_tile, []

    def interrupted(run, **options):
        calls.append(len(run.texels))
        if calls == [100, 100]:  # Ctrl-C in the second tile of the first run
            raise KeyboardInterrupt
        return fit_tile(run, **options)

    monkeypatch.setattr(texel_fits, "_fit_tile", interrupted)
    output = tmp_path / "maps"
    options = dict(output=output, progress=False, tile_texels=100, textures=False)
    with pytest.raises(KeyboardInterrupt):
        svbrdf.fit(folder, "ward", **options)
    assert not (output / "params.npz").exists() and sorted(p.name for p in (output / ".tiles").iterdir()) == [
        "000000.npz",
        "key.json",
    ]
    calls.clear()
    resumed = svbrdf.fit(folder, "ward", resume=True, **options)
    assert calls[:2] == [100, 56] and (output / "params.npz").exists()  # then the neighbour starts' refits
    whole = svbrdf.fit(folder, "ward", progress=False, tile_texels=100)
    for name in whole.params:
        np.testing.assert_allclose(resumed.params[name], whole.params[name], rtol=1e-12)
    with pytest.raises(BrdfInputError, match="give output"):
        svbrdf.fit(folder, "ward", resume=True)


def test_resuming_another_fit_is_refused(ward_capture, tmp_path, monkeypatch):
    folder, _ = ward_capture
    tiles = tmp_path / "maps" / ".tiles"
    tiles.mkdir(parents=True)
    (tiles / "key.json").write_text(json.dumps({"capture": "another"}))
    with pytest.raises(
        BrdfInputError, match="of another capture, other photographs or other options; fit afresh, without resume"
    ):
        svbrdf.fit(folder, "ward", output=tmp_path / "maps", resume=True, progress=False)


def test_masked_texels_and_texels_with_too_few_samples_are_not_fitted(noiseless_capture, tmp_path):
    folder, _ = noiseless_capture
    mask = np.ones((6, 8))
    mask[2, 3] = 0
    np.save(tmp_path / "mask.npy", mask)
    import shutil

    copy = tmp_path / "capture"
    shutil.copytree(folder, copy)
    shutil.copy(tmp_path / "mask.npy", copy / "mask.npy")
    document = json.loads((copy / "capture.json").read_text())
    (copy / "capture.json").write_text(json.dumps(document | {"mask": "mask.npy"}))
    maps = svbrdf.fit(copy, "lambert", progress=False)
    assert maps.fit["n_samples"][2, 3] == 0 and np.all(np.isnan(maps.params["rho_d"][2, 3]))
    assert not maps.fit["converged"][2, 3] and maps.summary()["fitted"] == 47


def test_lobes_are_flattened_and_nested_again():
    params = {"rho_d": [0.1], "lobes": [{"rho_s": [0.2], "cxy": -0.6, "n": 12.0}, {"rho_s": [0.1], "cxy": 0.5}]}
    flat = flat_params(params)
    assert sorted(flat) == ["lobe0_cxy", "lobe0_n", "lobe0_rho_s", "lobe1_cxy", "lobe1_rho_s", "rho_d"]
    assert nested_params(flat) == params


def test_a_cluster_task_reads_the_photographs_at_its_own_texels_alone(ward_capture, monkeypatch):
    """A worker's task (``_fit_groups``, ``tests/test_cluster.py`` runs it on workers) reads the photographs at the
    texels of its groups alone, once, and fits each group as a tile from its own starts."""
    folder, _ = ward_capture
    read, read_photographs = [], texel_fits.read_photographs

    def recorded(capture, texels=None):
        read.append(texels)
        return read_photographs(capture, texels)

    monkeypatch.setattr(texel_fits, "read_photographs", recorded)
    groups = [(np.arange(10, 14), None), (np.array([41, 40]), [{"a": 1}, {"a": 2}])]
    fitted = texel_fits._fit_groups(
        svbrdf.read_capture(folder), lambda run, starts: (run.texels.tolist(), starts), groups, True
    )
    assert [sorted(np.asarray(texels).tolist()) for texels in read] == [[10, 11, 12, 13, 40, 41]]
    assert fitted == [([10, 11, 12, 13], None), ([41, 40], [{"a": 1}, {"a": 2}])]
