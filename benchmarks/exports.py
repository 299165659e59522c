"""Exports and renders, timed (issue 28: "any export ≤ 3 s, ``render`` reuses its export").

    make bench-exports            # or: .venv/bin/python benchmarks/exports.py [--repeats 3] [--baseline CHECKOUT]

The oak example (``examples/ward-pickled-oak.csv``) is fitted once with Ward, Cook-Torrance (Beckmann, V-groove,
Schlick: approximated by Mitsuba and glTF), 2-lobe Lafortune and a GGX/Smith conductor Cook-Torrance (exact in
Mitsuba). Then each command below runs in a fresh process, process start to exit (what a user waits for):

* ``brdffit export RESULT --to mitsuba`` and ``--to gltf`` of each fit;
* ``brdffit render RESULT -o sphere.png`` (the export made again, then rendered) and ``brdffit render BSDF.xml``
  (the exported file rendered as it is);

``cold``: with an empty compilation cache (a fresh folder, ``BRDFFIT_CACHE_DIR``), the first run on a machine;
``warm``: with the cache that run filled (the project's default: the command line keeps compiled programs,
``docs/command-line.md``). Medians of ``--repeats`` runs. ``--baseline CHECKOUT`` times another checkout of brdffit
(e.g. the code before this benchmark's change) in the same rounds, taking turns command by command, so that a shared
machine's load falls on both alike. ``--only TEXT`` times the commands whose label holds ``TEXT`` alone (with
``--output`` elsewhere, so that the full table stays). Prints the table and writes
``benchmarks/results/exports.json`` and ``exports.md``.
"""

import argparse
import datetime
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
EXAMPLE = ROOT / "examples" / "ward-pickled-oak.csv"
#: The fits: a name and the ``brdffit fit`` options.
FITS = {
    "ward": ["--model", "ward"],
    "cook-torrance": ["--model", "cook-torrance"],
    "lafortune-2": ["--model", "lafortune", "--lobes", "2"],
    "ggx-conductor": [
        "--model",
        "cook-torrance",
        "--fresnel",
        "conductor",
        "--distribution",
        "ggx",
        "--shadowing",
        "smith",
    ],
    "ward-aniso": ["--model", "ward-aniso"],  # fitted to the brushed samples (BRUSHED)
}
#: The brushed material's samples: ``brdffit synth`` options (seeded), fitted as ``FITS["ward-aniso"]``.
BRUSHED = [
    "--model",
    "ward-aniso",
    "--params",
    '{"rho_d": [0.2, 0.15, 0.1], "rho_s": [0.3, 0.3, 0.3], "alpha_x": 0.05, "alpha_y": 0.4}',
    "--geometry",
    "random",
    "--n-samples",
    "5000",
    "--noise",
    "0.01",
    "--seed",
    "1",
]
#: The render's size and samples per pixel (``brdffit render``'s defaults).
RENDER = ["--size", "256", "--spp", "64"]


def brdffit(checkout: Path, *arguments: str, cache: Path) -> tuple[float, float, str]:
    """Run ``brdffit ARGUMENTS`` from ``checkout`` in a fresh process; its wall seconds, its CPU seconds (user and
    system, all its threads: what a shared machine's load does not inflate as much) and its output."""
    environment = os.environ | {"PYTHONPATH": str(checkout), "BRDFFIT_CACHE_DIR": str(cache)}
    command = [sys.executable, "-c", "import sys; from brdffit.cli import main; sys.exit(main(sys.argv[1:]))"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    # Run outside any checkout: ``python -c`` puts the working folder first on the path, ahead of PYTHONPATH.
    done = subprocess.run(
        [*command, *arguments], env=environment, capture_output=True, text=True, check=False, cwd=cache
    )
    seconds = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode != 0:
        raise RuntimeError(f"brdffit {' '.join(arguments)} failed ({done.returncode}): {done.stderr.strip()}")
    return seconds, cpu, done.stdout


def commands(folder: Path) -> dict[str, list[str]]:
    """The commands timed, by label, on the fits in ``folder``."""
    timed = {}
    for name in FITS:
        result = str(folder / f"{name}.json")
        timed[f"export {name} --to mitsuba"] = ["export", result, "--to", "mitsuba", "-o", str(folder / f"{name}.xml")]
        timed[f"export {name} --to gltf"] = ["export", result, "--to", "gltf", "-o", str(folder / f"{name}.gltf")]
    for name in ("ward", "lafortune-2"):
        timed[f"render {name}.json"] = ["render", str(folder / f"{name}.json"), "-o", str(folder / "s.png"), *RENDER]
        timed[f"render {name}.xml"] = ["render", str(folder / f"{name}.xml"), "-o", str(folder / "x.png"), *RENDER]
    return timed


def measured(checkouts: dict[str, Path], repeats: int, folder: Path, only: str | None = None) -> dict:
    """Every command of :func:`commands` (those whose label holds ``only``, where given) for each checkout, cold and
    warm, ``repeats`` times, taking turns."""
    runs: dict = {}
    timed = {label: arguments for label, arguments in commands(folder).items() if only is None or only in label}
    for round_ in range(repeats):
        caches = {label: Path(tempfile.mkdtemp(prefix=f"cache-{label}-", dir=folder)) for label in checkouts}
        for command, arguments in timed.items():
            for label, checkout in checkouts.items():
                if arguments[0] == "render" and arguments[1].endswith(".xml") and label != "this":
                    continue  # an older brdffit cannot render a BSDF file
                for state in ("cold", "warm"):
                    if state == "cold":  # the cache of this command's programs emptied: a first run
                        caches[label] = Path(tempfile.mkdtemp(prefix=f"cache-{label}-", dir=folder))
                    seconds, cpu, out = brdffit(checkout, *arguments, cache=caches[label])
                    timing = runs.setdefault(label, {}).setdefault(command, {})
                    timing.setdefault(state, []).append(seconds)
                    timing.setdefault(f"{state}_cpu", []).append(cpu)
                    timing["says"] = out.splitlines()[1].strip()[:160] if "\n" in out else ""
                    print(
                        f"  round {round_ + 1}: {label:8} {state}  {seconds:6.2f} s ({cpu:5.2f} s CPU)  {command}",
                        flush=True,
                    )
    return {
        label: {
            command: {
                state: {
                    "median_s": statistics.median(timing[state]),
                    "runs_s": timing[state],
                    "median_cpu_s": statistics.median(timing[f"{state}_cpu"]),
                    "runs_cpu_s": timing[f"{state}_cpu"],
                }
                for state in ("cold", "warm")
            }
            | {"says": timing["says"]}
            for command, timing in by_command.items()
        }
        for label, by_command in runs.items()
    }


def table(results: dict) -> str:
    """The printed table: one row per command, cold and warm medians of each checkout."""
    labels = list(results["timings"])
    header = "| command | " + " | ".join(f"{label} cold | {label} warm" for label in labels) + " |"
    lines = [header, "|" + "---|" * (1 + 2 * len(labels))]
    for command in results["timings"]["this"]:
        cells = []
        for label in labels:
            timing = results["timings"][label].get(command)
            for state in ("cold", "warm"):
                cells.append(
                    "—"
                    if timing is None
                    else f"{timing[state]['median_s']:.2f} s ({timing[state]['median_cpu_s']:.2f} s CPU)"
                )
        lines.append(f"| `brdffit {command}` | " + " | ".join(cells) + " |")
    machine = results["machine"]
    lines.append("")
    lines.append(
        f"{results['date']}, {machine['cpus']} cores ({machine['processor'] or machine['platform']}), medians of"
        f" {results['repeats']} runs, each a fresh process: wall seconds, process start to exit (and the process's"
        " CPU seconds, user and system); cold: an empty compilation cache, warm: the cache the cold run filled."
    )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="runs per timing (default 3)")
    parser.add_argument("--baseline", type=Path, help="another checkout of brdffit, timed in the same rounds")
    parser.add_argument("--output", type=Path, default=RESULTS, help="folder for exports.json and exports.md")
    parser.add_argument("--only", metavar="TEXT", help="time only the commands whose label holds TEXT (ward-aniso)")
    args = parser.parse_args()
    checkouts = {"this": ROOT} | ({"baseline": args.baseline.resolve()} if args.baseline else {})
    with tempfile.TemporaryDirectory(prefix="brdffit-bench-exports-") as folder:
        folder = Path(folder)
        cache = Path(tempfile.mkdtemp(prefix="cache-fits-", dir=folder))
        brushed = folder / "brushed.csv"
        brdffit(ROOT, "synth", *BRUSHED, "-o", str(brushed), cache=cache)
        for name, options in FITS.items():
            data = brushed if name == "ward-aniso" else EXAMPLE
            brdffit(ROOT, "fit", str(data), *options, "-o", str(folder / f"{name}.json"), cache=cache)
            print(f"  fitted {name}", flush=True)
        results = {
            "date": datetime.date.today().isoformat(),
            "repeats": args.repeats,
            "machine": {"cpus": os.cpu_count(), "processor": platform.processor(), "platform": platform.platform()},
            "timings": measured(checkouts, args.repeats, folder, args.only),
        }
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "exports.json").write_text(json.dumps(results, indent=1) + "\n")
    text = table(results)
    (args.output / "exports.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
