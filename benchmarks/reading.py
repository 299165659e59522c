"""Reading a samples file, measured (issue 29): the peak memory and time per row of ``load_samples`` on CSVs.

    make bench-reading            # or: .venv/bin/python benchmarks/reading.py [--rows 1e5,1e6] [--repeats 3]

Each file holds ``theta_i, phi_i, theta_o, phi_o, r, g, b`` with 17 significant digits (as ``save_samples``
writes: ~136 bytes a row), seeded random directions above the horizon. Each load runs in a fresh process, which
reports its peak resident memory (Linux's ``VmHWM``; ``ru_maxrss`` would count the parent's before the child's
``exec``) after importing brdffit and after ``load_samples``: their
difference over the rows is the reader's memory per row (the samples it returns included: 72 bytes a row for 3
channels); then it loads the file again under ``tracemalloc``, whose peak counts the bytes allocated (numpy's
arrays and Python's objects, not the interpreter's free lists): the same number where the machine has memory to
spare. Medians over ``--repeats``. Writes ``benchmarks/results/reading.json`` and ``reading.md``
and prints the table.
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
RESULTS = ROOT / "benchmarks" / "results"

#: The process that loads one file and prints its rows, memory per row (bytes) and seconds.
_LOAD = """
import re, sys, time, tracemalloc
from pathlib import Path
from brdffit import load_samples
peak = lambda: int(re.search(r"VmHWM:\\s+(\\d+) kB", Path("/proc/self/status").read_text()).group(1))
before = peak()
start = time.perf_counter()
samples = load_samples(sys.argv[1])
seconds = time.perf_counter() - start
after = peak()
del samples
tracemalloc.start()
samples = load_samples(sys.argv[1])
traced = tracemalloc.get_traced_memory()[1]
print(samples.n_samples, (after - before) * 1024 / samples.n_samples, traced / samples.n_samples, seconds)
"""


def write_file(path: Path, rows: int, seed: int = 0) -> None:
    """A samples file of ``rows`` seeded random rows, written as ``save_samples`` writes numbers."""
    rng = np.random.default_rng(seed)
    table = np.column_stack(
        [rng.uniform(0, 80, rows), rng.uniform(0, 360, rows), rng.uniform(0, 80, rows), rng.uniform(0, 360, rows)]
        + [rng.uniform(0, 1, rows) for _ in range(3)]
    )
    with open(path, "w") as file:
        file.write("theta_i,phi_i,theta_o,phi_o,r,g,b\n")
        np.savetxt(file, table, fmt="%.17g", delimiter=",")


def measure(path: Path) -> tuple[int, float, float, float]:
    """Rows, bytes per row (resident, and allocated as ``tracemalloc`` counts) and seconds of ``load_samples`` of
    ``path`` in a fresh process."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    command = [sys.executable, "-c", _LOAD, str(path)]
    run = subprocess.run(command, capture_output=True, text=True, check=True, cwd=ROOT, env=env)
    rows, resident, traced, seconds = run.stdout.split()
    return int(rows), float(resident), float(traced), float(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", default="1e5,1e6", help="comma-separated row counts (default 1e5,1e6)")
    parser.add_argument("--repeats", type=int, default=3, help="loads of each file, each in a fresh process")
    args = parser.parse_args()
    found = []
    with tempfile.TemporaryDirectory() as folder:
        for rows in (int(float(count)) for count in args.rows.split(",")):
            path = Path(folder) / f"rows-{rows}.csv"
            write_file(path, rows)
            runs = [measure(path) for _ in range(args.repeats)]
            found.append(
                {
                    "rows": rows,
                    "file_bytes_per_row": path.stat().st_size / rows,
                    "resident_bytes_per_row": statistics.median(run[1] for run in runs),
                    "traced_bytes_per_row": statistics.median(run[2] for run in runs),
                    "seconds": statistics.median(run[3] for run in runs),
                }
            )
            path.unlink()
    when = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    machine = f"{platform.processor() or platform.machine()}, {platform.python_version()}"
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "reading.json").write_text(json.dumps({"date": when, "machine": machine, "runs": found}, indent=1))
    lines = [
        f"# Reading a samples file ({when}, {machine})",
        "",
        f"Median of {args.repeats} loads, each in a fresh process; peak resident memory over what importing brdffit"
        " took.",
        "",
        "| rows | file, bytes/row | peak resident, bytes/row | peak allocated (tracemalloc), bytes/row | seconds |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['rows']:,} | {r['file_bytes_per_row']:.0f} | {r['resident_bytes_per_row']:.0f}"
        f" | {r['traced_bytes_per_row']:.0f} | {r['seconds']:.2f} |"
        for r in found
    ]
    (RESULTS / "reading.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
