"""Many files on many threads, repeated (issue 29): ``brdffit fit`` of 300 files with ``--threads 16``, 10 runs.

    make bench-threads            # or: .venv/bin/python benchmarks/threads.py [--files 300] [--threads 16] [--runs 10]

The stored programs once raced: with the compilation cache on (the command line's default), batch fits crashed
with ``TypeError: 'Exported' object is not callable`` in 10 of 10 such runs. Each file holds 200 seeded random
direction pairs of a Ward material (``brdffit synth``), its values scaled per file (up to 20%) and given 1%
multiplicative noise (seeded), so the fits differ. The first run fills the cache folder (a fresh one, under the
benchmark's temporary folder), the others find it warm. Each run is a fresh process; a crash is a non-zero exit, a
traceback on standard error or fewer results than files. Writes ``benchmarks/results/threads.json`` and
``threads.md`` and prints the table.
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
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
#: The command line, run by this interpreter (from this checkout: PYTHONPATH is set to it).
BRDFFIT = [sys.executable, "-c", "import sys; from brdffit.cli import run; sys.exit(run())"]
MATERIAL = '{"rho_d": [0.3], "rho_s": [0.1], "alpha": 0.2}'


def write_files(folder: Path, n_files: int) -> list[Path]:
    """``n_files`` samples files in ``folder``: one synthesized file's directions, its values scaled and noised."""
    template = folder / "template.csv"
    synth = ["synth", "--model", "ward", "--params", MATERIAL, "--geometry", "random", "--n-samples", "200"]
    subprocess.run([*BRDFFIT, *synth, "--seed", "1", "-o", str(template)], check=True, capture_output=True)
    rows = np.loadtxt(template, delimiter=",", skiprows=1)
    paths = []
    for index in range(n_files):
        rng = np.random.default_rng(index)
        values = rows.copy()
        values[:, 4] *= (1 + 0.2 * rng.random()) * (1 + 0.01 * rng.standard_normal(len(rows)))
        path = folder / f"s{index:03d}.csv"
        np.savetxt(path, values, delimiter=",", header="theta_i,phi_i,theta_o,phi_o,value", comments="", fmt="%.17g")
        paths.append(path)
    return paths


def one_run(paths: list[Path], threads: int, output: Path, environment: dict) -> dict:
    """One ``brdffit fit`` of every file into ``output``: its exit status, results written, tracebacks, seconds."""
    start = time.perf_counter()
    done = subprocess.run(
        [*BRDFFIT, "fit", *map(str, paths), "--model", "ward", "--threads", str(threads), "-o", f"{output}/"],
        capture_output=True,
        text=True,
        env=environment,
    )
    seconds = time.perf_counter() - start
    written = len(list(output.glob("*.json"))) if output.is_dir() else 0
    tracebacks = done.stderr.count("Traceback")
    crashed = done.returncode != 0 or tracebacks > 0 or written < len(paths)
    return {
        "exit": done.returncode,
        "written": written,
        "tracebacks": tracebacks,
        "seconds": seconds,
        "crashed": crashed,
    }


def table(runs: list[dict], n_files: int, threads: int) -> str:
    lines = [
        f"`brdffit fit` of {n_files} files, `--threads {threads}`, the compilation cache on (filled by run 1)",
        "",
        "| run | exit | results | tracebacks | seconds |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {k} | {run['exit']} | {run['written']} | {run['tracebacks']} | {run['seconds']:.1f} |"
        for k, run in enumerate(runs, 1)
    ]
    crashes = sum(run["crashed"] for run in runs)
    median = statistics.median(run["seconds"] for run in runs[1:] or runs)
    lines += ["", f"{crashes} crashes in {len(runs)} runs; median warm run {median:.1f} s."]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=300)
    parser.add_argument("--threads", type=int, default=16)
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="brdffit-threads-") as temporary:
        folder = Path(temporary)
        environment = dict(os.environ, BRDFFIT_CACHE_DIR=str(folder / "cache"), PYTHONPATH=str(ROOT))
        paths = write_files(folder, args.files)
        runs = []
        for run in range(args.runs):
            runs.append(one_run(paths, args.threads, folder / f"out{run}", environment))
            print(f"run {run + 1}: {runs[-1]}", flush=True)
    text = table(runs, args.files, args.threads)
    print(text)
    stamp = {"date": datetime.date.today().isoformat(), "machine": platform.machine(), "cpus": os.cpu_count()}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "threads.json").write_text(json.dumps({"runs": runs, **vars(args), **stamp}, indent=1) + "\n")
    (RESULTS / "threads.md").write_text(text + "\n")


if __name__ == "__main__":
    main()
