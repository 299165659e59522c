"""Into the renderer, measured (issue 28): materials made by Mitsuba 3's own BSDFs, fitted, compared and exported.

    make bench-renderers          # or: .venv/bin/python benchmarks/renderers.py [--materials gold,plastic-ggx]

For each material: Mitsuba 3 (``scalar_rgb``) evaluates its BSDF at a hemisphere of direction pairs (light at 6
zeniths, viewer at 18 zeniths × 24 azimuths: 2,592 pairs, RGB), 1% multiplicative noise is added (seeded); then

* ``brdffit compare`` with its default candidates ranks the models (5-fold cross-validation);
* the best model, and the model that matches Mitsuba's where brdffit has one, are exported to Mitsuba, and Mitsuba
  itself, loading the export, is evaluated at the data's own directions (``brdffit export --samples``);
* the table says, per material and model: the fit's median error at the data, the export's (exact or
  approximate), the export's median brightness (export/data) and the seconds the export took.

What a user is promised: the export, evaluated by the renderer at the data's directions, lies within 1.5% median
of the data (the data's noise is 1%). Needs Mitsuba 3 (``pip install 'brdffit[render]'``). Writes
``benchmarks/results/renderers.json`` and ``renderers.md`` and prints the table.
"""

import argparse
import datetime
import json
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from brdffit import Samples, compare, data_synth, fit  # noqa: E402
from brdffit.data_synth.library import mitsuba_brdf  # noqa: E402
from brdffit.export.at_data import DARK  # noqa: E402
from brdffit.export.mitsuba import mitsuba_bsdf  # noqa: E402

#: The data's noise: 1% of each value, seeded.
NOISE = 0.01
#: The geometry: light zeniths × viewer zeniths × viewer azimuths (``data_synth.hemisphere_grid``).
GEOMETRY = (6, 18, 24)
#: The promise: the export within this median relative error of the data at the data's directions.
PROMISE = 0.015

#: The materials: a name, Mitsuba's plugin dictionary, and brdffit's matching model (a spec), if it has one.
MATERIALS = {
    "gold-ggx": (
        {"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.2},
        "cook-torrance:fresnel=conductor,distribution=ggx,shadowing=smith",
    ),
    "copper-beckmann": (
        {"type": "roughconductor", "material": "Cu", "distribution": "beckmann", "alpha": 0.15},
        "cook-torrance:fresnel=conductor,shadowing=smith",
    ),
    "aluminium-ggx": (
        {"type": "roughconductor", "material": "Al", "distribution": "ggx", "alpha": 0.3},
        "cook-torrance:fresnel=conductor,distribution=ggx,shadowing=smith",
    ),
    "silver-anisotropic": (
        {"type": "roughconductor", "material": "Ag", "distribution": "ggx", "alpha_u": 0.05, "alpha_v": 0.3},
        "cook-torrance:fresnel=conductor,distribution=ggx,shadowing=smith,anisotropic=true",
    ),
    "plastic-ggx": (
        {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": 0.1,
            "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]},
        },
        "roughplastic:distribution=ggx",
    ),
    "plastic-beckmann": (
        {
            "type": "roughplastic",
            "distribution": "beckmann",
            "alpha": 0.3,
            "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.3, 0.5]},
        },
        "roughplastic",
    ),
    "principled": (
        {
            "type": "principled",
            "base_color": {"type": "rgb", "value": [0.6, 0.3, 0.2]},
            "roughness": 0.4,
            "metallic": 0.0,
            "specular": 0.5,
        },
        "principled",
    ),
    "principled-clearcoat": (
        {
            "type": "principled",
            "base_color": {"type": "rgb", "value": [0.2, 0.3, 0.6]},
            "roughness": 0.5,
            "clearcoat": 1.0,
            "clearcoat_gloss": 0.9,
        },
        "principled",
    ),
}


def material_samples(name: str) -> Samples:
    """The material's BRDF made by Mitsuba at the geometry's pairs, with 1% noise (seeded by its position)."""
    plugin, _ = MATERIALS[name]
    wi, wo = data_synth.hemisphere_grid(*GEOMETRY)
    values = mitsuba_brdf(plugin, wi, wo)
    noisy, _ = data_synth.add_noise(values, NOISE, seed=list(MATERIALS).index(name))
    return Samples.from_arrays(wi, wo, noisy, channels=("r", "g", "b"), source=f"Mitsuba 3 {name}")


def median_error(values: np.ndarray, data: np.ndarray) -> float:
    """The median relative error over the values the export's own figure counts (``export/at_data.py``: at least
    its ``DARK``, 10⁻⁴ 1/sr)."""
    counted = data >= DARK
    return float(np.median(np.abs(values[counted] / data[counted] - 1.0)))


def exported_row(name: str, how: str, result, samples: Samples) -> dict:
    """One row: the fit's and its Mitsuba export's error at the data's directions, and the export's time."""
    start = time.perf_counter()
    exported = mitsuba_bsdf(result)
    seconds = time.perf_counter() - start
    at_data = exported.compared_with(result, samples).at_data
    return {
        "material": name,
        "how": how,
        "model": exported.source,
        "fit_median_error": median_error(result.predict(samples.wi, samples.wo), samples.values),
        "export": "exact" if exported.exact else "approximate",
        "export_median_error": at_data.median_error,
        "export_brightness": at_data.brightness,
        "export_seconds": seconds,
        "within_promise": at_data.median_error <= PROMISE,
        "params": result.params,
    }


def measure(name: str) -> list[dict]:
    samples = material_samples(name)
    _, matching = MATERIALS[name]
    start = time.perf_counter()
    comparison = compare(samples, seed=0)
    compare_seconds = time.perf_counter() - start
    rows = [exported_row(name, "compare's best", comparison.best.result, samples)]
    rows[0]["compare_seconds"] = compare_seconds
    if matching is not None:
        model, _, options = matching.partition(":")
        result = fit(samples, model, **dict(option.split("=") for option in options.split(",") if option))
        rows.append(exported_row(name, "matching model", result, samples))
    return rows


def table(rows: list[dict]) -> str:
    lines = [
        "| material | model | how | fit: median error | export | export: median error | export/data | export s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        mark = "" if row["within_promise"] else " ✗"
        lines.append(
            f"| {row['material']} | `{row['model']}` | {row['how']} | {row['fit_median_error']:.2%} |"
            f" {row['export']} | {row['export_median_error']:.2%}{mark} | {row['export_brightness']:.3f} |"
            f" {row['export_seconds']:.1f} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--materials", default=",".join(MATERIALS), help="comma-separated names (default: all)")
    args = parser.parse_args()
    names = [name for name in args.materials.split(",") if name]
    unknown = [name for name in names if name not in MATERIALS]
    if unknown:
        parser.error(f"unknown materials {', '.join(unknown)}; known: {', '.join(MATERIALS)}")
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fits' caveats: the table is the report
        for name in names:
            new = measure(name)
            rows += new
            print("\n".join(table(new).splitlines()[2:]), flush=True)
    text = table(rows)
    print(text)
    results = ROOT / "benchmarks" / "results"
    header = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "machine": platform.processor() or platform.machine(),
        "noise": NOISE,
        "geometry": GEOMETRY,
        "promise": PROMISE,
    }
    (results / "renderers.json").write_text(json.dumps(header | {"rows": rows}, indent=1) + "\n")
    (results / "renderers.md").write_text(f"# Into the renderer ({header['date']})\n\n{text}\n")


if __name__ == "__main__":
    main()
