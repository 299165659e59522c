"""brdffit's benchmarks: measured, printed, compared with scipy.optimize.least_squares in one run.

    make bench                    # or: .venv/bin/python benchmarks/run.py [--quick] [--repeats 3]

Sections (issue 3):

(a) MERL-size fits (1,458,000 direction pairs × RGB, 1% noise), Cook-Torrance and
    Ward: brdffit against least_squares ``trf`` and ``lm`` with finite
    differences and ``lm`` with the exact Jacobian, on the same data, start
    (brdffit's data-driven one) and loss (log), with final costs. brdffit is
    timed with compilation: from an empty persistent cache (a first run) and
    with a filled one (every later run), and on its default path (its own
    start search included).
(b) 100 Cook-Torrance materials × 100,000 samples: fit_batch against a loop of
    least_squares ``lm`` (exact Jacobian, compiled once) from the same starts,
    and fit_batch on its default path.
(c) ``brdffit fit`` of the shipped 10k-sample example, process start to result written.
(d) Peak resident memory of the MERL-size Cook-Torrance fit (the process that loads the samples and fits).
(e) Time per Levenberg-Marquardt step against one fused normal-equation pass (the lower bound of a step), and
    the pass's own lower bound: the larger of the bytes of its arrays at the memory's streaming rate and XLA's
    count of its flops at the rate of a float64 matrix product, both rates measured in the run.
(f) MCMC (issue 4): emcee, 32 walkers × 2000 steps on the 10k-sample example, compile included.
(g) Reading a full MERL file (issue 5): 1,458,000 bins to direction pairs.
(h) ``brdffit compare`` of 4 models × 5 folds on the 10k-sample example (issue 12) against the four plain
    ``brdffit fit`` runs of the same models, each a fresh process without a compilation cache, in turns.
(i) A 256² lit sphere (``brdffit.plots.sphere``'s renderer) of Ward, Cook-Torrance and 2-lobe Lafortune, in a
    fresh process: the first render (compilation included) and later ones, under 1 and 4 lights.
(j) Many fits (issue 14): 20 Ward materials × 100,000 samples (a material library) and 1,000 × 500 (the
    per-texel case): fit_batch from given starts, on its default path, and on its default path over a Dask
    LocalCluster of 1 and 2 workers (cluster start-up outside the clock, each worker compiling), against a
    loop of least_squares ``lm`` (exact Jacobian, compiled once) from the same starts; compile included.
(n) ``brdffit compare`` with its default candidates (19 specs: the renderers' own models included) on the
    10k-sample example (issue 28's goal: ≤ 30 s), process start to output written: a first run (an empty
    compilation cache) and later ones (the cache filled by the first), in turns.
(k) Start-up: commands that compute nothing (``--help``, ``--version``, ``models``, ``info``, ``convert``, an
    exact ``export``) and a ``fit`` of the example with a filled compilation cache, process start to exit.

``--sections`` runs some of them; the others keep their results from the last
run in ``latest.json`` (each section records its date).

Every timing is a median over ``--repeats`` runs, each in a fresh process;
the machine is shared, so compare ratios from one run. In (a) and (b) the
solvers take turns, one run each per round, so that drift in the machine's
speed falls on all of them alike. Writes
``benchmarks/results/latest.json`` and ``latest.md`` and prints the table.
"""

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from worker import BATCH_SOLVERS  # noqa: E402

from brdffit import data_synth, get_model  # noqa: E402
from brdffit.fitting.objective.losses import get_loss  # noqa: E402

WORKER = Path(__file__).with_name("worker.py")
RESULTS = Path(__file__).with_name("results")
MATERIALS = {
    # Ngan et al. 2005's fits of MERL special-walnut-224 (Cook-Torrance, ks = 4·albedo/π) and pickled-oak-260 (Ward).
    "cook-torrance": {"kd": [0.0187, 0.0145, 0.00961], "ks": [0.3209, 0.2725, 0.1821], "m": 0.258, "f0": 0.0688},
    "ward": {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146},
}
SCIPY_SOLVERS = ("scipy-trf", "scipy-lm", "scipy-lm-exact")
#: The results' sections and the letters the table calls them by.
SECTION_LETTERS = {
    "cook-torrance": "a, d, e",
    "ward": "a, d, e",
    "batch": "b",
    "cli": "c",
    "mcmc": "f",
    "merl_load": "g",
    "compare": "h",
    "render": "i",
    "many_large": "j",
    "many_small": "j",
    "startup": "k",
    "default_compare": "n",
    "hold": "m",
}


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def worker(*arguments: str, cache: str = "") -> dict:
    """One measurement in a fresh process; ``cache`` is its BRDFFIT_CACHE_DIR ("" = no persistent cache)."""
    environment = {**os.environ, "BRDFFIT_CACHE_DIR": cache}
    done = subprocess.run(
        [sys.executable, str(WORKER), *arguments], env=environment, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise RuntimeError(f"worker {' '.join(arguments)} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def summarised(runs: list[dict]) -> dict:
    """The last run's fields, with the median time (and peak memory) of all of them."""
    result = {key: runs[-1][key] for key in runs[-1]}
    result["seconds"] = statistics.median(run["seconds"] for run in runs)
    result["all_seconds"] = [run["seconds"] for run in runs]
    if "peak_rss_mb" in runs[-1]:
        result["peak_rss_mb"] = statistics.median(run["peak_rss_mb"] for run in runs)
    return result


def repeated(repeats: int, *arguments: str, cache: str = "") -> dict:
    return summarised([worker(*arguments, cache=cache) for _ in range(repeats)])


def interleaved(repeats: int, variants: dict[str, tuple[tuple[str, ...], str]], label: str) -> dict:
    """Each variant (its worker arguments and cache folder) once per round, ``repeats`` rounds.

    The machine is shared and its speed drifts over minutes; running the
    variants in turn rather than one after the other puts every variant's
    runs in the same stretches of time, so that the ratios compare like with like.
    """
    runs: dict[str, list[dict]] = {name: [] for name in variants}
    for round_number in range(1, repeats + 1):
        for name, (arguments, cache) in variants.items():
            log(f"{label}: {name}, round {round_number}/{repeats}")
            runs[name].append(worker(*arguments, cache=cache))
    return {name: summarised(done) for name, done in runs.items()}


def merl_data(model_name: str, size: int, folder: Path) -> tuple[Path, Path]:
    """(a)'s data and start for one model, written into ``folder``: ``size`` uniformly random direction pairs of
    :data:`MATERIALS`' material with 1% noise (``.npz``), and brdffit's data-driven start of the log loss (JSON)."""
    model, loss = get_model(model_name), get_loss("log")
    wi, wo = data_synth.uniform_random(size, seed=1)
    samples = data_synth.synthesize(model_name, MATERIALS[model_name], wi, wo, noise=0.01, seed=2)
    data = folder / f"{model_name}.npz"
    np.savez(data, wi=samples.wi, wo=samples.wo, values=samples.values)
    from brdffit.fitting.objective.problem import build_problem
    from brdffit.fitting.single.fit import search_problem
    from brdffit.fitting.starts.grid import starting_points

    search = search_problem(samples, build_problem(samples), "float64", seed=0)
    theta = starting_points(model, loss, search, 1)[0]
    start = folder / f"{model_name}-start.json"
    start.write_text(json.dumps(model.dictionary.from_params(model.unconstrained.to_params(theta, 3))))
    return data, start


def merl_section(model_name: str, size: int, repeats: int, folder: Path) -> dict:
    """(a), (d) and (e) for one model."""
    data, start = merl_data(model_name, size, folder)
    common = ("merl", "--model", model_name, "--data", str(data), "--start", str(start))

    cache = str(folder / f"cache-{model_name}")
    worker(*common, "--solver", "brdffit", cache=cache)  # fills the persistent cache
    variants = {
        "brdffit_cold": ((*common, "--solver", "brdffit"), ""),
        "brdffit_cached": ((*common, "--solver", "brdffit"), cache),
        "brdffit_default": ((*common, "--solver", "brdffit-default"), ""),
    } | {solver: ((*common, "--solver", solver), "") for solver in SCIPY_SOLVERS}
    section: dict = {"n_samples": size} | interleaved(repeats, variants, f"(a) {model_name}")
    log(f"(e) {model_name}: time per step")
    section["per_step"] = worker("steps", "--model", model_name, "--data", str(data), "--start", str(start))
    return section


def batch_section(materials: int, size: int, repeats: int) -> dict:
    """(b): 100 Cook-Torrance materials, fit_batch from given starts and on its default path against the scipy loop."""
    return batch_variants(
        "cook-torrance", materials, size, ("brdffit", "brdffit-default", "scipy-lm-exact"), repeats, "b"
    )


def batch_variants(model: str, materials: int, size: int, solvers: tuple[str, ...], repeats: int, letter: str) -> dict:
    """The worker's ``batch`` measurement of each of ``solvers`` on ``materials`` × ``size`` of ``model``, in turns."""
    arguments = ("batch", "--model", model, "--materials", str(materials), "--size", str(size))
    variants = {solver: ((*arguments, "--solver", solver), "") for solver in solvers}
    label = f"({letter}) {materials} × {size}"
    return {"materials": materials, "n_samples": size} | interleaved(repeats, variants, label)


#: (j) many fits (issue 14): (materials, samples each) of Ward, the material library and the per-texel case.
MANY = {"many_large": (20, 100_000), "many_small": (1000, 500)}
MANY_SOLVERS = (*BATCH_SOLVERS, "scipy-lm-exact")


def many_section(materials: int, size: int, repeats: int) -> dict:
    """(j): Ward fit_batch (given starts, default path, and the default path on a Dask LocalCluster of 1 and 2
    workers) against a loop of scipy least_squares lm from the same starts, compile included, in turns."""
    return batch_variants("ward", materials, size, MANY_SOLVERS, repeats, "j")


#: (k) commands that compute nothing, and a warm fit: process start to exit.
STARTUP = {
    "--help": ["--help"],
    "--version": ["--version"],
    "models": ["models"],
    "info": ["info", "{example}"],
    "convert": ["convert", "{example}", "{folder}/converted.dat"],
    "export (exact)": ["export", "{result}", "--to", "mitsuba", "-o", "{folder}/exported.xml"],
    "fit (warm cache)": ["fit", "{example}", "-o", "{folder}/warm.json"],
}


def startup_section(repeats: int, folder: Path) -> dict:
    """(k): wall time of each command of :data:`STARTUP`, median of ``max(repeats, 5)`` runs after one that fills
    the compilation cache."""
    import time

    script = str(Path(sys.executable).with_name("brdffit"))
    cache = str(folder / "startup-cache")
    example = ROOT / "examples" / "ward-pickled-oak.csv"
    result = folder / "startup-result.json"
    environment = {**os.environ, "BRDFFIT_CACHE_DIR": cache}
    # a Lambert fit, which Mitsuba's diffuse BSDF is exactly: the export maps parameters and computes nothing
    lambert = [script, "fit", str(example), "--model", "lambert", "-o", str(result)]
    subprocess.run(lambert, env=environment, capture_output=True, check=True)
    warm = [script, "fit", str(example), "-o", str(folder / "warm.json")]
    subprocess.run(warm, env=environment, capture_output=True, check=True)  # fills the cache of the warm fit
    names = {"example": example, "folder": folder, "result": result}
    seconds = {}
    for name, arguments in STARTUP.items():
        command = [script, *(argument.format(**names) for argument in arguments)]
        log(f"(k) brdffit {name}")
        runs = []
        for _ in range(max(repeats, 5)):
            for leftover in [*folder.glob("converted.dat"), *folder.glob("exported.xml"), *folder.glob("warm.json")]:
                leftover.unlink()
            clock = time.perf_counter()
            subprocess.run(command, env=environment, capture_output=True, check=True)
            runs.append(time.perf_counter() - clock)
        seconds[name] = {"seconds": statistics.median(runs), "all_seconds": runs}
    return seconds


def cli_section(repeats: int, folder: Path) -> dict:
    """(c): wall time of `brdffit fit` on the shipped example, from process start to the result written."""
    import time

    script = Path(sys.executable).with_name("brdffit")
    example = ROOT / "examples" / "ward-pickled-oak.csv"
    cache = str(folder / "cli-cache")

    def once() -> float:
        clock = time.perf_counter()
        subprocess.run(
            [str(script), "fit", str(example), "-o", str(folder / "cli.json")],
            env={**os.environ, "BRDFFIT_CACHE_DIR": cache},
            capture_output=True,
            check=True,
        )
        return time.perf_counter() - clock

    log("(c) command line, first run (empty compilation cache)")
    first = once()
    log("(c) command line, later runs")
    later = [once() for _ in range(max(repeats, 5))]
    return {"first_run_seconds": first, "seconds": statistics.median(later), "all_seconds": later, "n_samples": 10368}


#: The models of (h), as compare's specs and as fit's options.
COMPARED = {
    "lambert": ["--model", "lambert"],
    "ward": ["--model", "ward"],
    "cook-torrance:fresnel=conductor": ["--model", "cook-torrance", "--fresnel", "conductor"],
    "lafortune:lobes=2": ["--model", "lafortune", "--lobes", "2"],
}


def compare_section(repeats: int, folder: Path) -> dict:
    """(h): `brdffit compare` (4 models × 5 folds) against the 4 plain fits, process start to output written."""
    import time

    script = str(Path(sys.executable).with_name("brdffit"))
    example = str(ROOT / "examples" / "ward-pickled-oak.csv")

    def timed(*arguments: str) -> float:
        clock = time.perf_counter()
        subprocess.run(
            [script, *arguments], env={**os.environ, "BRDFFIT_CACHE_DIR": ""}, capture_output=True, check=True
        )
        return time.perf_counter() - clock

    compare_runs, fit_runs = [], []
    for round_number in range(1, repeats + 1):
        log(f"(h) compare against 4 fits, round {round_number}/{repeats}")
        specs = ",".join(COMPARED)
        compare_runs.append(timed("compare", example, "--models", specs, "--folds", "5", "-o", str(folder / "c.json")))
        fit_runs.append(sum(timed("fit", example, *flags, "-o", str(folder / "f.json")) for flags in COMPARED.values()))
    return {
        "models": list(COMPARED),
        "folds": 5,
        "compare_seconds": statistics.median(compare_runs),
        "fits_seconds": statistics.median(fit_runs),
        "all_compare_seconds": compare_runs,
        "all_fits_seconds": fit_runs,
    }


def default_compare_section(repeats: int, folder: Path) -> dict:
    """(n): `brdffit compare` with the default candidates, first runs (empty cache) and later ones, in turns."""
    import time

    script = str(Path(sys.executable).with_name("brdffit"))
    example = str(ROOT / "examples" / "ward-pickled-oak.csv")
    first_runs, later_runs = [], []
    for round_number in range(1, repeats + 1):
        log(f"(n) default compare, round {round_number}/{repeats}")
        cache = folder / f"cache-{round_number}"
        for runs in (first_runs, later_runs):  # the first fills this round's cache, the second finds it full
            clock = time.perf_counter()
            subprocess.run(
                [script, "compare", example, "-o", str(folder / "d.json")],
                env={**os.environ, "BRDFFIT_CACHE_DIR": str(cache)},
                capture_output=True,
                check=True,
            )
            runs.append(time.perf_counter() - clock)
    specs = len(json.loads((folder / "d.json").read_text())["models"])
    return {
        "specs": specs,
        "first_seconds": statistics.median(first_runs),
        "later_seconds": statistics.median(later_runs),
        "all_first_seconds": first_runs,
        "all_later_seconds": later_runs,
    }


def render_section(repeats: int) -> dict:
    """(i): the sphere renderer's time per model, each model in fresh processes."""
    models = ("ward", "cook-torrance", "lafortune")
    results = {}
    for model in models:
        log(f"(i) rendering a 256² sphere of {model}")
        results[model] = repeated(repeats, "render", "--model", model)
    return results


def mcmc_section(repeats: int) -> dict:
    log("(f) mcmc: 32 walkers × 2000 steps on the example")
    return repeated(repeats, "mcmc", "--walkers", "32", "--steps", "2000")


def merl_load_section(repeats: int, folder: Path) -> dict:
    log("(g) reading a full MERL file")
    from brdffit.export.merl import write_merl

    data = folder / "ward.binary"
    write_merl("ward", MATERIALS["ward"], data)  # here, so that the reading process's peak memory is the reader's
    return repeated(repeats, "merl-load", "--data", str(data))


def hold_section(repeats: int) -> dict:
    """(m): held parameters' fits in one process; the compilations each triggers, and scipy holding eta."""
    log("(m) fits that hold eta at 1.5, 1.6, 1.4, then bounds: one compiled solver")
    runs = [worker("hold") for _ in range(repeats)]

    def medians(key: str) -> list[dict]:
        fits = zip(*(run[key] for run in runs), strict=True)
        return [one[0] | {"seconds": statistics.median(each["seconds"] for each in one)} for one in fits]

    first = runs[0]
    by_fit = medians("runs")
    for position, fit in enumerate(by_fit):  # a compilation in any run counts: the claim is that there is none
        fit["compilations"] = max(run["runs"][position]["compilations"] for run in runs)
    return first | {"runs": by_fit, "scipy": medians("scipy"), "given_start": medians("given_start")}


def machine() -> dict:
    import jax
    import optimistix
    import scipy

    cpu = platform.processor() or platform.machine()
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {
        "date": datetime.date.today().isoformat(),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "backend": jax.default_backend(),
        "python": platform.python_version(),
        "jax": jax.__version__,
        "optimistix": optimistix.__version__,
        "scipy": scipy.__version__,
        "numpy": np.__version__,
    }


def table(results: dict) -> str:
    """The markdown summary the README shows."""
    info = results["machine"]
    measured: dict[tuple, list[str]] = {}
    for key, letter in SECTION_LETTERS.items():
        section = results.get(key)
        if isinstance(section, dict) and "date" in section:
            where = (section["date"], section.get("cpu", "?"), section.get("repeats", "?"))
            measured.setdefault(where, []).append(letter)
    runs = "; ".join(
        f"({', '.join(dict.fromkeys(letters))}) on {date}, {cpu}, medians of {repeats} runs"
        for (date, cpu, repeats), letters in measured.items()
    )
    lines = [
        f"Measured {runs}; {info['cores']} cores, {info['backend']} (jax {info['jax']}, optimistix"
        f" {info['optimistix']}, scipy {info['scipy']}); each run in a fresh process; in (a) and (b) the solvers take"
        " turns, round by round. Compare ratios within one section: the machines differ.",
        "",
        "| (a) MERL-size fit, 1,458,000 × RGB | Cook-Torrance | cost | Ward | cost |",
        "|---|---|---|---|---|",
    ]
    rows = [
        ("brdffit, compile included (empty cache)", "brdffit_cold"),
        ("brdffit, compile cached (later runs)", "brdffit_cached"),
        ("brdffit default path (own start search, empty cache)", "brdffit_default"),
        ("scipy least_squares trf, finite differences", "scipy-trf"),
        ("scipy least_squares lm, finite differences", "scipy-lm"),
        ("scipy least_squares lm, exact Jacobian", "scipy-lm-exact"),
    ]
    merl = {name: results[name] for name in ("cook-torrance", "ward") if name in results}
    if not merl:
        lines = lines[:2]
    for label, key in rows if merl else ():
        cells = []
        for section in merl.values():
            run = section[key]
            count = f", {run['steps']} steps" if "steps" in run else f", {run['nfev']} evaluations"
            cells += [f"{run['seconds']:.2f} s{count}", f"{run['cost']:.10g}"]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    for baseline in SCIPY_SOLVERS if merl else ():
        cells = []
        for section in merl.values():
            cold = section[baseline]["seconds"] / section["brdffit_cold"]["seconds"]
            cached = section[baseline]["seconds"] / section["brdffit_cached"]["seconds"]
            cells += [f"{cold:.1f}× / {cached:.1f}×", ""]
        lines.append(f"| speed-up over {baseline} (empty / filled cache) | " + " | ".join(cells) + " |")
    cells = []
    for section in merl.values():
        rounds = zip(section["scipy-trf"]["all_seconds"], section["brdffit_cold"]["all_seconds"], strict=True)
        cells += [", ".join(f"{scipy_seconds / seconds:.1f}×" for scipy_seconds, seconds in rounds), ""]
    if merl:
        lines.append("| speed-up over scipy-trf, empty cache, round by round | " + " | ".join(cells) + " |")
    batch = results.get("batch")
    if batch:
        scipy_run = batch["scipy-lm-exact"]
        lines += [
            "",
            f"| (b) {batch['materials']} Cook-Torrance materials × {batch['n_samples']:,} samples"
            " | time | converged | speed-up |",
            "|---|---|---|---|",
        ]
        for label, key in (
            ("brdffit fit_batch, same starts as scipy", "brdffit"),
            ("brdffit fit_batch, default path (own start search)", "brdffit-default"),
            ("scipy least_squares lm (exact Jacobian) loop", "scipy-lm-exact"),
        ):
            run = batch[key]
            ratio = scipy_run["seconds"] / run["seconds"]
            lines.append(
                f"| {label} | {run['seconds']:.1f} s | {run['converged']}/{batch['materials']} | {ratio:.1f}× |"
            )
    for key in MANY:
        many = results.get(key)
        if not many:
            continue
        scipy_run = many["scipy-lm-exact"]
        lines += [
            "",
            f"| (j) {many['materials']:,} Ward materials × {many['n_samples']:,} samples | time | per fit | converged"
            " | speed-up over scipy |",
            "|---|---|---|---|---|",
        ]
        for label, name in (
            ("brdffit fit_batch, same starts as scipy", "brdffit"),
            ("brdffit fit_batch, default path (own start search)", "brdffit-default"),
            ("the default path on one thread (`threads=1`)", "brdffit-default-1thread"),
            ("the default path, compiled programs reused (a second call)", "brdffit-default-warm"),
            ("the default path on a Dask LocalCluster, 1 worker", "brdffit-dask-1"),
            ("the default path on a Dask LocalCluster, 2 workers", "brdffit-dask-2"),
            ("scipy least_squares lm (exact Jacobian) loop", "scipy-lm-exact"),
        ):
            run = many[name]
            lines.append(
                f"| {label} | {run['seconds']:.2f} s | {1000 * run['seconds'] / many['materials']:.2f} ms"
                f" | {run['converged']}/{many['materials']} | {scipy_run['seconds'] / run['seconds']:.1f}× |"
            )
        ratio = many["brdffit-default"]["seconds"] / many["brdffit"]["seconds"]
        lines.append(f"| default path / given starts | {ratio:.2f}× | | | |")
    startup = results.get("startup")
    if startup:
        cells = ", ".join(f"`{name}` {run['seconds']:.2f} s" for name, run in startup.items() if isinstance(run, dict))
        lines += ["", f"(k) Process start to exit, medians: {cells}."]
    cli = results.get("cli")
    if cli:
        lines += [
            "",
            f"(c) `brdffit fit` of the 10,368-sample example, process start to result written: median "
            f"{cli['seconds']:.2f} s (first run, compiling: {cli['first_run_seconds']:.2f} s).",
        ]
    if "cook-torrance" in results:
        section = results["cook-torrance"]
        lines.append(
            "(d) Peak resident memory of the MERL-size Cook-Torrance fit:"
            f" {section['brdffit_cold']['peak_rss_mb']:.0f} MB."
        )
        lines.append("(e) Time per Levenberg-Marquardt step / one fused normal-equation pass:")
        for name, section in merl.items():
            step = section["per_step"]
            per_step = step["solve_seconds"] / step["steps"]
            line = (
                f"    {name}: {1000 * per_step:.0f} ms / {1000 * step['pass_seconds']:.0f} ms"
                f" = {per_step / step['pass_seconds']:.2f}× ({step['steps']} steps)"
            )
            if "pass_flops" in step:  # worker.pass_bound: the bytes and XLA's flops at this machine's rates
                line += (
                    f"; the pass's bound {1000 * step['bound_seconds']:.0f} ms, the larger of its bytes at the"
                    f" memory's rate ({step['pass_bytes'] / 1e6:.0f} MB at"
                    f" {step['bandwidth_bytes_per_second'] / 1e9:.1f} GB/s:"
                    f" {1000 * step['pass_bytes'] / step['bandwidth_bytes_per_second']:.0f} ms) and its flops at"
                    f" the machine's float64 rate ({step['pass_flops'] / 1e9:.2f} GFLOP at"
                    f" {step['flops_per_second'] / 1e9:.0f} GFLOP/s:"
                    f" {1000 * step['pass_flops'] / step['flops_per_second']:.0f} ms):"
                    f" a step is {per_step / step['bound_seconds']:.1f}× that bound"
                )
            if "transform_seconds" in step:  # worker.transform_alone: the loss's transform of every value, alone
                line += (
                    "; the loss's transform of every value alone (log1p; the fastest of 7 runs) takes"
                    f" {1000 * step['transform_seconds']:.0f} ms:"
                    f" a step is {per_step / step['transform_seconds']:.1f}× that"
                )
            lines.append(line)
    posterior = results.get("mcmc")
    if posterior:
        lines.append(
            f"(f) MCMC, emcee {posterior['walkers']} walkers × {posterior['steps']} steps on the"
            f" {posterior['n_samples']:,}-sample example, compile included: median {posterior['seconds']:.1f} s"
            f" ({posterior['evaluations_per_second']:.0f} walker evaluations/s; acceptance"
            f" {posterior['acceptance']:.2f}, τ ≤ {posterior['max_autocorr_time']:.0f} steps)."
        )
    loading = results.get("merl_load")
    if loading:
        lines.append(
            f"(g) Reading a full MERL file ({loading['n_samples']:,} valid direction pairs × RGB): median"
            f" {loading['seconds']:.2f} s, peak memory {loading['peak_rss_mb']:.0f} MB."
        )
    compared = results.get("compare")
    if compared:
        rounds = zip(compared["all_compare_seconds"], compared["all_fits_seconds"], strict=True)
        ratio = compared["compare_seconds"] / compared["fits_seconds"]
        lines.append(
            f"(h) `brdffit compare` of {len(compared['models'])} models × {compared['folds']} folds on the example:"
            f" median {compared['compare_seconds']:.1f} s against {compared['fits_seconds']:.1f} s for the"
            f" {len(compared['models'])} plain `brdffit fit` runs ({ratio:.2f}×;"
            f" round by round {', '.join(f'{c / f:.2f}×' for c, f in rounds)}), no compilation cache."
        )
    defaults = results.get("default_compare")
    if defaults:
        firsts, laters = (
            ", ".join(f"{x:.1f}" for x in defaults[key]) for key in ("all_first_seconds", "all_later_seconds")
        )
        lines.append(
            f"(n) `brdffit compare` with its {defaults['specs']} default candidates on the example: median"
            f" {defaults['first_seconds']:.1f} s on a first run (an empty compilation cache),"
            f" {defaults['later_seconds']:.1f} s on later ones (runs {firsts} s and {laters} s)."
        )
    held = results.get("hold")
    if held:
        pairs = zip(held["given_start"], held["scipy"], strict=True)
        difference = max(abs(ours["cost"] - theirs["cost"]) / theirs["cost"] for ours, theirs in pairs)
        cells = "; ".join(
            f"{run['label']}: {run['seconds']:.2f} s, {run['compilations']} compilation(s), {run['steps']} steps"
            for run in held["runs"]
        )
        lines.append(
            f"(m) Fits of one dielectric Cook-Torrance dataset ({held['n_samples']:,} samples) that hold parameters,"
            f" one process, medians of {held['repeats']} processes: {cells}. From one start, eta held at"
            " 1.5 / 1.6 / 1.4: brdffit "
            + " / ".join(f"{run['seconds']:.2f} s" for run in held["given_start"])
            + ", scipy least_squares lm (exact Jacobian, eta held by a closure) "
            + " / ".join(f"{run['seconds']:.2f} s" for run in held["scipy"])
            + f"; costs equal to {difference:.0e}."
        )
    rendered = results.get("render")
    if rendered:
        cells = ", ".join(
            f"{model} {1000 * run['point']['first_seconds']:.0f} ms first / {1000 * run['point']['seconds']:.1f} ms"
            f" (4 lights: {1000 * run['environment']['seconds']:.1f} ms)"
            for model, run in rendered.items()
            if isinstance(run, dict)
        )
        lines.append(f"(i) A 256² lit sphere, first render (compiling) / later ones, one light: {cells}.")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="runs per timing (default 3)")
    parser.add_argument("--quick", action="store_true", help="small sizes, to check that the benchmarks run")
    parser.add_argument("--output", type=Path, default=RESULTS, help="folder for latest.json and latest.md")
    parser.add_argument(
        "--sections",
        default="abcfghijkmn",
        help="which to run: a (with d, e), b, c, f, g, h, i, j, k, m, n; default all (the README's table needs all)",
    )
    args = parser.parse_args()
    merl_size, materials, batch_size = (20_000, 3, 5_000) if args.quick else (1_458_000, 100, 100_000)
    previous = args.output / "latest.json"
    results: dict = json.loads(previous.read_text()) if previous.exists() and not args.quick else {}
    if results.get("quick"):
        results = {}
    results |= {"machine": machine(), "repeats": args.repeats, "quick": args.quick}
    today = datetime.date.today().isoformat()
    # Each section says where and when it was measured: a later run of some sections keeps the others' figures.
    stamp = {"date": today, "cpu": results["machine"]["cpu"], "repeats": args.repeats}
    with tempfile.TemporaryDirectory(prefix="brdffit-bench-") as temporary:
        folder = Path(temporary)
        if "a" in args.sections:
            for model_name in MATERIALS:
                results[model_name] = merl_section(model_name, merl_size, args.repeats, folder) | stamp
        if "b" in args.sections:
            results["batch"] = batch_section(materials, batch_size, args.repeats) | stamp
        if "c" in args.sections:
            results["cli"] = cli_section(args.repeats, folder) | stamp
        if "f" in args.sections:
            results["mcmc"] = mcmc_section(args.repeats) | stamp
        if "g" in args.sections:
            results["merl_load"] = merl_load_section(args.repeats, folder) | stamp
        if "h" in args.sections:
            results["compare"] = compare_section(args.repeats, folder) | stamp
        if "i" in args.sections:
            results["render"] = render_section(args.repeats) | stamp
        if "j" in args.sections:
            for key, (count, size) in MANY.items():
                count, size = (20, 500) if args.quick else (count, size)
                results[key] = many_section(count, size, args.repeats) | stamp
        if "k" in args.sections:
            results["startup"] = startup_section(args.repeats, folder) | stamp
        if "n" in args.sections:
            results["default_compare"] = default_compare_section(args.repeats, folder) | stamp
        if "m" in args.sections:
            results["hold"] = hold_section(args.repeats) | stamp
    text = table(results)
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "latest.json").write_text(json.dumps(results, indent=2) + "\n")
    (args.output / "latest.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
