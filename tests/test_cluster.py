"""fit_batch and a capture's maps over a Dask cluster (``brdffit/fitting/many/cluster.py``,
``brdffit/svbrdf/texel_fits.py``): a LocalCluster of two worker processes gives the local results, reads paths and
photographs on its workers, loses no result when a worker dies mid-run, and drops the tasks an interrupted run
leaves."""

import os
import signal
import threading
import time
import warnings

import jax
import numpy as np
import pytest

from brdffit import BrdfInputError, data_synth, fit_batch, save_samples

pytestmark = pytest.mark.slow  # each test starts a Dask cluster of processes: ~100 s in all

distributed = pytest.importorskip("distributed", reason="dask[distributed] (the cluster extra) is not installed")

#: Results of the same programs on the same machine agree to rounding; a program for another number of stacked
#: datasets may fuse differently, which moves a float64 optimum by far less than this.
SAME = 1e-12


@pytest.fixture(scope="module")
def client():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # distributed's own start-up notices
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
        with cluster, distributed.Client(cluster) as client:
            yield client


@pytest.fixture(scope="module")
def materials():
    """40 seeded Ward materials on one 500-sample geometry (the per-texel case), and two with more samples."""
    rng = np.random.default_rng(3)
    wi, wo = data_synth.uniform_random(500, seed=7)
    datasets = []
    for index in range(40):
        params = {
            "rho_d": rng.uniform(0.05, 0.5, 3).tolist(),
            "rho_s": rng.uniform(0.02, 0.3, 3).tolist(),
            "alpha": float(rng.uniform(0.05, 0.4)),
        }
        datasets.append(data_synth.synthesize("ward", params, wi, wo, noise=0.01, seed=index))
    return datasets


def flat(params) -> np.ndarray:
    return np.array(jax.tree.leaves(params), dtype=float)


def assert_same(ours, theirs):
    assert len(ours) == len(theirs)
    for one, other in zip(ours, theirs, strict=True):
        assert (one.model, one.channels, one.n_samples) == (other.model, other.channels, other.n_samples)
        np.testing.assert_allclose(flat(one.params), flat(other.params), rtol=SAME, atol=0)
        assert one.cost == pytest.approx(other.cost, rel=SAME)
        assert (one.converged, one.warnings) == (other.converged, other.warnings)


def test_the_cluster_gives_the_local_results_in_input_order(client, materials):
    local = fit_batch(materials, "ward", progress=False)
    spread = fit_batch(materials, "ward", progress=False, client=client)
    assert_same(spread, local)
    workers = client.run(lambda dask_worker: len(dask_worker.data) + dask_worker.state.executed_count)
    assert all(count > 0 for count in workers.values()), "both workers fitted"


def test_paths_are_read_on_the_workers_with_the_read_options(client, materials, tmp_path):
    paths = []
    for index, samples in enumerate(materials[:6]):
        paths.append(tmp_path / f"material-{index}.csv")
        save_samples(samples, paths[-1])
    options = {"quantity": "reflectance-factor"}
    local = fit_batch(paths, "ward", progress=False, read_options=options)
    spread = fit_batch([str(path) for path in paths], "ward", progress=False, client=client, read_options=options)
    assert_same(spread, local)
    assert all(result.quantity == "reflectance-factor" for result in spread)
    assert spread[0].params != fit_batch(paths[:1], "ward", progress=False)[0].params
    with pytest.raises(BrdfInputError, match=r"read_options has 'quantiy'; allowed: format, angles, quantity"):
        fit_batch(paths, "ward", client=client, read_options={"quantiy": "brdf"})
    with pytest.raises(BrdfInputError, match=r"missing\.csv"):
        fit_batch([tmp_path / "missing.csv"], "ward", client=client)


def test_a_worker_killed_mid_run_loses_no_result(client, materials):
    local = fit_batch(materials, "ward", progress=False)
    found = {}

    def spread():
        found["results"] = fit_batch(materials, "ward", progress=False, client=client)

    thread = threading.Thread(target=spread)
    thread.start()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # wait until a worker holds a task, then kill that worker
        busy = [worker for worker, keys in client.processing().items() if keys]
        if busy:
            break
        time.sleep(0.02)
    assert busy, "no task reached a worker"
    pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
    os.kill(pid, signal.SIGKILL)
    thread.join(timeout=300)
    assert not thread.is_alive()
    assert_same(found["results"], local)
    client.wait_for_workers(2, timeout=60)  # the nanny restarts the worker for the tests after this one


def test_the_command_line_spreads_a_library_over_local_workers(materials, tmp_path, capsys):
    """``brdffit fit lib/* -o fits/ --workers 2`` writes the results the local run writes; a file that cannot be
    read stops it with one line before any fit, and nothing is written."""
    from brdffit import load_result
    from brdffit.cli import main

    library = tmp_path / "lib"
    library.mkdir()
    paths = []
    for index, samples in enumerate(materials[:4]):
        paths.append(library / f"m{index}.csv")
        save_samples(samples, paths[-1])
    assert main(["fit", *map(str, paths), "-o", str(tmp_path / "here") + "/"]) == 0
    assert main(["fit", *map(str, paths), "-o", str(tmp_path / "spread") + "/", "--workers", "2"]) == 0
    assert "Traceback" not in capsys.readouterr().err
    for path in paths:
        here, spread = (load_result(tmp_path / folder / f"{path.stem}.ward.json") for folder in ("here", "spread"))
        assert_same([spread], [here])
    status = main(
        ["fit", str(paths[0]), str(library / "missing.csv"), "-o", str(tmp_path / "none") + "/", "--workers", "2"]
    )
    err = capsys.readouterr().err
    assert status == 2 and err.strip().splitlines() == [f"brdffit: error: {library / 'missing.csv'}: no such file"]
    assert not (tmp_path / "none").exists()
    assert main(["fit", str(paths[0]), "--workers", "0", "-o", str(tmp_path / "zero.json")]) == 2
    assert capsys.readouterr().err.strip() == "brdffit: error: --workers must be 1 or more, got 0"
    chain = ["--uncertainty", "mcmc", "--chain", str(tmp_path / "chain.npz"), "-o", str(tmp_path / "one.json")]
    assert main(["fit", str(paths[0]), "--workers", "1", *chain]) == 2
    assert capsys.readouterr().err.strip().startswith("brdffit: error: --chain keeps a chain in this process")
    assert not (tmp_path / "one.json").exists()
    status = main(["fit", str(paths[0]), "--scheduler", "tcp://127.0.0.1:9", "-o", str(tmp_path / "nowhere.json")])
    assert status == 2 and "--scheduler tcp://127.0.0.1:9: no Dask scheduler answers there" in capsys.readouterr().err


def assert_same_maps(there, here):
    for name in here.params:
        np.testing.assert_allclose(there.params[name], here.params[name], rtol=SAME, atol=0)
    np.testing.assert_allclose(there.fit["cost"], here.fit["cost"], rtol=SAME, atol=0)
    np.testing.assert_array_equal(there.fit["converged"], here.fit["converged"])
    assert (there.neighbour_starts, there.notes) == (here.neighbour_starts, here.notes)


@pytest.fixture
def read_here(monkeypatch):
    """The texels this process reads the photographs at: one array a call, None for every texel."""
    import brdffit.svbrdf.texel_fits as texel_fits

    calls = []

    def recorded(capture, texels=None):
        calls.append(texels)
        return read_photographs(capture, texels)

    read_photographs = texel_fits.read_photographs
    monkeypatch.setattr(texel_fits, "read_photographs", recorded)
    return calls


def test_a_captures_texels_fitted_on_the_cluster_are_the_local_ones(client, tmp_path, read_here, monkeypatch):
    """``brdffit.svbrdf.fit(…, client=)``: each tile's texels fitted by the workers, the maps the same as here; the
    workers read the photographs, this process checks them, keeping the texels its scale note looks at (every
    one of a capture of 36)."""
    import brdffit.svbrdf as svbrdf
    from brdffit.data_synth.capture import synth_capture

    synth_capture(tmp_path / "capture", "ward", shape=(6, 6), n_images=16, noise=0.01, seed=1)
    here = svbrdf.fit(tmp_path / "capture", "ward", progress=False, tile_texels=16)
    assert len(read_here) == 1 and read_here.pop() is None
    monkeypatch.chdir(tmp_path)  # a relative path: the workers, started elsewhere, open the photographs all the same
    there = svbrdf.fit("capture", "ward", progress=False, tile_texels=16, client=client)
    assert len(read_here) == 1 and len(read_here[0]) == 36
    assert_same_maps(there, here)


def test_a_large_captures_photographs_are_read_by_the_workers_alone(client, tmp_path, read_here, monkeypatch):
    """On a capture of 40 × 40 texels this process reads the photographs at the 267 texels its scale note looks at,
    the workers at the rest; the neighbour starts' refits (every fitted texel here, RESTART_ABOVE at 0) run on the
    workers too, each reading its own texels; the maps are this process's."""
    import brdffit.svbrdf as svbrdf
    import brdffit.svbrdf.neighbours as neighbours
    from brdffit.data_synth.capture import synth_capture

    synth_capture(tmp_path / "capture", "ward", shape=(40, 40), n_images=8, noise=0.01, seed=2)
    monkeypatch.setattr(neighbours, "RESTART_ABOVE", 0.0)
    monkeypatch.setattr(neighbours, "PASSES", 1)
    here = svbrdf.fit(tmp_path / "capture", "ward", progress=False, tile_texels=400)
    read_here.clear()
    there = svbrdf.fit(tmp_path / "capture", "ward", progress=False, tile_texels=400, client=client)
    assert [len(texels) for texels in read_here] == [267]
    assert here.neighbour_starts["retried"] == 1600
    assert_same_maps(there, here)


def test_a_cluster_fit_interrupted_resumes_from_its_kept_tiles(client, tmp_path, monkeypatch):
    """Ctrl-C after the first band's tile is kept: no maps, that tile kept; resumed on the cluster, the workers fit
    the other tiles alone, and the maps are those of a fit here that was never interrupted."""
    import brdffit.svbrdf as svbrdf
    from brdffit.data_synth.capture import synth_capture
    from brdffit.svbrdf.tiles import TileStore

    synth_capture(tmp_path / "capture", "ward", shape=(6, 6), n_images=16, noise=0.01, seed=1)
    keep, kept = TileStore.keep, []

    def interrupted(store, number, tile):
        if kept:
            raise KeyboardInterrupt
        kept.append(number)
        keep(store, number, tile)

    monkeypatch.setattr(TileStore, "keep", interrupted)
    options = dict(output=tmp_path / "maps", progress=False, tile_texels=12, textures=False, client=client)
    with pytest.raises(KeyboardInterrupt):
        svbrdf.fit(tmp_path / "capture", "ward", **options)
    assert not (tmp_path / "maps" / "params.npz").exists()
    deadline = time.monotonic() + 30  # the bands not done are cancelled: the scheduler lets them go
    while brdffit_tasks(client) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not brdffit_tasks(client)
    assert sorted(path.name for path in (tmp_path / "maps" / ".tiles").glob("0*.npz")) == [f"{kept[0]:06d}.npz"]
    fitted = []

    def recorded(store, number, tile):
        fitted.append(number)
        keep(store, number, tile)

    monkeypatch.setattr(TileStore, "keep", recorded)
    resumed = svbrdf.fit(tmp_path / "capture", "ward", resume=True, **options)
    assert sorted(fitted) == sorted({0, 1, 2} - {kept[0]}) and (tmp_path / "maps" / "params.npz").exists()
    assert_same_maps(resumed, svbrdf.fit(tmp_path / "capture", "ward", progress=False, tile_texels=12))


def brdffit_tasks(client) -> list[str]:
    """The keys of brdffit's tasks the cluster's scheduler still holds."""
    return client.run_on_scheduler(
        lambda dask_scheduler: [str(key) for key in dask_scheduler.tasks if str(key).startswith("brdffit-")]
    )


def test_a_bad_photograph_stops_a_cluster_fit_before_any_tile(client, tmp_path):
    """A photograph of the wrong size is found by this process, which checks every photograph before a worker
    starts: a one-line error, and nothing written."""
    import brdffit.svbrdf as svbrdf
    from brdffit.data_synth.capture import synth_capture

    synth_capture(tmp_path / "capture", "ward", shape=(6, 6), n_images=4, noise=0.01, seed=1)
    np.save(tmp_path / "capture" / sorted((tmp_path / "capture").glob("*.npy"))[-1].name, np.ones((5, 6, 3)))
    with pytest.raises(BrdfInputError, match=r"\.npy: 5 × 6 pixels; the capture's plane has 6 × 6 texels"):
        svbrdf.fit(tmp_path / "capture", "ward", progress=False, client=client, output=tmp_path / "maps")
    assert not (tmp_path / "maps").exists()
