"""Where one normal-equation pass's time goes, kernel by kernel (issue 32's step goal; (e) of ``run.py``).

    make bench-kernels            # or: .venv/bin/python benchmarks/kernels.py [--size 1458000]

On (a)'s MERL-size data (Cook-Torrance and Ward, the log loss, each at (a)'s start), in one process, the pass a
Levenberg-Marquardt step runs (``problem.normal_equations``, compiled with brdffit's options):

* its time, the median of 7 warm runs;
* the kernels XLA runs for it, each one's time summed over the pass's chunks, from JAX's profiler
  (``jax.profiler.trace``; its Perfetto trace is read back, and a kernel is an event named after an instruction of
  the compiled program): how many run for each chunk, their sum against the pass's time, the slowest ones;
* the pass at chunks of 4,096 and 65,536 samples as well as ``problem.CHUNK``'s: what a chunk costs whatever its
  size (from the difference between two sizes: the pass's time is a fixed cost a chunk plus a cost a sample);
* two controls on the same data: the ``l2`` loss, and the log loss with its transform's ``log1p`` replaced by a
  division, ``x / (1 + x)`` (not a loss: what the transform's transcendental function costs in the pass).

Every configuration is measured once a round, in turns, for ``--rounds`` rounds, and the round of its median time is
the one shown (its profile with it): this machine has stretches of seconds in which a pass takes 2–3 times as long,
its cores busy all the while, whatever runs before it (a process that runs one compiled pass for 15 s: 7% of its
passes slow, in stretches; with 0.2 s between passes, 71% in one run). The table shows the profiled passes' own time
beside the timed ones' (the profiler's overhead is a few percent): a profile taken in a slow stretch shows it. Prints
the tables, writes ``benchmarks/results/kernels.json`` and ``kernels.md``.
"""

import argparse
import collections
import datetime
import functools
import gzip
import json
import os
import platform
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).parent))

from run import merl_data  # noqa: E402
from worker import load  # noqa: E402

import brdffit.fitting.objective.problem as problem_module  # noqa: E402
from brdffit import get_model  # noqa: E402
from brdffit._jax import float64, jax  # noqa: E402
from brdffit._programs.jit import compiler_options  # noqa: E402
from brdffit.fitting.objective.losses import Loss, get_loss  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
MODELS = ("cook-torrance", "ward")
#: Chunk sizes besides ``problem.CHUNK`` at which the pass is timed.
OTHER_CHUNKS = (2**12, 2**16)
#: How many of the slowest kernels the table names.
SLOWEST = 5
#: The control in which the log loss's ``log1p`` is a division (same slope's form, no transcendental function).
DIVISION = Loss("log-as-division", "x / (1 + x), x = f·cos θi (a control)", lambda v, y, ci: v * ci / (1 + v * ci))


def compiled_pass(model, loss, theta, problem):
    """The normal-equation pass of ``model`` and ``loss`` compiled for ``problem`` as the solver's is, and the names
    of its compiled program's instructions (the kernels the profiler reports are named after them)."""
    lowered = jax.jit(lambda t, p: problem_module.normal_equations(model, loss, t, p)).lower(theta, problem)
    compiled = lowered.compile(compiler_options=compiler_options())
    names = set(re.findall(r"^\s*(?:ROOT\s+)?%?([\w.\-]+)\s*=", compiled.as_text(), flags=re.MULTILINE))
    return compiled, names


#: The samples of a data file, read once for all its configurations and rounds (~0.15 s and 100 MB a read).
_loaded = functools.cache(load)


def seconds_of(run, repeats: int = 7) -> float:
    """The median of ``repeats`` timed calls of ``run`` after one to warm up."""
    jax.block_until_ready(run())
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        jax.block_until_ready(run())
        times.append(time.perf_counter() - began)
    return statistics.median(times)


def kernel_seconds(run, names: set[str], passes: int = 3) -> tuple[dict[str, tuple[float, int]], float]:
    """Each kernel's time (s) and calls a pass, over ``passes`` profiled passes (the events of JAX's profiler whose
    name is an instruction of the compiled program), and the profiled passes' own time a pass (s)."""
    with tempfile.TemporaryDirectory() as folder:
        with jax.profiler.trace(folder, create_perfetto_trace=True):
            began = time.perf_counter()
            for _ in range(passes):
                jax.block_until_ready(run())
            profiled = (time.perf_counter() - began) / passes
        (trace,) = Path(folder).rglob("*perfetto_trace.json.gz")
        document = json.loads(gzip.decompress(trace.read_bytes()))
    events = document["traceEvents"] if isinstance(document, dict) else document
    total: collections.Counter = collections.Counter()
    calls: collections.Counter = collections.Counter()
    for event in events:
        if event.get("ph") == "X" and event.get("name") in names:
            total[event["name"]] += event.get("dur", 0) * 1e-6  # the trace gives durations in µs
            calls[event["name"]] += 1
    return {name: (total[name] / passes, calls[name] // passes) for name in total}, profiled


def measured(model_name: str, loss: Loss, data: Path, start: Path, chunk: int, profile: bool) -> dict:
    """The pass of ``model_name`` and ``loss`` on ``data`` at ``start`` with chunks of at most ``chunk`` samples: its
    time, and with ``profile`` its kernels."""
    model = get_model(model_name)
    samples = _loaded(data)
    default_chunk, problem_module.CHUNK = problem_module.CHUNK, chunk
    try:
        with float64():
            params = model.dictionary.to_params(json.loads(start.read_text()))
            theta = jax.numpy.asarray(model.unconstrained.from_params(params))
            problem = jax.jit(functools.partial(problem_module.prepared, loss))(problem_module.build_problem(samples))
            compiled, names = compiled_pass(model, loss, theta, problem)
            run = functools.partial(compiled, theta, problem)
            rows = problem.wi.shape[0]
            found = {
                "model": model_name,
                "loss": loss.name,
                "chunk": problem_module.chunk_size(rows),
                "chunks": rows // problem_module.chunk_size(rows),
                "pass_seconds": seconds_of(run),
            }
            if profile:
                kernels, found["profiled_pass_seconds"] = kernel_seconds(run, names)
                found["kernels"] = sorted(
                    ({"name": name, "seconds": seconds, "calls": calls} for name, (seconds, calls) in kernels.items()),
                    key=lambda kernel: -kernel["seconds"],
                )
            return found
    finally:
        problem_module.CHUNK = default_chunk


def summary(found: dict) -> dict:
    """``found`` (:func:`measured`, profiled) with its kernels summed: a chunk's kernels, their total time."""
    per_chunk = sum(kernel["calls"] for kernel in found["kernels"]) / found["chunks"]
    return found | {
        "kernels_per_chunk": per_chunk,
        "kernel_seconds": sum(kernel["seconds"] for kernel in found["kernels"]),
    }


def fixed_cost_of_a_chunk(by_chunk: list[dict]) -> float:
    """Seconds a chunk costs whatever its size: from the smallest chunks and the default ones, the pass's time being
    ``chunks · fixed + samples · per sample`` (both passes hold the same samples)."""
    small, default = by_chunk[0], by_chunk[1]
    return (small["pass_seconds"] - default["pass_seconds"]) / (small["chunks"] - default["chunks"])


def table(results: dict) -> str:
    """The results as markdown."""
    lines = [
        "| model | loss | pass | profiled pass | kernels a chunk | kernels' sum | slowest kernels (ms a pass) |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in results["profiled"]:
        slowest = ", ".join(f"`{k['name']}` {1000 * k['seconds']:.1f}" for k in row["kernels"][:SLOWEST])
        lines.append(
            f"| {row['model']} | {row['loss']} | {1000 * row['pass_seconds']:.1f} ms"
            f" | {1000 * row['profiled_pass_seconds']:.1f} ms | {row['kernels_per_chunk']:.0f}"
            f" | {1000 * row['kernel_seconds']:.1f} ms | {slowest} |"
        )
    lines += ["", "| model | chunk | chunks | pass, median | each round |", "|---|---|---|---|---|"]
    for model_name, rows in results["by_chunk"].items():
        for row in rows:
            rounds = ", ".join(f"{1000 * seconds:.0f}" for seconds in row["all_seconds"])
            cells = f"{row['chunk']:,} | {row['chunks']} | {1000 * row['pass_seconds']:.1f} ms | {rounds} ms"
            lines.append(f"| {model_name} | {cells} |")
    lines.append("")
    for model_name, fixed in results["fixed_cost_of_a_chunk"].items():
        default = results["by_chunk"][model_name][1]
        share = 1000 * fixed * default["chunks"]
        lines.append(
            f"{model_name}: a chunk costs {1e6 * fixed:.0f} µs whatever its size: {share:.1f} ms of the pass at"
            f" {default['chunk']:,} samples a chunk."
        )
    lines += ["", f"{results['date']}, {results['machine']}, {results['n_samples']:,} samples, the log loss's start."]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=1_458_000, help="direction pairs (default: a MERL table's)")
    parser.add_argument("--rounds", type=int, default=5, help="rounds of every measurement, in turns (default 5)")
    args = parser.parse_args()
    results: dict = {
        "date": datetime.date.today().isoformat(),
        "machine": f"{platform.machine()}, {len(os.sched_getaffinity(0))} cores",
        "n_samples": args.size,
        "profiled": [],
        "by_chunk": {},
        "fixed_cost_of_a_chunk": {},
    }
    with tempfile.TemporaryDirectory() as folder:
        made = {}
        for model_name in MODELS:
            print(f"{model_name}: data and start", file=sys.stderr, flush=True)
            made[model_name] = merl_data(model_name, args.size, Path(folder))
        configurations = [
            (model_name, loss, chunk, chunk == problem_module.CHUNK)
            for model_name in MODELS
            for loss, chunks in (
                (get_loss("log"), (problem_module.CHUNK, *OTHER_CHUNKS)),
                (get_loss("l2"), (problem_module.CHUNK,)),
                (DIVISION, (problem_module.CHUNK,)),
            )
            for chunk in chunks
        ]
        rounds: dict = collections.defaultdict(list)
        for round_number in range(1, args.rounds + 1):
            for model_name, loss, chunk, profile in configurations:
                print(
                    f"round {round_number}: {model_name}, {loss.name}, chunks of {chunk:,}", file=sys.stderr, flush=True
                )
                rounds[model_name, loss.name, chunk].append(
                    measured(model_name, loss, *made[model_name], chunk, profile)
                )
    for (model_name, loss_name, _chunk), runs in rounds.items():
        middle = sorted(runs, key=lambda run: run["pass_seconds"])[len(runs) // 2]  # the round of the median time
        if "kernels" in middle:
            results["profiled"].append(summary(middle))
        if loss_name == "log":
            results["by_chunk"].setdefault(model_name, []).append(
                middle | {"all_seconds": [r["pass_seconds"] for r in runs]}
            )
    for model_name, by_chunk in results["by_chunk"].items():
        by_chunk.sort(key=lambda row: row["chunk"])
        results["fixed_cost_of_a_chunk"][model_name] = fixed_cost_of_a_chunk(by_chunk)
    text = table(results)
    print(text)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "kernels.json").write_text(json.dumps(results, indent=1) + "\n")
    (RESULTS / "kernels.md").write_text(text + "\n")


if __name__ == "__main__":
    main()
