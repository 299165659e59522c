"""Where a single fit's time goes (issue 32), each run a fresh process, process start to exit.

    make bench-phases             # or: .venv/bin/python benchmarks/phases.py [--repeats 3] [--size 1458000]

Two fits, each ``cold`` (an empty compilation cache: a machine's first run, everything traced and compiled) and
``warm`` (the cache the cold run filled: brdffit's stored programs and executables, ``docs/command-line.md``):

* ``brdffit fit examples/ward-pickled-oak.csv --model ward -o RESULT`` (the shipped 10k example), as a user runs it;
* a MERL-size Cook-Torrance fit (1,458,000 direction pairs × RGB, 1% noise) from Python: ``Samples.from_arrays`` of
  saved arrays, ``brdffit.fit``, ``result.save``.

Each phase is timed in the process by wrapping the function that does it: reading the samples, the fit's set-up,
the start search (grid and race), the Levenberg-Marquardt solve, the caveats (the screens of lobe shares and
albedo, reciprocity, the rest), writing, and what is left of the process (Python's start and imports before the
command's work, the interpreter's exit). "Programs made ready" is the time spent loading stored programs and
executables, or tracing and compiling them, wherever it falls (it is part of the phases above; the part in
background threads overlaps them). Medians of ``--repeats`` runs; prints the table, writes
``benchmarks/results/phases.json`` and ``phases.md``, and puts the table into ``docs/scale.md`` (between its
``phases`` markers; ``tests/test_docs.py`` holds the two equal).
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
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SCALE_PAGE = ROOT / "docs" / "scale.md"
#: The lines in ``docs/scale.md`` between which the table stands.
MARKERS = ("<!-- phases: made by benchmarks/phases.py -->", "<!-- phases: end -->")
EXAMPLE = ROOT / "examples" / "ward-pickled-oak.csv"
#: Ngan et al. 2005's Cook-Torrance fit of MERL special-walnut-224 (as benchmarks/run.py's section (a)).
WALNUT = {"kd": [0.0187, 0.0145, 0.00961], "ks": [0.3209, 0.2725, 0.1821], "m": 0.258, "f0": 0.0688}
#: The phases in the table's order: a name and what it is.
PHASES = {
    "start-up": "Python's start and every import (JAX, SciPy, brdffit), wherever it falls",
    "read": "reading the samples",
    "set-up": "the fit's set-up (problems, the screens' program started)",
    "starts": "start search (grid, race)",
    "solve": "Levenberg-Marquardt solve",
    "screens": "caveats: screens (lobe shares, directional albedo)",
    "reciprocity": "caveats: reciprocity (what the main thread waits for)",
    "result": "the result and its other caveats",
    "write": "writing the result",
    "other": "the rest of the command (parsing, checks, printing)",
    "exit": "the interpreter's exit",
}


# ---------------------------------------------------------------------------------------------------- the worker
class Spans:
    """Seconds spent in wrapped functions on the main thread, per phase: a phase called inside another counts as its
    own, not the enclosing one's; and the seconds spent making programs ready, on any thread."""

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.programs = {"main": 0.0, "background": 0.0}
        self._open: list[float] = []  # for each phase under way on the main thread, its inner phases' seconds

    def timed(self, real, phase: str):
        def call(*args, **kwargs):
            if threading.current_thread() is not threading.main_thread():
                return real(*args, **kwargs)
            self._open.append(0.0)
            start = time.perf_counter()
            try:
                return real(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - start
                inner = self._open.pop()
                self.seconds[phase] = self.seconds.get(phase, 0.0) + elapsed - inner
                if self._open:
                    self._open[-1] += elapsed

        return call

    def wrap(self, owner, name: str, phase: str) -> None:
        setattr(owner, name, self.timed(getattr(owner, name), phase))

    def wrap_programs(self, owner, name: str) -> None:
        real = getattr(owner, name)

        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return real(*args, **kwargs)
            finally:
                where = "main" if threading.current_thread() is threading.main_thread() else "background"
                self.programs[where] += time.perf_counter() - start

        setattr(owner, name, timed)


def time_imports(spans: Spans) -> None:
    """Count every import (statements and ``importlib.import_module``) as the phase ``imports``."""
    import builtins
    import importlib

    builtins.__import__ = spans.timed(builtins.__import__, "imports")
    importlib.import_module = spans.timed(importlib.import_module, "imports")


def instrument(spans: Spans) -> None:
    """Wrap the functions each phase runs in."""
    import brdffit.data.load
    from brdffit._programs import stored
    from brdffit.fitting.single import caveats, result, stacked

    spans.wrap(brdffit.data.load, "load_samples", "read")
    spans.wrap(stacked.StackedFit, "__init__", "set-up")
    spans.wrap(stacked.StackedFit, "starts", "starts")
    spans.wrap(stacked.StackedFit, "solve", "solve")
    spans.wrap(stacked, "screen_bucket", "screens")
    spans.wrap(caveats, "reciprocity", "reciprocity")  # where a fit checks after its solve (many datasets at once)
    spans.wrap(stacked.StackedFit, "_reciprocity_checked", "reciprocity")  # a single fit's check runs in a thread
    spans.wrap(stacked, "result_of", "result")
    spans.wrap(result.FitResult, "save", "write")
    spans.wrap_programs(stored, "stored_program")


def report(spans: Spans, started: float, record: Path) -> None:
    """Write what the worker measured: its phases, when it started and when the command's work ended
    (``time.time()``)."""
    payload = {
        "started": started,
        "ended": time.time(),
        "seconds": spans.seconds,
        "programs": spans.programs,
    }
    record.write_text(json.dumps(payload))


def worker_cli(record: Path, argv: list[str]) -> None:
    """``brdffit`` with ``argv``, as its console script runs it (``cli.run``, its quick exit included)."""
    started = time.time()
    spans = Spans()
    time_imports(spans)
    import brdffit.cli

    instrument(spans)
    real_exit = brdffit.cli._exit

    def leave(status):
        report(spans, started, record)
        real_exit(status)

    brdffit.cli._exit = leave
    sys.argv = ["brdffit", *argv]
    brdffit.cli.run()


def worker_merl(record: Path, data: Path, output: Path, cache: str) -> None:
    """A MERL-size Cook-Torrance fit from Python; the interpreter exits as a script's does."""
    started = time.time()
    spans = Spans()
    time_imports(spans)
    import numpy as np

    import brdffit

    instrument(spans)
    if cache:
        brdffit.enable_compilation_cache(cache)

    def read():
        with np.load(data) as arrays:
            return brdffit.Samples.from_arrays(arrays["wi"], arrays["wo"], arrays["values"], ("r", "g", "b"))

    samples = spans.timed(read, "read")()
    result = brdffit.fit(samples, "cook-torrance")
    result.save(output)
    report(spans, started, record)


# ---------------------------------------------------------------------------------------------------- the parent
def run_once(arguments: list[str], cache: str) -> dict:
    """One fresh process of this script's worker: its phases, with start-up and exit from the wall clock."""
    with tempfile.TemporaryDirectory() as scratch:
        record = Path(scratch) / "phases.json"
        environment = dict(os.environ, BRDFFIT_CACHE_DIR=cache)
        environment.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: byte code cached, as pip leaves it
        launched = time.time()
        subprocess.run(
            [sys.executable, __file__, "--worker", str(record), *arguments],
            check=True,
            env=environment,
            cwd=scratch,
            stdout=subprocess.DEVNULL,
        )
        finished = time.time()
        measured = json.loads(record.read_text())
    seconds = measured["seconds"]
    wall = finished - launched
    in_process = measured["ended"] - launched
    phases = {name: seconds.get(name, 0.0) for name in PHASES if name not in ("start-up", "other", "exit")}
    phases["start-up"] = (measured["started"] - launched) + seconds.get("imports", 0.0)
    phases["exit"] = wall - in_process
    phases["other"] = max(in_process - sum(phases.values()) + phases["exit"], 0.0)
    return {
        "wall": wall,
        "phases": phases,
        "programs_main": measured["programs"]["main"],
        "programs_background": measured["programs"]["background"],
    }


def measure(name: str, arguments: list[str], repeats: int, folder: Path) -> dict:
    """``repeats`` cold runs (each an empty cache) and warm runs (the cache of the first cold run), in turns."""
    warm_cache = folder / f"cache-{name}"
    runs: dict[str, list[dict]] = {"cold": [], "warm": []}
    run_once(arguments, str(warm_cache))  # fills the cache the warm runs use
    for round_number in range(repeats):
        runs["cold"].append(run_once(arguments, str(folder / f"cold-{name}-{round_number}")))
        runs["warm"].append(run_once(arguments, str(warm_cache)))
        print(
            f"  {name} round {round_number + 1}: cold {runs['cold'][-1]['wall']:.2f} s,"
            f" warm {runs['warm'][-1]['wall']:.2f} s",
            flush=True,
        )
    return {kind: summary(each) for kind, each in runs.items()}


def summary(runs: list[dict]) -> dict:
    median = lambda values: statistics.median(values)
    return {
        "wall": median([run["wall"] for run in runs]),
        "walls": [run["wall"] for run in runs],
        "phases": {name: median([run["phases"][name] for run in runs]) for name in PHASES},
        "programs_main": median([run["programs_main"] for run in runs]),
        "programs_background": median([run["programs_background"] for run in runs]),
    }


def table(results: dict) -> str:
    columns = [(fit, kind) for fit in results["fits"] for kind in ("cold", "warm")]
    header = "| phase | " + " | ".join(f"{results['fits'][fit]['label']}, {kind}" for fit, kind in columns) + " |"
    lines = [header, "|---" * (len(columns) + 1) + "|"]
    cell = lambda seconds: f"{seconds:.2f} s" if seconds >= 0.005 else "–"
    for name, meaning in PHASES.items():
        values = [results["fits"][fit][kind]["phases"][name] for fit, kind in columns]
        lines.append(f"| {meaning} | " + " | ".join(cell(value) for value in values) + " |")
    total = [results["fits"][fit][kind]["wall"] for fit, kind in columns]
    lines.append("| **process start to exit** | " + " | ".join(f"**{value:.2f} s**" for value in total) + " |")
    for where in ("main", "background"):
        values = [results["fits"][fit][kind][f"programs_{where}"] for fit, kind in columns]
        label = "on the main thread" if where == "main" else "in background threads, overlapping"
        lines.append(f"| of which programs made ready, {label} | " + " | ".join(cell(v) for v in values) + " |")
    lines.append("")
    lines.append(
        f"{results['date']}, {results['cores']} cores ({results['platform']}), medians of {results['repeats']} runs,"
        " each a fresh process with byte code cached; cold: an empty compilation cache, warm: the cache of an earlier"
        " run."
    )
    return "\n".join(lines)


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        record, kind, *rest = sys.argv[2:]
        if kind == "cli":
            worker_cli(Path(record), rest)
        else:
            data, output = rest
            worker_merl(Path(record), Path(data), Path(output), os.environ.get("BRDFFIT_CACHE_DIR", ""))
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--size", type=int, default=1_458_000, help="direction pairs of the MERL-size fit")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    import numpy as np

    from brdffit import data_synth

    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        data = folder / "walnut.npz"
        wi, wo = data_synth.uniform_random(args.size, seed=1)
        samples = data_synth.synthesize("cook-torrance", WALNUT, wi, wo, noise=0.01, seed=2)
        np.savez(data, wi=samples.wi, wo=samples.wo, values=samples.values)
        fits = {
            "example": ("the example's `brdffit fit`", ["cli", "fit", str(EXAMPLE), "--model", "ward", "-o", "r.json"]),
            "merl": (f"MERL-size Cook-Torrance ({args.size:,})", ["merl", str(data), str(folder / "walnut.json")]),
        }
        results: dict = {
            "date": datetime.date.today().isoformat(),
            "cores": os.cpu_count(),
            "platform": platform.platform(),
            "repeats": args.repeats,
            "fits": {},
        }
        for name, (label, arguments) in fits.items():
            print(f"{label}:", flush=True)
            results["fits"][name] = {"label": label} | measure(name, arguments, args.repeats, folder)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "phases.json").write_text(json.dumps(results, indent=1) + "\n")
    text = table(results)
    (RESULTS / "phases.md").write_text(text + "\n")
    page = SCALE_PAGE.read_text()
    before, _, rest = page.partition(MARKERS[0] + "\n")
    _, _, after = rest.partition(MARKERS[1])
    SCALE_PAGE.write_text(f"{before}{MARKERS[0]}\n{text}\n{MARKERS[1]}{after}")
    print(text)


if __name__ == "__main__":
    main()
