"""(l) The data-driven model (issue 15) on a library of MERL tables: build time and memory, and held-out materials
fitted from the 20 pairs the basis chooses, against the analytic models fitted to the same 20 samples.

    .venv/bin/python -m brdffit.data_synth.library LIBRARY --analytic 60 --mitsuba 40   # 100 tables, ~3 GB, ~3 min
    .venv/bin/python benchmarks/pca.py LIBRARY [--components 8,16,24] [--held-out 0.25] [--seed 0]

1. Build: ``build_basis`` of every table of the library (100), in a fresh process: wall time and peak resident
   memory (``ru_maxrss``), medians of ``--repeats``.
2. Held out: a seeded quarter of each kind of material (brdffit's models; Mitsuba's principled, roughconductor,
   roughplastic) is left out; a basis of each ``--components`` is built from the rest.
3. Each held-out material is measured at the basis's 20 greedy pairs (its table's values there) with 1%
   multiplicative noise (seeded), and fitted with ``pca`` (ridge 1e-4, 1e-3 the default, 1e-2) and with each
   analytic candidate (Ward, Cook-Torrance with Schlick and with conductor Fresnel, Blinn-Phong, one Lafortune
   lobe), log loss. Each fit is judged on the dense table: the median relative error ``|f − y| / y`` over 20,000
   seeded bins with θi, θo ≤ 80° and y > 0. The best analytic model is the one whose dense error is lowest (an
   oracle: a user with 20 samples could not pick it so well), so a win of the data-driven model is not flattered.

Writes ``benchmarks/results/pca.json`` and ``pca.md`` and prints the table.
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import brdffit
from brdffit.data.merl import SCALES, bin_directions, stored_planes
from brdffit.data.samples import Samples
from brdffit.datadriven.basis import save_basis
from brdffit.datadriven.build import build_basis
from brdffit.datadriven.directions import condition_number, select_bins

RESULTS = Path(__file__).parent / "results"
ANALYTIC = {
    "ward": {"model": "ward"},
    "cook-torrance": {"model": "cook-torrance"},
    "cook-torrance:conductor": {"model": "cook-torrance", "fresnel": "conductor"},
    "blinn-phong": {"model": "blinn-phong"},
    "lafortune": {"model": "lafortune"},
}
RIDGES = (1e-4, 1e-3, 1e-2)
N_PAIRS, NOISE, DENSE, MAX_THETA = 20, 0.01, 20_000, 80.0


def group(entry: dict) -> str:
    """A material's kind for the summary: brdffit's models, or the Mitsuba plugin (principled with a clear coat
    apart, the layered materials analytic models cannot represent)."""
    if entry["source"] == "brdffit":
        return "brdffit analytic"
    bsdf = entry["parameters"]["bsdf"]
    if entry["kind"] == "principled" and bsdf.get("clearcoat", 0) >= 0.5:
        return "principled + clear coat"
    return f"mitsuba {entry['kind']}"


def held_out_split(entries: list[dict], share: float, seed: int) -> tuple[list[dict], list[dict]]:
    """A seeded ``share`` of each kind held out (at least one per kind)."""
    rng = np.random.default_rng(seed)
    kinds: dict[str, list[dict]] = {}
    for entry in entries:
        kinds.setdefault(f"{entry['source']}/{entry['kind']}", []).append(entry)
    held = []
    for members in kinds.values():
        count = max(1, round(share * len(members)))
        held += [members[i] for i in sorted(rng.choice(len(members), count, replace=False))]
    names = {entry["name"] for entry in held}
    return [entry for entry in entries if entry["name"] not in names], held


def table_of(path: Path) -> np.ndarray:
    """A MERL file's BRDF (bins, 3) in 1/sr."""
    return (np.asarray(stored_planes(path)) * SCALES[:, None]).T


def measure_build(files: list[Path], components: int, repeats: int) -> dict:
    """``build_basis`` of ``files`` in fresh processes: wall time and peak resident memory, medians."""
    code = (
        "import json, resource, sys, time\n"
        "from brdffit.datadriven.build import build_basis\n"
        "files = sys.argv[2:]\n"
        "start = time.perf_counter()\n"
        "build_basis(files, components=int(sys.argv[1]))\n"
        "print(json.dumps({'seconds': time.perf_counter() - start,"
        " 'peak_mb': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))\n"
    )
    runs = []
    for _ in range(repeats):
        done = subprocess.run(
            [sys.executable, "-c", code, str(components), *map(str, files)], capture_output=True, text=True, check=True
        )
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return {
        "tables": len(files),
        "components": components,
        "seconds": float(np.median([run["seconds"] for run in runs])),
        "peak_mb": float(np.median([run["peak_mb"] for run in runs])),
        "input_gb": sum(path.stat().st_size for path in files) / 1e9,
        "repeats": repeats,
    }


def dense_error(predicted: np.ndarray, truth: np.ndarray) -> float:
    return float(np.median(np.abs(predicted - truth) / truth))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("library", type=Path, help="a folder written by python -m brdffit.data_synth.library")
    parser.add_argument(
        "--components", type=lambda text: [int(k) for k in text.split(",")], default=[8, 16, 24], help="K,K,…"
    )
    parser.add_argument("--held-out", type=float, default=0.25, help="share of each kind held out (default 0.25)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--repeats", type=int, default=1, help="build runs, each in a fresh process (default 1; 0 keeps the last)"
    )
    parser.add_argument("--output", type=Path, default=RESULTS)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    entries = json.loads((args.library / "library.json").read_text())
    files = {entry["name"]: args.library / entry["file"] for entry in entries}

    build = measure_build(list(files.values()), max(args.components), args.repeats) if args.repeats else None
    previous = args.output / "pca.json"
    if build is None and previous.exists():  # --repeats 0 keeps the last measured build
        build = json.loads(previous.read_text()).get("build_100")
    if build:
        print(
            f"build: {build['tables']} tables ({build['input_gb']:.2f} GB), {build['components']} components:"
            f" {build['seconds']:.1f} s, peak {build['peak_mb']:.0f} MB"
        )

    kept, held = held_out_split(entries, args.held_out, args.seed)
    runs = [held_out_run(args, files, kept, held, components) for components in args.components]
    output = {"date": time.strftime("%Y-%m-%d"), "build_100": build, "runs": runs}
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "pca.json").write_text(json.dumps(output, indent=1) + "\n")
    (args.output / "pca.md").write_text(markdown(output) + "\n")
    print(markdown(output))


def held_out_run(args, files: dict, kept: list[dict], held: list[dict], components: int) -> dict:
    """The basis of ``kept`` with ``components``, and every held-out material fitted from its 20 pairs."""
    started = time.perf_counter()
    basis = build_basis([files[entry["name"]] for entry in kept], components=components)
    folder = tempfile.TemporaryDirectory(prefix="brdffit-pca-")  # the basis: ~3.7 MB a component, removed after
    basis_path = Path(folder.name) / f"basis-{components}.npz"
    save_basis(basis, basis_path)
    print(
        f"basis of {len(kept)} tables in {time.perf_counter() - started:.1f} s; explained"
        f" {np.round(100 * basis.explained, 1).tolist()} %"
    )
    bins = select_bins(basis, N_PAIRS)
    condition = condition_number(basis, bins)
    wi, wo = bin_directions()
    limit = np.cos(np.radians(MAX_THETA))
    rng = np.random.default_rng(args.seed)
    eligible = np.flatnonzero(basis.filled & (wi[:, 2] >= limit) & (wo[:, 2] >= limit))

    rows = []
    for number, entry in enumerate(held):
        table = table_of(files[entry["name"]])
        noisy = table[bins] * (1 + NOISE * np.random.default_rng(args.seed + number).standard_normal((N_PAIRS, 3)))
        samples = Samples.from_arrays(wi[bins], wo[bins], noisy, channels=("r", "g", "b"), source=entry["name"])
        positive = eligible[np.all(table[eligible] > 0, axis=1)]
        dense = rng.choice(positive, min(DENSE, positive.size), replace=False)
        truth = table[dense]
        errors, seconds, converged = {}, {}, {}
        for ridge in RIDGES:
            started = time.perf_counter()
            result = brdffit.fit(samples, model="pca", basis=str(basis_path), ridge=ridge)
            seconds[f"pca {ridge:g}"] = time.perf_counter() - started
            errors[f"pca {ridge:g}"] = dense_error(result.predict(wi[dense], wo[dense]), truth)
            converged[f"pca {ridge:g}"] = result.converged
        reference = rng.choice(positive, min(DENSE, positive.size), replace=False)  # the basis's own limit
        dense_samples = Samples.from_arrays(wi[reference], wo[reference], table[reference], channels=("r", "g", "b"))
        result = brdffit.fit(dense_samples, model="pca", basis=str(basis_path))
        errors["pca dense"] = dense_error(result.predict(wi[dense], wo[dense]), truth)
        for name, options in ANALYTIC.items():
            started = time.perf_counter()
            result = brdffit.fit(samples, **options)
            seconds[name] = time.perf_counter() - started
            errors[name] = dense_error(result.predict(wi[dense], wo[dense]), truth)
            converged[name] = result.converged
        best = min(ANALYTIC, key=lambda name: errors[name])
        rows.append(
            {
                "material": entry["name"],
                "group": group(entry),
                "errors": errors,
                "seconds": seconds,
                "converged": converged,
                "best_analytic": best,
            }
        )
        print(
            f"{entry['name']:32s} {group(entry):26s} pca {errors['pca 0.001']:.3f}  best analytic {best}"
            f" {errors[best]:.3f}"
        )

    folder.cleanup()
    return {
        "basis": {
            "tables": len(kept),
            "components": components,
            "explained": basis.explained.tolist(),
            "pairs": N_PAIRS,
            "condition_number": condition,
        },
        "held_out": rows,
        "summary": summarise(rows),
    }


def summarise(rows: list[dict]) -> list[dict]:
    """Per group and over all: median dense error of pca (each ridge) and of the best analytic model, and how often
    pca (default ridge) wins."""
    groups = [*sorted({row["group"] for row in rows}), "all"]
    out = []
    for name in groups:
        members = [row for row in rows if name in ("all", row["group"])]
        pca = [row["errors"]["pca 0.001"] for row in members]
        analytic = [row["errors"][row["best_analytic"]] for row in members]
        out.append(
            {
                "group": name,
                "materials": len(members),
                **{
                    f"pca {ridge:g}": float(np.median([row["errors"][f"pca {ridge:g}"] for row in members]))
                    for ridge in RIDGES
                },
                "pca dense": float(np.median([row["errors"]["pca dense"] for row in members])),
                "best analytic": float(np.median(analytic)),
                "pca wins": int(sum(p < a for p, a in zip(pca, analytic, strict=True))),
                "fits not converged": int(sum(not ok for row in members for ok in row["converged"].values())),
            }
        )
    return out


def markdown(output: dict) -> str:
    build = output["build_100"]
    lines = [f"## (l) Data-driven model ({output['date']})", ""]
    if build:
        lines += [
            f"Build of {build['tables']} MERL tables ({build['input_gb']:.2f} GB), {build['components']} components:"
            f" {build['seconds']:.1f} s, peak resident memory {build['peak_mb']:.0f} MB.",
            "",
        ]
    for run in output["runs"]:
        basis = run["basis"]
        lines += [
            f"Basis of {basis['tables']} tables, {basis['components']} components (variance explained"
            f" {sum(basis['explained']):.1%}); {basis['pairs']} greedy pairs, condition number"
            f" {basis['condition_number']:.3g}. Median relative error of the dense table (θ ≤ 80°), fits from the"
            " 20 pairs with 1% noise:",
            "",
            "| materials | n | pca ridge 1e-4 | pca 1e-3 (default) | pca 1e-2 | pca, 20,000 samples | best analytic"
            " (oracle) | pca wins | fits not converged |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for row in run["summary"]:
            lines.append(
                f"| {row['group']} | {row['materials']} | {row['pca 0.0001']:.3f} | {row['pca 0.001']:.3f} |"
                f" {row['pca 0.01']:.3f} | {row['pca dense']:.3f} | {row['best analytic']:.3f} |"
                f" {row['pca wins']}/{row['materials']} | {row['fits not converged']} |"
            )
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
