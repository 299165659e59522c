"""One benchmark measurement in a fresh process; prints one JSON line. Run by ``benchmarks/run.py``.

Every measurement runs in its own process so that nothing compiled by an
earlier one is reused: "compile included" means what it says. The data are
made (or loaded) before the clock starts; the clock covers the fit from the
samples in memory to the result (parameters and cost) in hand.

    python benchmarks/worker.py merl --model cook-torrance --solver brdffit --data D.npz --start S.json
    python benchmarks/worker.py steps --model cook-torrance --data D.npz --start S.json
    python benchmarks/worker.py batch --solver scipy-lm-exact --materials 100 --size 100000 [--model ward]
    python benchmarks/worker.py mcmc --walkers 32 --steps 2000
    python benchmarks/worker.py merl-load --data FILE.binary
    python benchmarks/worker.py render --model ward
    python benchmarks/worker.py hold
"""

import argparse
import functools
import json
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from brdffit import Samples, data_synth, enable_compilation_cache, fit, fit_batch, get_model
from brdffit.fitting.objective.losses import get_loss

LOSS = "log"


def peak_rss_mb() -> float:
    """Peak resident memory of this process, MB: ``VmHWM`` of ``/proc/self/status`` where there is one.

    ``getrusage``'s ``ru_maxrss`` is no good here: Linux carries the forked parent's high-water mark
    across ``exec``, so every worker reported at least run.py's own peak (878 MB for a reader that uses 470 MB).
    """
    try:
        with open("/proc/self/status") as status:
            line = next(line for line in status if line.startswith("VmHWM:"))
        return int(line.split()[1]) / 1024
    except (OSError, StopIteration):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def load(path) -> Samples:
    arrays = np.load(path)
    return Samples.from_arrays(arrays["wi"], arrays["wo"], arrays["values"], channels=("r", "g", "b"))


@functools.cache
def scipy_functions(model_name: str):
    """The residual vector and its Jacobian, jitted once per model with the data as an argument, as a
    competent scipy user would write them (compiled on first call, inside the clock)."""
    import jax

    from brdffit.fitting.objective.problem import prepared, residuals

    model, loss = get_model(model_name), get_loss(LOSS)

    def flat(theta, data):
        return residuals(model, loss, theta, data).ravel()

    return jax.jit(functools.partial(prepared, loss)), jax.jit(flat), jax.jit(jax.jacfwd(flat))


def scipy_fit(model_name: str, samples: Samples, theta0: np.ndarray, method: str, exact: bool):
    """scipy.optimize.least_squares on the same residuals, from the same start, in float64 as brdffit computes
    (a JAX user turns ``jax_enable_x64`` on; without it every array here would silently become float32)."""
    import jax
    import jax.numpy as jnp
    import scipy.optimize

    from brdffit.fitting.objective.problem import build_problem

    jax.config.update("jax_enable_x64", True)

    n = samples.n_samples
    # T(y) and the scale computed once, as brdffit's solver does; then exactly the samples, no padding.
    prepare, residual, jacobian = scipy_functions(model_name)
    problem = jax.tree.map(lambda a: a[:n], prepare(build_problem(samples)))
    out = scipy.optimize.least_squares(
        lambda th: np.asarray(residual(jnp.asarray(th), problem)),
        theta0,
        method=method,
        jac=(lambda th: np.asarray(jacobian(jnp.asarray(th), problem))) if exact else "2-point",
    )
    return {"cost": 2.0 * float(out.cost), "nfev": int(out.nfev), "converged": bool(out.status > 0)}


#: (b), (j): brdffit's ways through many fits (``batch``), each measured against the scipy loop.
BATCH_SOLVERS = (
    "brdffit",
    "brdffit-default",
    "brdffit-default-1thread",
    "brdffit-default-warm",
    "brdffit-dask-1",
    "brdffit-dask-2",
)
SCIPY = {"scipy-trf": ("trf", False), "scipy-lm": ("lm", False), "scipy-lm-exact": ("lm", True)}


def merl(args) -> dict:
    enable_compilation_cache()  # BRDFFIT_CACHE_DIR="" (set by run.py) keeps it off
    samples = load(args.data)
    start = json.loads(Path(args.start).read_text())
    model = get_model(args.model)
    clock = time.perf_counter()
    if args.solver == "brdffit":
        result = fit(samples, args.model, start=start, n_starts=1)
        out = {"cost": result.cost, "steps": result.n_steps, "converged": result.converged}
    elif args.solver == "brdffit-default":
        result = fit(samples, args.model)
        out = {"cost": result.cost, "steps": result.n_steps, "converged": result.converged}
    else:
        theta0 = model.unconstrained.from_params(model.dictionary.to_params(start))
        out = scipy_fit(args.model, samples, theta0, *SCIPY[args.solver])
    return out | {"seconds": time.perf_counter() - clock, "peak_rss_mb": peak_rss_mb(), "n_samples": samples.n_samples}


def steps(args) -> dict:
    """(e): time per Levenberg-Marquardt step against one fused normal-equation pass (both compiled, warm)."""
    import jax
    import jax.numpy as jnp

    from brdffit._programs import jit
    from brdffit.fitting.objective.problem import build_problem, normal_equations, prepared
    from brdffit.fitting.solver.compiled import compiled_solver

    samples = load(args.data)
    model, loss = get_model(args.model), get_loss(LOSS)
    # The loss's target and scale filled in once, as the solver does before its first step; both are timed on it.
    problem = jit(functools.partial(prepared, loss))(build_problem(samples))
    theta = jnp.asarray(
        model.unconstrained.from_params(model.dictionary.to_params(json.loads(Path(args.start).read_text())))
    )

    sums = jit(lambda t, p: normal_equations(model, loss, t, p))  # compiled as the solver is (brdffit's options)
    solve = compiled_solver(model, loss, 256)

    def seconds_of(call, repeats, summary=np.median):
        """``summary`` (the median; the minimum for a floor) of ``repeats`` timed calls after one to warm up."""
        jax.block_until_ready(call())
        times = []
        for _ in range(repeats):
            clock = time.perf_counter()
            output = jax.block_until_ready(call())
            times.append(time.perf_counter() - clock)
        return float(summary(times)), output

    pass_seconds, _ = seconds_of(lambda: sums(theta, problem), 7)
    solve_seconds, output = seconds_of(lambda: solve(theta, problem), 3)
    transform = jit(functools.partial(transform_alone, loss))
    transform_seconds, _ = seconds_of(lambda: transform(problem), 7, np.min)  # a floor: its fastest run
    timed = {
        "pass_seconds": pass_seconds,
        "solve_seconds": solve_seconds,
        "steps": int(output[2]),
        "transform_seconds": transform_seconds,
    }
    return timed | pass_bound(lambda t, p: normal_equations(model, loss, t, p), theta, problem, seconds_of)


def transform_alone(loss, problem):
    """(e)'s other floor: the loss's transform (``log1p`` for the log loss) of each of the problem's N × C values,
    alone, over the pass's chunks, summed. A pass applies it to every value the model gives, so it takes at least
    this long at the rate XLA's code computes it here; XLA's flop count calls a ``log1p`` one flop, which it is
    not."""
    import jax
    import jax.numpy as jnp

    from brdffit.fitting.objective.problem import chunks

    def accumulate(total, chunk):
        # model values near the measurements: the transform's cost does not depend on them
        values = 1.01 * chunk.measured
        return total + jnp.sum(loss.transform(values, chunk.measured, chunk.wi[:, 2:3])), None

    return jax.lax.scan(accumulate, jnp.zeros((), problem.measured.dtype), chunks(problem))[0]


def float64_product_rate(size: int = 1024, repeats: int = 5) -> float:
    """The machine's float64 rate (FLOP/s): a ``size``² numpy float64 matrix product (BLAS, on every core), the
    median of ``repeats`` after one to warm up. (``jax.numpy.dot`` of the same arrays computes in float32 unless JAX's
    float64 is on: 143–162 GFLOP/s here, against numpy's ~100 in float64.)"""
    a = np.random.default_rng(0).standard_normal((size, size))
    a @ a
    seconds = []
    for _ in range(repeats):
        began = time.perf_counter()
        a @ a
        seconds.append(time.perf_counter() - began)
    return 2 * size**3 / float(np.median(seconds))


def pass_bound(normal_pass, theta, problem, seconds_of) -> dict:
    """(e)'s lower bound of one normal-equation pass on this machine, the larger of two:

    * the bytes it must read (every array of the problem, once) at the memory's streaming rate, measured here by a
      256 MB numpy sum;
    * its arithmetic at the machine's float64 rate: XLA's count of the flops (``cost_analysis``) of the pass over
      one chunk of samples, times the chunks (XLA counts a loop's body once, so the count is taken on a problem of
      one chunk), at the rate of a float64 matrix product on every core (:func:`float64_product_rate`: no
      elementwise work runs faster; XLA counts a transcendental function as one flop, so the bound is generous).
    """
    import jax

    from brdffit._jax import float64
    from brdffit.fitting.objective.problem import chunk_size

    bytes_read = float(sum(np.asarray(leaf).nbytes for leaf in jax.tree.leaves(problem)))
    stream = np.ones(32 * 2**20)  # 256 MB
    stream_seconds, _ = seconds_of(lambda: stream.sum(), 5)
    bandwidth = stream.nbytes / stream_seconds
    n = problem.wi.shape[0]
    size = chunk_size(n)
    one_chunk = jax.tree.map(lambda leaf: leaf[:size], problem)
    with float64():  # traced as the solver's pass is: float64 (outside brdffit's jit, JAX would make it float32)
        chunk_flops = jax.jit(normal_pass).lower(theta, one_chunk).compile().cost_analysis()
    chunk_flops = (chunk_flops[0] if isinstance(chunk_flops, list) else chunk_flops)["flops"]
    flops = float(chunk_flops) * (n // size)
    rate = float64_product_rate()
    return {
        "pass_bytes": bytes_read,
        "bandwidth_bytes_per_second": bandwidth,
        "pass_flops": flops,
        "flops_per_second": rate,
        "bound_seconds": max(bytes_read / bandwidth, flops / rate),
    }


#: Seeded realistic parameter ranges of the batch benchmarks' materials.
BATCH_MATERIALS = {
    "cook-torrance": lambda rng: {
        "kd": rng.uniform(0.01, 0.4, 3).tolist(),
        "ks": rng.uniform(0.05, 0.6, 3).tolist(),
        "m": float(np.exp(rng.uniform(np.log(0.05), np.log(0.5)))),
        "f0": float(rng.uniform(0.02, 0.9)),
    },
    "ward": lambda rng: {
        "rho_d": rng.uniform(0.02, 0.5, 3).tolist(),
        "rho_s": rng.uniform(0.02, 0.3, 3).tolist(),
        "alpha": float(np.exp(rng.uniform(np.log(0.05), np.log(0.4)))),
    },
}


def batch_data(model_name: str, materials: int, size: int):
    """``materials`` materials of ``model_name`` (seeded, realistic ranges) on one random geometry of ``size``
    pairs, 1% noise."""
    rng = np.random.default_rng(2024)
    wi, wo = data_synth.uniform_random(size, seed=7)
    return [
        data_synth.synthesize(model_name, BATCH_MATERIALS[model_name](rng), wi, wo, noise=0.01, seed=100 + index)
        for index in range(materials)
    ]


def batch_starts(model_name: str, datasets) -> list[dict]:
    """brdffit's data-driven start of each dataset, given to both solvers (computed before the clock)."""
    from brdffit.fitting.objective.problem import build_problems
    from brdffit.fitting.starts.grid import grid_starts, search_subset

    model, loss = get_model(model_name), get_loss(LOSS)
    starts = []
    for samples in datasets:
        subset = search_subset(samples, 0)
        searched = samples if subset is None else samples.select(subset)
        theta = grid_starts(model, loss, 1, build_problems([searched], "float64", 1))[0, 0]
        starts.append(model.dictionary.from_params(model.unconstrained.to_params(theta, samples.n_channels)))
    return starts


def batch(args) -> dict:
    """(b), (j): ``fit_batch`` of many materials (given starts, or its default path: on one thread, on a Dask
    LocalCluster of ``brdffit-dask-N`` workers, or called a second time with its programs compiled), or a loop of
    scipy least_squares from the same starts; compile included but for ``brdffit-default-warm``."""
    import jax

    datasets = batch_data(args.model, args.materials, args.size)
    starts = batch_starts(args.model, datasets) if args.solver in ("brdffit", *SCIPY) else None
    model = get_model(args.model)
    jax.clear_caches()  # the start search above compiled things the clock must not get for free
    cluster = client = None
    if args.solver.startswith("brdffit-dask-"):
        from distributed import Client, LocalCluster

        workers = int(args.solver.rsplit("-", 1)[1])
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    options = dict(start=starts, progress=False, client=client)
    if args.solver == "brdffit-default-1thread":
        options["threads"] = 1
    if args.solver == "brdffit-default-warm":  # the clock times a second call: compiled programs reused
        fit_batch(datasets, args.model, **options)
    clock = time.perf_counter()
    if args.solver.startswith("brdffit"):
        results = fit_batch(datasets, args.model, **options)
        costs = [r.cost for r in results]
        converged = sum(r.converged for r in results)
        steps = [r.n_steps for r in results]
    else:
        method, exact = SCIPY[args.solver]
        outs = [
            scipy_fit(
                args.model,
                samples,
                model.unconstrained.from_params(model.dictionary.to_params(start)),
                method,
                exact,
            )
            for samples, start in zip(datasets, starts, strict=True)
        ]
        costs = [o["cost"] for o in outs]
        converged = sum(o["converged"] for o in outs)
        steps = [o["nfev"] for o in outs]
    seconds = time.perf_counter() - clock
    if cluster is not None:
        client.close()
        cluster.close()
    return {"seconds": seconds, "converged": converged, "costs": costs, "steps": steps, "peak_rss_mb": peak_rss_mb()}


def mcmc(args) -> dict:
    """(f): ``brdffit.sample_posterior`` of the shipped example (fitted first, outside the clock), compile included."""
    import warnings

    from brdffit import MCMC, load_samples, sample_posterior

    samples = load_samples(Path(__file__).resolve().parents[1] / "examples" / "ward-pickled-oak.csv")
    result = fit(samples, "ward")
    clock = time.perf_counter()
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        sampled = sample_posterior(result, samples, MCMC(walkers=args.walkers, steps=args.steps, burn=args.steps // 4))
    seconds = time.perf_counter() - clock
    diagnostics = sampled.uncertainty["diagnostics"]
    return {
        "seconds": seconds,
        "n_samples": samples.n_samples,
        "walkers": args.walkers,
        "steps": args.steps,
        "acceptance": diagnostics["acceptance"],
        "max_autocorr_time": max(diagnostics["autocorr_time"]),
        "evaluations_per_second": args.walkers * args.steps / seconds,
    }


HELD_TRUTH = {"kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5], "m": 0.2, "eta": 1.5}
#: (m)'s fits, in order, all of one dataset in one process: what each holds.
HELD_FITS = (
    ("eta = 1.5, m in [0.01, 1], the first held fit (compiles)", {"fixed": {"eta": 1.5}, "bounds": {"m": [0.01, 1.0]}}),
    ("eta = 1.6", {"fixed": {"eta": 1.6}}),
    ("eta = 1.4", {"fixed": {"eta": 1.4}}),
    ("eta = 1.5, m in [0.1, 0.3]", {"fixed": {"eta": 1.5}, "bounds": {"m": [0.1, 0.3]}}),
    ("kd = [0.1, 0.2, 0.3], eta in [1.2, 2]", {"fixed": {"kd": [0.1, 0.2, 0.3]}, "bounds": {"eta": [1.2, 2.0]}}),
)


def hold(args) -> dict:
    """(m): fits of one dielectric Cook-Torrance dataset (8 × 36 × 36 grid, 1% noise) that hold other values in one
    process, each timed with the XLA compilations it triggered (``jax.monitoring``): a held value is data to the
    compiled solver, so only the first held fit compiles. Beside them, scipy's ``least_squares`` (lm, exact
    Jacobian, float64) with ``eta`` held by a closure over the same residuals, as a scipy user would hold it, from
    the same start (the free fit's optimum with ``m`` at 0.3)."""
    import warnings

    import jax
    import jax.numpy as jnp
    import scipy.optimize

    from brdffit.fitting.objective.problem import build_problem, prepared, residuals

    jax.config.update("jax_enable_x64", True)
    wi, wo = data_synth.hemisphere_grid(8, 36, 36)
    samples = data_synth.synthesize("cook-torrance", HELD_TRUTH, wi, wo, noise=0.01, seed=7, fresnel="dielectric")
    compiled: list[str] = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, duration, **_: compiled.append(event) if "backend_compile" in event else None
    )
    runs = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit(samples, "cook-torrance", fresnel="dielectric")  # the free fit's programs, outside the measurement
        for label, options in HELD_FITS:
            before, clock = len(compiled), time.perf_counter()
            result = fit(samples, "cook-torrance", fresnel="dielectric", **options)
            seconds = time.perf_counter() - clock
            runs.append(
                {"label": label, "seconds": seconds, "compilations": len(compiled) - before, "cost": result.cost}
                | {"steps": result.n_steps, "converged": result.converged}
            )
    model, loss = get_model("cook-torrance", fresnel="dielectric"), get_loss(LOSS)
    n = samples.n_samples
    problem = jax.tree.map(lambda a: a[:n], jax.jit(functools.partial(prepared, loss))(build_problem(samples)))

    def flat(free, eta, data):  # kd (3), ks (3), ln m free; ln(eta - 1) held
        return residuals(model, loss, jnp.concatenate([free, jnp.log(eta - 1.0)[None]]), data).ravel()

    residual, jacobian = jax.jit(flat), jax.jit(jax.jacfwd(flat))
    start = np.log(np.array([0.1, 0.2, 0.3, 0.5, 0.5, 0.5, 0.3]))
    scipy_runs = []
    for eta in (1.5, 1.6, 1.4):
        clock = time.perf_counter()
        out = scipy.optimize.least_squares(
            lambda th, e=eta: np.asarray(residual(jnp.asarray(th), e, problem)),
            start,
            jac=lambda th, e=eta: np.asarray(jacobian(jnp.asarray(th), e, problem)),
            method="lm",
        )
        scipy_runs.append({"eta": eta, "seconds": time.perf_counter() - clock, "cost": 2.0 * float(out.cost)})
    brdffit_runs = []
    for eta in (1.5, 1.6, 1.4):
        clock = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start_params = {"kd": [0.1, 0.2, 0.3], "ks": [0.5, 0.5, 0.5], "m": 0.3, "eta": eta}
            result = fit(samples, "cook-torrance", fresnel="dielectric", start=start_params, fixed={"eta": eta})
        brdffit_runs.append({"eta": eta, "seconds": time.perf_counter() - clock, "cost": result.cost})
    return {
        "seconds": runs[-1]["seconds"],
        "n_samples": n,
        "runs": runs,
        "scipy": scipy_runs,
        "given_start": brdffit_runs,
    }


def merl_load(args) -> dict:
    """(g): ``brdffit.load_samples`` of a full MERL file (written by run.py from a Ward model), fresh process."""
    from brdffit import load_samples

    clock = time.perf_counter()
    samples = load_samples(args.data)
    return {"seconds": time.perf_counter() - clock, "n_samples": samples.n_samples, "peak_rss_mb": peak_rss_mb()}


#: (i): the models rendered, with parameters of real materials (Ngan et al. 2005) and the real tape's 2-lobe fit.
RENDERED = {
    "ward": ({}, {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}),
    "cook-torrance": ({}, {"kd": [0.0187, 0.0145, 0.00961], "ks": [0.3209, 0.2725, 0.1821], "m": 0.258, "f0": 0.0688}),
    "lafortune": (
        {"lobes": 2},
        {
            "rho_d": [0.39],
            "lobes": [
                {"rho_s": [0.27], "cxy": 0.577, "cz": 0.578, "n": 1780.0},
                {"rho_s": [0.47], "cxy": -0.585, "cz": 0.561, "n": 45.2},
            ],
        },
    ),
}


def render(args) -> dict:
    """(i): a 256² lit sphere of a model in a fresh process, compile included (first) and compiled (median of 7)."""
    from brdffit.views.render import render_sphere

    options, params = RENDERED[args.model]
    times = {}
    for lights in ("point", "environment"):
        runs = []
        for _ in range(8):
            clock = time.perf_counter()
            render_sphere(args.model, params, size=256, lights=lights, **options)
            runs.append(time.perf_counter() - clock)
        times[lights] = {"first_seconds": runs[0], "seconds": float(np.median(runs[1:]))}
    return {"model": args.model, "size": 256, "seconds": times["point"]["first_seconds"], **times}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    one = commands.add_parser("merl")
    one.add_argument("--model", required=True)
    one.add_argument("--solver", required=True, choices=["brdffit", "brdffit-default", *SCIPY])
    one.add_argument("--data", required=True)
    one.add_argument("--start", required=True)
    per_step = commands.add_parser("steps")
    per_step.add_argument("--model", required=True)
    per_step.add_argument("--data", required=True)
    per_step.add_argument("--start", required=True)
    many = commands.add_parser("batch")
    many.add_argument("--solver", required=True, choices=[*BATCH_SOLVERS, *SCIPY])
    many.add_argument("--model", default="cook-torrance", choices=list(BATCH_MATERIALS))
    many.add_argument("--materials", type=int, default=100)
    many.add_argument("--size", type=int, default=100_000)
    posterior = commands.add_parser("mcmc")
    posterior.add_argument("--walkers", type=int, default=32)
    posterior.add_argument("--steps", type=int, default=2000)
    loading = commands.add_parser("merl-load")
    loading.add_argument("--data", required=True)
    rendering = commands.add_parser("render")
    rendering.add_argument("--model", required=True, choices=list(RENDERED))
    commands.add_parser("hold")
    args = parser.parse_args()
    commands = {
        "merl": merl,
        "steps": steps,
        "batch": batch,
        "mcmc": mcmc,
        "merl-load": merl_load,
        "render": render,
        "hold": hold,
    }
    output = commands[args.command](args)
    print(json.dumps(output))


if __name__ == "__main__":
    os.environ.setdefault("BRDFFIT_CACHE_DIR", "")
    main()
