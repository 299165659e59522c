"""Spatially varying materials, measured (issue 31): the per-texel cost of ``brdffit svbrdf fit`` against a scipy
loop, the compilation a capture pays, and a 256 × 256 capture end to end.

    make bench-svbrdf             # or: .venv/bin/python benchmarks/svbrdf.py [--repeats 3] [--side 256]

1. **Per texel, compiled.** A 64 × 64 Ward capture of 32 photographs (``brdffit synth capture``, 1% noise) fitted
   by ``brdffit.svbrdf.fit`` in one process: once to compile, then ``--repeats`` times; the median over 4,096
   texels is the default path's cost a texel (reading the photographs, start search, solve, caveats, results). On
   one thread and on every core.
2. **scipy beside it**, in the same process: ``scipy.optimize.least_squares`` (``trf``, finite differences, what a
   user writes first; and ``lm`` with the exact Jacobian, compiled by JAX) on the same texels' samples, the same
   relative residuals and parameters (Ward, log albedos and log α), from the maps' median (a good start: brdffit's
   own start search is not given to scipy), one texel after another on 256 texels.
3. **Where the time goes**, on one thread: each phase's function wrapped and timed; and the solve's arithmetic,
   XLA's count of the flops of one texel's residuals and their Jacobian (``cost_analysis``) and the normal
   equations' ``2·m·n² + n³/3`` times the steps taken, against the machine's float64 rate (a 1024² matrix product).
4. **Compilation:** the fit of the 64 × 64 capture in a fresh process with an empty cache (``BRDFFIT_CACHE_DIR``,
   switched on as the command line does), and again in another fresh process with the programs it stored.
5. **End to end:** ``brdffit svbrdf fit`` of a ``--side`` × ``--side`` capture of 32 photographs, process start to
   maps written, with its peak resident memory (``VmHWM``).

Writes ``benchmarks/results/svbrdf.json`` and ``svbrdf.md`` and prints the table.
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
sys.path.insert(0, str(ROOT))

#: The capture of the per-texel measurements, and how many of its texels scipy fits.
SIDE, IMAGES, SCIPY_TEXELS = 64, 32, 256

#: A fit of a capture in a fresh process: its seconds (``svbrdf.fit``, after the imports) and its peak memory.
_FRESH = """
import re, sys, time
from pathlib import Path
import brdffit
import brdffit.svbrdf as svbrdf
brdffit.enable_compilation_cache()  # as the command line does
start = time.perf_counter()
svbrdf.fit(sys.argv[1], progress=False)
seconds = time.perf_counter() - start
print(seconds, re.search(r"VmHWM:\\s+(\\d+) kB", Path("/proc/self/status").read_text()).group(1))
"""
#: The command line end to end, with its peak memory.
_COMMAND = """
import re, sys
from pathlib import Path
from brdffit.cli import main
status = main(["-q", "svbrdf", "fit", sys.argv[1], "-o", sys.argv[2]])
print(status, re.search(r"VmHWM:\\s+(\\d+) kB", Path("/proc/self/status").read_text()).group(1))
"""


def environment(cache: str | None = None) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # a user's Python keeps its bytecode
    if cache is not None:
        env["BRDFFIT_CACHE_DIR"] = cache
    return env


def synthesize(folder: Path, side: int) -> None:
    from brdffit.data_synth.capture import synth_capture

    synth_capture(folder, "ward", shape=(side, side), n_images=IMAGES, noise=0.01, seed=0)


def per_texel(capture: Path, repeats: int) -> dict:
    """Section 1: the median seconds a texel of the warm default path, on one thread and on every core."""
    import brdffit.svbrdf as svbrdf

    found = {}
    for threads in (1, None):
        svbrdf.fit(capture, progress=False, threads=threads)  # compiled (and the photographs' files cached)
        runs = []
        for _ in range(repeats):
            start = time.perf_counter()
            svbrdf.fit(capture, progress=False, threads=threads)
            runs.append(time.perf_counter() - start)
        found["one thread" if threads == 1 else "every core"] = statistics.median(runs) / SIDE**2
    return found


def scipy_loop(capture: Path) -> dict:
    """Section 2: scipy's ``least_squares`` a texel, trf with finite differences and lm with JAX's Jacobian."""
    import jax
    from scipy.optimize import least_squares

    import brdffit.svbrdf as svbrdf
    from brdffit.svbrdf.texels import read_photographs, texel_samples

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    maps = svbrdf.fit(capture, progress=False)
    start = np.concatenate(
        [np.log(np.nanmedian(maps.params[name].reshape(-1, 3), axis=0)) for name in ("rho_d", "rho_s")]
        + [[np.log(np.nanmedian(maps.params["alpha"]))]]
    )
    run = texel_samples(read_photographs(svbrdf.read_capture(capture)), np.arange(SCIPY_TEXELS))

    def residuals(theta, wi, wo, measured):
        rho_d, rho_s, alpha = jnp.exp(theta[:3]), jnp.exp(theta[3:6]), jnp.exp(theta[6])
        h = wi + wo
        h = h / jnp.linalg.norm(h, axis=1, keepdims=True)
        tan2 = (1.0 - h[:, 2] ** 2) / h[:, 2] ** 2
        lobe = jnp.exp(-tan2 / alpha**2) / (4.0 * jnp.pi * alpha**2 * jnp.sqrt(wi[:, 2] * wo[:, 2]))
        predicted = rho_d[None, :] / jnp.pi + lobe[:, None] * rho_s[None, :]
        return ((predicted - measured) / jnp.maximum(measured, 1e-4)).ravel()

    compiled = jax.jit(residuals)
    jacobian = jax.jit(jax.jacfwd(residuals))
    found = {}
    for method in ("trf", "lm"):
        seconds = 0.0
        for texel in range(SCIPY_TEXELS):
            keep = run.kept[texel]
            arguments = (run.wi[texel, keep], run.wo[texel, keep], run.values[texel, keep])
            function = lambda theta, a=arguments: np.asarray(compiled(theta, *a))
            options = {"jac": lambda theta, a=arguments: np.asarray(jacobian(theta, *a))} if method == "lm" else {}
            function(start)  # compiled for this texel's shape before the clock starts
            if method == "lm":
                options["jac"](start)
            began = time.perf_counter()
            least_squares(function, start, method=method, **options)
            seconds += time.perf_counter() - began
        found[method] = seconds / SCIPY_TEXELS
    return found


def where_the_time_goes(capture: Path) -> dict:
    """Section 3: the seconds a texel spends in each phase on one thread (each phase's function wrapped and timed),
    and the arithmetic of the solve: flops a step by XLA's count, steps taken, against the machine's rate."""
    import collections
    import functools

    import jax

    import brdffit.svbrdf as svbrdf
    from brdffit.fitting.objective.losses import get_loss
    from brdffit.fitting.objective.problem import build_problem, residuals
    from brdffit.fitting.single import stacked
    from brdffit.physics.models.registry import get_model
    from brdffit.svbrdf import texel_fits

    spent: collections.Counter = collections.Counter()
    phases = [
        (texel_fits, "read_photographs", "reading the photographs"),
        (texel_fits, "texel_samples", "the texels' samples"),
        (stacked.StackedFit, "starts", "start search (grid, race of the starts)"),
        (stacked.StackedFit, "solve", "solve (Levenberg-Marquardt)"),
        (stacked, "screen_bucket", "caveats' screens (albedo, lobes)"),
        (stacked, "result_of", "results (caveats, FitResult; Python)"),
    ]
    originals = []
    for owner, name, label in phases:
        original = getattr(owner, name)
        originals.append((owner, name, original))

        def timed(*args, _original=original, _label=label, **kwargs):
            began = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                spent[_label] += time.perf_counter() - began

        setattr(owner, name, functools.wraps(original)(timed))
    try:
        maps = svbrdf.fit(capture, progress=False, threads=1)
        spent.clear()
        began = time.perf_counter()
        maps = svbrdf.fit(capture, progress=False, threads=1)
        total = time.perf_counter() - began
    finally:
        for owner, name, original in originals:
            setattr(owner, name, original)
    per_texel = {label: spent[label] / SIDE**2 for _, _, label in phases}
    per_texel["the rest (tiles, batches, maps)"] = total / SIDE**2 - sum(per_texel.values())

    jax.config.update("jax_enable_x64", True)
    from brdffit.fitting.many.cluster import fit_here
    from brdffit.svbrdf.texels import read_photographs, texel_samples

    capture_ = svbrdf.read_capture(capture)
    run = texel_samples(read_photographs(capture_), np.arange(512))
    datasets = [run.samples(t, capture_.channels, "texel") for t in range(512)]
    results = fit_here(datasets, "ward", "relative", progress=False)
    steps = float(np.mean([result.n_steps for result in results]))
    model, loss = get_model("ward"), get_loss("relative")
    problem = build_problem(datasets[0])
    theta = model.unconstrained.from_params(model.dictionary.to_params(results[0].params))
    residual = jax.jit(lambda t: residuals(model, loss, t, problem)).lower(theta).compile()
    jacobian = jax.jit(jax.jacfwd(lambda t: residuals(model, loss, t, problem))).lower(theta).compile()
    m, n = problem.measured.size, theta.size
    flops_step = _flops(residual) + _flops(jacobian) + 2 * m * n * n + n**3 / 3
    from worker import float64_product_rate  # benchmarks/ is this script's folder, first on its path

    rate = float64_product_rate()
    solve = per_texel["solve (Levenberg-Marquardt)"]
    return {
        "per_texel": per_texel,
        "total": total / SIDE**2,
        "mean_steps": steps,
        "flops_step": flops_step,
        "solve_flops_per_second": steps * flops_step / solve,
        "matmul_flops_per_second": rate,
        "padded_samples": int(problem.wi.shape[0]),
        "bytes_texel": run.wi[0].nbytes + run.wo[0].nbytes + run.values[0].nbytes + IMAGES * 3 * 4,
        "unconverged": int(np.sum(~maps.fit["converged"])),
    }


def _flops(compiled) -> float:
    analysis = compiled.cost_analysis()
    analysis = analysis[0] if isinstance(analysis, list) else analysis
    return float(analysis.get("flops", float("nan")))


def compilation(capture: Path) -> dict:
    """Section 4: the fit's seconds in a fresh process with an empty cache, and with the cache it filled."""
    with tempfile.TemporaryDirectory() as cache:
        runs = []
        for _ in range(2):
            command = [sys.executable, "-c", _FRESH, str(capture)]
            out = subprocess.run(command, capture_output=True, text=True, check=True, env=environment(cache)).stdout
            runs.append(float(out.split()[0]))
    return {"cold": runs[0], "cached": runs[1]}


def end_to_end(side: int, folder: Path) -> dict:
    """Section 5: the command line on a ``side`` × ``side`` capture, process start to maps written."""
    capture = folder / f"capture-{side}"
    synthesize(capture, side)
    began = time.perf_counter()
    command = [sys.executable, "-c", _COMMAND, str(capture), str(folder / f"maps-{side}")]
    out = subprocess.run(command, capture_output=True, text=True, check=True, env=environment()).stdout
    seconds = time.perf_counter() - began
    status, peak = out.split()
    return {"side": side, "images": IMAGES, "seconds": seconds, "status": int(status), "peak_mb": int(peak) / 1024}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="warm fits of the 64 × 64 capture (default 3)")
    parser.add_argument("--side", type=int, default=256, help="the end-to-end capture's side in texels (default 256)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        capture = Path(folder) / "capture"
        synthesize(capture, SIDE)
        found = {
            "per_texel": per_texel(capture, args.repeats),
            "scipy": scipy_loop(capture),
            "phases": where_the_time_goes(capture),
            "compilation": compilation(capture),
            "end_to_end": end_to_end(args.side, Path(folder)),
        }
    when = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    machine = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}"
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "svbrdf.json").write_text(json.dumps({"date": when, "machine": machine, **found}, indent=1) + "\n")
    ours, scipy, phases = found["per_texel"], found["scipy"], found["phases"]
    ms = lambda seconds: f"{1e3 * seconds:.3f} ms"
    end = found["end_to_end"]
    lines = [
        f"# Spatially varying materials ({when}, {machine})",
        "",
        f"A {SIDE} × {SIDE} Ward capture of {IMAGES} photographs (1% noise); medians of {args.repeats} warm fits;"
        f" scipy on {SCIPY_TEXELS} of its texels, one after another, in the same process.",
        "",
        "| per texel | seconds | × brdffit's (every core) |",
        "|---|---|---|",
        f"| brdffit, every core ({os.cpu_count()}) | {ms(ours['every core'])} | 1 |",
        f"| brdffit, one thread | {ms(ours['one thread'])} | {ours['one thread'] / ours['every core']:.2f} |",
        f"| scipy least_squares, trf, finite differences | {ms(scipy['trf'])}"
        f" | {scipy['trf'] / ours['every core']:.1f} |",
        f"| scipy least_squares, lm, JAX's compiled Jacobian | {ms(scipy['lm'])}"
        f" | {scipy['lm'] / ours['every core']:.1f} |",
        "",
        "Where a texel's time goes, on one thread:",
        "",
        "| phase | per texel |",
        "|---|---|",
        *[f"| {label} | {ms(seconds)} |" for label, seconds in phases["per_texel"].items()],
        f"| all | {ms(phases['total'])} |",
        "",
        f"The solve's arithmetic: {phases['mean_steps']:.1f} steps a texel (the mean) of {phases['flops_step']:,.0f}"
        f" flops each by XLA's count (residuals and their Jacobian on {phases['padded_samples']} padded samples, the"
        f" normal equations), {phases['solve_flops_per_second'] / 1e9:.2f} GFLOP/s, where a 1024² float64 matrix"
        f" product runs at {phases['matmul_flops_per_second'] / 1e9:.0f} GFLOP/s here: a texel's problem is too small"
        " for its arithmetic to bound it; each step's fixed work (the loop, its tests, the 7 × 7 solve) does. A texel"
        f" reads {phases['bytes_texel']:,} bytes, which stay in cache.",
        "",
        f"Compilation: the {SIDE} × {SIDE} fit takes {found['compilation']['cold']:.2f} s in a fresh process with an"
        f" empty cache, {found['compilation']['cached']:.2f} s with the programs it stored; warm in one process,"
        f" {ours['every core'] * SIDE**2:.2f} s.",
        "",
        f"End to end: `brdffit svbrdf fit` of a {end['side']} × {end['side']} capture of {end['images']} photographs,"
        f" process start to maps written: {end['seconds']:.1f} s, peak memory {end['peak_mb']:.0f} MB (exit status"
        f" {end['status']}).",
    ]
    (RESULTS / "svbrdf.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
