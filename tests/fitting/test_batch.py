"""fit_batch and `brdffit fit A B … -o OUTDIR/`: many datasets, one model."""

import os
import threading
import time

import numpy as np
import pytest
from reference_materials import flat_parameters

from brdffit import BrdfInputError, data_synth, fit, fit_batch, load_result, save_samples
from brdffit.cli import main
from brdffit.fitting.single.stacked import default_strategy

WARD = [{"rho_d": [0.1, 0.2], "rho_s": [0.02 * k, 0.03], "alpha": 0.05 + 0.04 * k} for k in range(1, 5)]


def datasets():
    """Four Ward materials; the last has a different size in the same bucket, the third another bucket."""
    sizes = [3000, 3000, 5000, 2900]
    result = []
    for k, (params, size) in enumerate(zip(WARD, sizes, strict=True)):
        wi, wo = data_synth.uniform_random(size, seed=k)
        result.append(data_synth.synthesize("ward", params, wi, wo, noise=0.01, seed=10 + k))
    return result


@pytest.mark.slow
def test_loop_equals_one_fit_at_a_time():
    samples = datasets()
    batch = fit_batch(samples, "ward", strategy="loop")
    assert batch == [fit(one, "ward") for one in samples]


def test_several_lobes_fit_one_at_a_time():
    """Lafortune with two lobes goes lobe by lobe, one dataset at a time, as fit does (this once failed: the batch
    handed fit its loss as an object, which it did not take)."""
    samples = datasets()[:2]
    batch = fit_batch(samples, "lafortune", lobes=2, strategy="loop")
    assert batch == [fit(one, "lafortune", lobes=2) for one in samples]


def same_results(these, those, rel=1e-12):
    """The same fits to ``rel``: a program stacking another number of datasets may order a sum differently."""
    for one, other in zip(these, those, strict=True):
        assert (other.n_samples, other.n_steps, other.converged) == (one.n_samples, one.n_steps, one.converged)
        assert other.cost == pytest.approx(one.cost, rel=rel)
        for name, value in flat_parameters(one.params).items():
            assert flat_parameters(other.params)[name] == pytest.approx(value, rel=rel), name


@pytest.mark.parametrize("model, options", [("ward", {}), ("lafortune", {"lobes": 2})])
def test_threads_change_no_result(model, options):
    """Batches fitted on 3 threads at once (Ward: a bucket of 3 datasets cut in 3 batches, and one of 1; Lafortune:
    one dataset a thread) give the results of one thread, in the order of the inputs."""
    samples = datasets() if model == "ward" else datasets()[:3]
    # Equal, as fit and fit_batch are (above): a dataset's programs treat it alone, however many are stacked.
    assert fit_batch(samples, model, threads=3, **options) == fit_batch(samples, model, threads=1, **options)


def test_a_failed_batch_stops_the_others(monkeypatch):
    """The first batch fails before its programs are compiled: its error comes out, and the batches waiting for
    those programs never start. (A failure after they are compiled races the batches started beside it: those may
    have begun, so the count would be timing's.)"""
    from brdffit.fitting.single.stacked import StackedFit

    calls = []

    def failing(*args, **kwargs):
        calls.append(1)
        raise RuntimeError("the solver broke")

    monkeypatch.setattr(StackedFit, "starts", failing)
    with pytest.raises(RuntimeError, match="the solver broke"):
        fit_batch(datasets()[:2] + datasets()[3:], "ward", threads=3)  # one bucket of 3, cut in 3 batches
    assert len(calls) == 1


def test_the_batches_running_at_once_hold_at_most_the_budget():
    """Units of 3, 2, 2, 5 (alone: beyond the budget) and 1 samples on 4 threads, a budget of 4."""
    from brdffit.fitting.many.threads import SampleBudget

    budget, lock = SampleBudget(4), threading.Lock()
    held, largest = [0], []

    def unit(samples):
        with budget.taken(samples):
            with lock:
                held[0] += samples
                largest.append((held[0], samples))
            time.sleep(0.05)
            with lock:
                held[0] -= samples

    threads = [threading.Thread(target=unit, args=(n,)) for n in (3, 2, 2, 5, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert all(total <= 4 or total == samples for total, samples in largest) and len(largest) == 5


def test_vmap_equals_loop():
    """The GPU strategy, run here on the CPU: the same optima (parameters to 1e-8, well inside the tolerances
    the solver stops at; vmapped arithmetic may be ordered differently)."""
    samples = datasets()
    looped = fit_batch(samples, "ward", strategy="loop")
    vmapped = fit_batch(samples, "ward", strategy="vmap")
    for one, other in zip(looped, vmapped, strict=True):
        assert other.converged and other.n_samples == one.n_samples
        assert other.cost == pytest.approx(one.cost, rel=1e-10)
        for name, value in flat_parameters(one.params).items():
            assert flat_parameters(other.params)[name] == pytest.approx(value, rel=1e-8), name


def test_vmap_runs_one_batch_at_a_time_whatever_the_threads(monkeypatch):
    """Two vmapped programs at once hung in XLA's CPU thread pool (512 texel fits on 2 threads of 2 cores): the vmap
    strategy fills the device alone, so ``threads`` does not apply to it."""
    from brdffit.fitting.many import batch

    seen = []
    real = batch.run_units
    monkeypatch.setattr(
        batch, "run_units", lambda units, fit, threads, bar: seen.append(threads) or real(units, fit, threads, bar)
    )
    fit_batch(datasets()[:2], "ward", strategy="vmap", threads=3)
    fit_batch(datasets()[:2], "ward", strategy="loop", threads=3)
    assert seen == [1, 3]


def test_vmap_with_float32_and_a_start():
    samples = datasets()[:2]
    results = fit_batch(samples, "ward", strategy="vmap", dtype="float32", start=WARD[0])
    assert all(r.converged and r.dtype == "float32" for r in results)


def test_one_start_per_dataset():
    samples = datasets()[:3]
    for strategy in ("loop", "vmap"):
        results = fit_batch(samples, "ward", strategy=strategy, start=WARD[:3])
        assert all(r.converged for r in results)
    mixed = fit_batch(samples, "ward", strategy="vmap", start=[WARD[0], None, WARD[2]])
    looped = fit_batch(samples, "ward", strategy="loop", start=[WARD[0], None, WARD[2]])
    assert [r.cost for r in mixed] == pytest.approx([r.cost for r in looped], rel=1e-10)
    with pytest.raises(BrdfInputError, match="2 starts for 3 datasets; give one per dataset or one for all"):
        fit_batch(samples, "ward", start=WARD[:2])


def test_strategy_and_arguments_are_checked():
    assert default_strategy() == "loop"  # the test machine is a CPU
    with pytest.raises(BrdfInputError, match=r"^strategy='gpu' is not allowed; choose one of: auto, loop, vmap"):
        fit_batch(datasets(), "ward", strategy="gpu")
    with pytest.raises(BrdfInputError, match="fit_batch needs at least one dataset"):
        fit_batch([], "ward")
    with pytest.raises(BrdfInputError, match=r"^threads=0 is not allowed; give a whole number ≥ 1"):
        fit_batch(datasets(), "ward", threads=0)


def test_progress_bar_on_request(capsys):
    fit_batch(datasets()[:2], "ward", progress=True)
    assert "/2 [" in capsys.readouterr().err  # tqdm redraws at most every 0.1 s: any frame of a 2-fit bar
    fit_batch(datasets()[:2], "ward")  # stderr is not a terminal under pytest: no bar
    assert capsys.readouterr().err == ""


def write_inputs(folder):
    paths = []
    for k, samples in enumerate(datasets()[:3]):
        path = folder / f"material{k}.csv"
        save_samples(samples, path)
        paths.append(path)
    return paths


def test_command_line_batch(tmp_path, capsys):
    paths = write_inputs(tmp_path)
    status = main(["fit", *map(str, paths), "--model", "ward", "-o", str(tmp_path / "out") + "/"])
    out, err = capsys.readouterr()
    assert status == 0, err
    assert sorted(os.listdir(tmp_path / "out")) == ["material0.ward.json", "material1.ward.json", "material2.ward.json"]
    lines = out.splitlines()
    assert lines[0].split()[:2] == ["samples", "steps"] and len(lines) == 4
    assert all("converged" in line for line in lines[1:])
    assert main(["fit", *map(str, paths), "--threads", "1", "-o", str(tmp_path / "one") + "/"]) == 0
    for name in os.listdir(tmp_path / "out"):
        same_results([load_result(tmp_path / "out" / name)], [load_result(tmp_path / "one" / name)])
    capsys.readouterr()
    assert main(["fit", *map(str, paths), "--threads", "0", "-o", str(tmp_path / "none") + "/"]) == 2
    assert capsys.readouterr().err.strip() == "brdffit: error: --threads must be 1 or more, got 0"
    assert not (tmp_path / "none").exists()


def test_command_line_batch_checks_every_input_before_writing(tmp_path, capsys):
    paths = write_inputs(tmp_path)
    paths[1].write_text("theta_i,phi_i,theta_o,phi_o,value\n10,0,95,0,0.1\n")
    before = sorted(os.listdir(tmp_path))
    status = main(["fit", *map(str, paths), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2 and f"{paths[1]}: row 1 (line 2), column theta_o" in err and err.count("\n") == 1
    assert sorted(os.listdir(tmp_path)) == before


@pytest.mark.parametrize(
    ("names", "output", "message"),
    [
        (["a/x.csv", "b/x.csv"], "out/", "a/x.csv and b/x.csv would both write out/x.ward.json"),
        (["a/x.csv", "a/y.csv"], "file.json", "-o file.json: is a file; with several samples files give a folder"),
    ],
)
def test_command_line_batch_output_errors(names, output, message, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in names:
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("theta_i,phi_i,theta_o,phi_o,value\n10,0,20,0,0.1\n")
    (tmp_path / "file.json").write_text("{}")
    status = main(["fit", *names, "-o", output])
    err = capsys.readouterr().err
    assert status == 2 and message in err
    assert not (tmp_path / "out").exists()


def test_batch_fits_are_deterministic_and_sizes_share_compiles():
    """Datasets of 3000 and 2900 samples share the 3072-row bucket: their solves reuse one compilation."""
    from brdffit.fitting.objective.problem import padded_size

    assert padded_size(3000) == padded_size(2900) == 3072
    results = fit_batch(datasets(), "ward")
    np.testing.assert_array_equal([r.n_samples for r in results], [3000, 3000, 5000, 2900])


@pytest.mark.parametrize("count", [1, 19, 20, 39, 40, 41, 100])
def test_a_bucket_is_cut_into_as_few_batches_as_memory_allows_and_even(count):
    """20 datasets of which 19 fit in a batch go as 10 + 10 (one stacked shape, one compiled program), not 19 + 1."""
    from brdffit.fitting.many.buckets import BATCH_SAMPLES, batches

    size = BATCH_SAMPLES // 19  # 19 datasets to a batch
    cut = batches(list(range(count)), size)
    lengths = [len(batch) for batch in cut]
    assert [index for batch in cut for index in batch] == list(range(count))
    assert len(cut) == -(-count // 19) and max(lengths) <= 19 and max(lengths) - min(lengths) <= 1
    assert max(lengths) * size <= BATCH_SAMPLES


@pytest.mark.parametrize("count", [1, 2, 3, 7, 20, 39, 100])
@pytest.mark.parametrize("parts", [2, 3, 8])
def test_a_bucket_is_cut_for_its_threads(count, parts):
    """For ``parts`` threads: a multiple of ``parts`` batches (or one a dataset), even, and the ``parts`` that run
    at once hold at most BATCH_SAMPLES samples together."""
    from brdffit.fitting.many.buckets import BATCH_SAMPLES, batches

    size = BATCH_SAMPLES // 19  # 19 datasets at a time in all
    cut = batches(list(range(count)), size, parts)
    lengths = sorted(len(batch) for batch in cut)
    assert [index for batch in cut for index in batch] == list(range(count))
    assert len(cut) % parts == 0 or len(cut) == count
    assert lengths[-1] - lengths[0] <= 1
    assert sum(lengths[-parts:]) * size <= BATCH_SAMPLES or lengths[-1] == 1
