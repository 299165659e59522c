"""A library of dense isotropic BRDF tables in MERL ``.binary`` format, to learn a BRDF basis from and to hold out.

Each :class:`Material` is either one of brdffit's isotropic analytic models with drawn parameters (``source``
``"brdffit"``, evaluated by :func:`brdffit.physics.evaluate.evaluate`) or one of Mitsuba 3's BSDFs
(``source`` ``"mitsuba"``: ``roughconductor``, ``roughplastic``, ``principled``, the last often with a strong clear
coat, a layered material that no single-lobe analytic model represents). Every material is tabulated at the
1,458,000 bins of a MERL table (Matusik, Pfister, Brand and McMillan, "A data-driven reflectance model",
SIGGRAPH 2003), the data from which a PCA basis of BRDFs is learnt (Matusik et al. 2003; Nielsen, Jensen and
Ramamoorthi, "On optimal, minimal BRDF sampling for reflectance acquisition", SIGGRAPH Asia 2015).

::

    materials = library_materials(50, 40, seed=0)
    write_library("/data/library", materials)  # <name>.binary for each, and library.json

or ``python -m brdffit.data_synth.library OUT_FOLDER --analytic 50 --mitsuba 40 --seed 0``.

Every value is a BRDF in 1/sr without cosine factor (``docs/conventions.md``); ``wi`` points towards the light,
``wo`` towards the viewer.
"""

import argparse
import copy
import json
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from brdffit._files import write_text_atomic
from brdffit.data.merl import FILE_BYTES, HORIZON, N_BINS, bin_directions, write_merl_table
from brdffit.physics.evaluate import evaluate
from brdffit.physics.metals import METALS as METALS_BY_SYMBOL

SOURCES = ("brdffit", "mitsuba")
MANIFEST = "library.json"
#: The list of the run under way (the manifest it will write), so that an interrupted run resumes correctly.
PENDING = ".library-pending.json"
#: Mitsuba's variant: the only one this project relies on (the LLVM variants are not available everywhere).
MITSUBA_VARIANT = "scalar_rgb"
#: Largest diffuse + specular albedo per channel (dimensionless): a plausible, energy-conserving material.
MAX_ALBEDO = 0.9
#: Range of the roughness α (rms slope, dimensionless) of the analytic models' lobes, drawn log-uniformly.
ALPHA_RANGE = (0.03, 0.6)
#: Mitsuba's ``material`` presets for ``roughconductor`` (measured spectral η, k, integrated to RGB by Mitsuba).
METALS = ("Au", "Cu", "Al", "Ag", "Cr", "W")
#: The measured metals (``physics/metals.py``) brdffit's own conductors are drawn near, and how far (a fraction) each
#: channel's ``eta`` and ``k`` may lie from the table's.
MEASURED_METALS = ("Au", "Ag", "Cu", "Al", "Cr", "Ni", "Ti", "Fe")
INDEX_SPREAD = 0.15
#: Share of the Mitsuba materials that are ``principled``; the rest is split between conductors and plastics.
PRINCIPLED_SHARE = 0.45


@dataclass(frozen=True)
class Material:
    """One material of the library.

    ``name``: unique and filename-safe (``ward-007``, ``mitsuba-principled-012``). ``source``: ``"brdffit"`` or
    ``"mitsuba"``. ``kind``: the brdffit model or the Mitsuba plugin. ``parameters`` (JSON-able): for brdffit
    ``{"params": <evaluate's parameter dictionary>, "options": <model options>}``, for Mitsuba
    ``{"bsdf": <the dictionary mi.load_dict takes>}``.
    """

    name: str
    source: str
    kind: str
    parameters: dict[str, Any]

    def __post_init__(self):
        if self.source not in SOURCES:
            raise ValueError(f"material {self.name}: source {self.source!r} is not one of {', '.join(SOURCES)}")

    def values(self, wi, wo) -> np.ndarray:
        """BRDF values (N, 3) in 1/sr, float64, at unit directions ``wi`` (to the light), ``wo`` (to the viewer)
        (N, 3); 0 where either has ``z ≤ 0``."""
        wi, wo = _pairs(wi, wo)
        if self.source == "brdffit":
            return evaluate(self.kind, self.parameters["params"], wi, wo, **self.parameters["options"])
        values = np.zeros((len(wi), 3))
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        values[above] = mitsuba_brdf(self.parameters["bsdf"], wi[above], wo[above])
        return values

    def table(self) -> np.ndarray:
        """The material's MERL table (N_BINS, 3) in 1/sr, in file order; 0 at bins below the horizon."""
        return _tabulate(self, *bin_directions())

    def entry(self, file: str) -> dict[str, Any]:
        """The material's record in the manifest, its table in ``file``."""
        return {
            "name": self.name,
            "file": file,
            "source": self.source,
            "kind": self.kind,
            "parameters": self.parameters,
        }


def _pairs(wi, wo) -> tuple[np.ndarray, np.ndarray]:
    wi, wo = np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64)
    if wi.ndim != 2 or wi.shape[1] != 3 or wi.shape != wo.shape:
        raise ValueError(f"wi and wo must both have shape (N, 3), got {wi.shape} and {wo.shape}")
    return wi, wo


def _tabulate(material: Material, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``material`` at the MERL bins' directions ``wi``, ``wo`` (N_BINS, 3): 0 where either ``z ≤ HORIZON``."""
    table = np.zeros((N_BINS, 3))
    above = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    table[above] = material.values(wi[above], wo[above])
    return table


# ---------------------------------------------------------------------- Mitsuba
def mitsuba():
    """The ``mitsuba`` module, imported on first use, with the :data:`MITSUBA_VARIANT` variant set.

    Raises ImportError with one line when Mitsuba 3 is not installed.
    """
    try:
        import mitsuba as mi
    except ImportError:
        raise ImportError(
            "Mitsuba 3 is not installed (pip install 'brdffit[render]'), so its materials cannot be tabulated;"
            " use --only-analytic"
        ) from None
    if mi.variant() != MITSUBA_VARIANT:
        mi.set_variant(MITSUBA_VARIANT)
    return mi


def mitsuba_brdf(plugin: dict[str, Any], wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The BRDF (N, 3) in 1/sr of the Mitsuba BSDF ``plugin`` (``mi.load_dict``'s dictionary) at upper-hemisphere
    pairs ``wi`` (to the light), ``wo`` (to the viewer) (N, 3).

    Mitsuba's ``bsdf.eval(ctx, si, d)`` is ``f(si.wi, d) · cos θ_d`` (foreshortening included) with ``si.wi``
    the direction the path arrives from (the viewer) and ``d`` the sampled one (the light), as in
    ``tests/export/test_mitsuba.py``; it is divided by ``cos θi = wi_z`` here. Mitsuba computes in float32
    (relative rounding ~1e-6); about 2 µs per pair.
    """
    mi = mitsuba()
    bsdf = mi.load_dict(copy.deepcopy(plugin))
    context, interaction, vector, evaluate_at = mi.BSDFContext(), mi.SurfaceInteraction3f(), mi.Vector3f, bsdf.eval
    values = []
    for light, view in zip(wi.tolist(), wo.tolist(), strict=True):
        interaction.wi = vector(view[0], view[1], view[2])
        value = evaluate_at(context, interaction, vector(light[0], light[1], light[2]))
        values.append((value[0], value[1], value[2]))
    return np.array(values, dtype=np.float64).reshape(-1, 3) / wi[:, 2:3]


# ---------------------------------------------------------------------- drawing parameters
def _number(value: float) -> float:
    """A drawn number as a short JSON-able float (4 decimals)."""
    return round(float(value), 4)


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(math.log(low), math.log(high))))


def _colour(rng: np.random.Generator, low: float, high: float) -> np.ndarray:
    """An RGB albedo: a brightness uniform in [low, high] times a random tint whose largest channel is 1."""
    tint = rng.uniform(0.25, 1.0, 3)
    return rng.uniform(low, high) * tint / tint.max()


def _grey(rng: np.random.Generator, low: float, high: float) -> np.ndarray:
    return np.full(3, rng.uniform(low, high))


def _diffuse_beside(rng: np.random.Generator, specular: np.ndarray, low: float = 0.02) -> np.ndarray:
    """A coloured diffuse albedo that keeps diffuse + ``specular`` within :data:`MAX_ALBEDO` in every channel."""
    room = MAX_ALBEDO - specular.max()
    return _colour(rng, min(low, room), room)


def _rgb(values: np.ndarray) -> list[float]:
    return [_number(value) for value in values]


def _lobe_albedos(rng: np.random.Generator, low: float, high: float) -> tuple[list[float], list[float]]:
    """``(rho_d, rho_s)``: a grey (dielectric) or, one time in four, coloured (metallic) specular albedo in
    [low, high] and a coloured diffuse one beside it."""
    specular = _colour(rng, low, high) if rng.random() < 0.25 else _grey(rng, low, high)
    return _rgb(_diffuse_beside(rng, specular)), _rgb(specular)


def _alpha(rng: np.random.Generator) -> float:
    return _number(_log_uniform(rng, *ALPHA_RANGE))


def _ward(rng: np.random.Generator) -> tuple[dict, dict]:
    """Ward 1992 (isotropic): α log-uniform in :data:`ALPHA_RANGE`, specular albedo 0.02–0.35."""
    rho_d, rho_s = _lobe_albedos(rng, 0.02, 0.35)
    return {"rho_d": rho_d, "rho_s": rho_s, "alpha": _alpha(rng)}, {}


def _half_vector_exponent(alpha: float) -> float:
    """The Blinn-Phong exponent of a lobe of rms slope ``alpha``: ``n = 2/α² − 2`` (Walter et al., EGSR 2007)."""
    return 2.0 / alpha**2 - 2.0


def _blinn_phong(rng: np.random.Generator) -> tuple[dict, dict]:
    """Normalised Blinn-Phong: ``n = 2/α² − 2`` for α log-uniform in :data:`ALPHA_RANGE` (n ≈ 3.6–2,200)."""
    rho_d, rho_s = _lobe_albedos(rng, 0.02, 0.4)
    return {"rho_d": rho_d, "rho_s": rho_s, "n": _number(_half_vector_exponent(_alpha(rng)))}, {}


def _phong(rng: np.random.Generator) -> tuple[dict, dict]:
    """Modified Phong: the mirror-direction lobe is about twice as wide in angle as the half-vector one, so
    ``n = (2/α² − 2)/4`` (at least 1) for α log-uniform in :data:`ALPHA_RANGE`."""
    rho_d, rho_s = _lobe_albedos(rng, 0.02, 0.4)
    return {"rho_d": rho_d, "rho_s": rho_s, "n": _number(max(1.0, _half_vector_exponent(_alpha(rng)) / 4))}, {}


def _lafortune_lobe(rng: np.random.Generator, retro: bool, albedo: float) -> dict:
    """One Lafortune 1997 lobe: ``cz/|cxy|`` in [0.7, 1.1] (a forward lobe tilted a little towards grazing, as
    Fresnel tilts real ones), or for ``retro`` a broad retro-reflective lobe; ``2 cxy² + cz² = 1``."""
    ratio = rng.uniform(0.7, 1.1)
    size = math.sqrt(2.0 + ratio**2)
    cxy = (1.0 if retro else -1.0) / size
    n = _log_uniform(rng, 2.0, 30.0) if retro else _log_uniform(rng, 5.0, 500.0)
    return {
        "rho_s": _rgb(_grey(rng, 0.5 * albedo, albedo)),
        "cxy": _number(cxy),
        "cz": _number(ratio / size),
        "n": _number(n),
    }


def _lafortune(rng: np.random.Generator) -> tuple[dict, dict]:
    """Lafortune 1997: a forward lobe and, half the time, a weaker retro-reflective one."""
    lobes = [_lafortune_lobe(rng, retro=False, albedo=0.35)]
    if rng.random() < 0.5:
        lobes.append(_lafortune_lobe(rng, retro=True, albedo=0.1))
    specular = np.sum([lobe["rho_s"] for lobe in lobes], axis=0)
    return {"rho_d": _rgb(_diffuse_beside(rng, specular)), "lobes": lobes}, {"lobes": len(lobes)}


def _microfacet_options(rng: np.random.Generator, fresnel: str) -> dict:
    distribution = ("beckmann", "ggx")[int(rng.integers(2))]
    shadowing = ("smith", "smith-correlated", "v-groove")[int(rng.integers(3))]
    return {"fresnel": fresnel, "distribution": distribution, "shadowing": shadowing}


def _cook_torrance_dielectric(rng: np.random.Generator) -> tuple[dict, dict]:
    """A plastic or paint: exact dielectric Fresnel with η in [1.3, 1.8] (F ≈ 2–8% at normal incidence), grey
    ``ks`` in [0.5, 1] (the lobe's albedo is ``ks·F``), coloured ``kd`` up to 0.8."""
    params = {
        "kd": _rgb(_colour(rng, 0.02, 0.8)),
        "ks": _rgb(_grey(rng, 0.5, 1.0)),
        "m": _alpha(rng),
        "eta": _number(rng.uniform(1.3, 1.8)),
    }
    return params, _microfacet_options(rng, "dielectric")


def _cook_torrance_conductor(rng: np.random.Generator) -> tuple[dict, dict]:
    """A metal as a renderer holds one: exact conductor Fresnel with a complex index per channel, ``ks`` 1 (the
    metal's colour is its index's), the RGB ``eta`` and ``k`` of one of :data:`MEASURED_METALS` each scaled by a
    factor in [1 − :data:`INDEX_SPREAD`, 1 + :data:`INDEX_SPREAD`] (an alloy, an oxide film: not the table's value a
    fit starts from), and a little grey ``kd`` (dust, ≤ 0.05 and ≤ what the normal-incidence reflectance leaves)."""
    metal = METALS_BY_SYMBOL[MEASURED_METALS[int(rng.integers(len(MEASURED_METALS)))]]
    eta = np.asarray(metal.eta_rgb) * rng.uniform(1.0 - INDEX_SPREAD, 1.0 + INDEX_SPREAD, 3)
    k = np.asarray(metal.k_rgb) * rng.uniform(1.0 - INDEX_SPREAD, 1.0 + INDEX_SPREAD, 3)
    normal_reflectance = ((eta - 1.0) ** 2 + k**2) / ((eta + 1.0) ** 2 + k**2)
    params = {
        "kd": _rgb(_grey(rng, 0.0, min(0.05, 1.0 - float(normal_reflectance.max())))),
        "ks": _rgb(np.ones(3)),
        "m": _alpha(rng),
        "eta": _rgb(eta),
        "k": _rgb(k),
    }
    return params, _microfacet_options(rng, "conductor")


def _cook_torrance_schlick(rng: np.random.Generator) -> tuple[dict, dict]:
    """Schlick's Fresnel: half dielectric-like (f0 in [0.02, 0.08], grey ``ks``, coloured ``kd``), half
    metal-like (f0 in [0.5, 0.95], coloured ``ks``, little ``kd``)."""
    if rng.random() < 0.5:
        kd, ks, f0 = _colour(rng, 0.02, 0.8), _grey(rng, 0.5, 1.0), rng.uniform(0.02, 0.08)
    else:
        kd, ks, f0 = _grey(rng, 0.0, 0.05), _colour(rng, 0.4, 0.85), rng.uniform(0.5, 0.95)
    params = {"kd": _rgb(kd), "ks": _rgb(ks), "m": _alpha(rng), "f0": _number(f0)}
    return params, _microfacet_options(rng, "schlick")


def _ward_duer(rng: np.random.Generator) -> tuple[dict, dict]:
    """Ward with Dür's 2006 normalisation: as :func:`_ward`."""
    return _ward(rng)


#: The analytic recipes, in the order the library cycles through them: (model, recipe name, draw).
ANALYTIC_RECIPES: tuple[tuple[str, str, Callable[[np.random.Generator], tuple[dict, dict]]], ...] = (
    ("ward", "ward", _ward),
    ("cook-torrance", "dielectric", _cook_torrance_dielectric),
    ("blinn-phong", "blinn-phong", _blinn_phong),
    ("cook-torrance", "conductor", _cook_torrance_conductor),
    ("lafortune", "lafortune", _lafortune),
    ("cook-torrance", "schlick", _cook_torrance_schlick),
    ("phong", "phong", _phong),
    ("cook-torrance", "dielectric", _cook_torrance_dielectric),
    ("ward-duer", "ward-duer", _ward_duer),
    ("cook-torrance", "conductor", _cook_torrance_conductor),
)


def _rgb_spectrum(values: np.ndarray) -> dict:
    return {"type": "rgb", "value": _rgb(values)}


def _roughconductor(rng: np.random.Generator, index: int) -> dict:
    """Mitsuba's ``roughconductor``: every fourth an RGB η in [0.2, 2.5] and k in [2, 6], the others the measured
    :data:`METALS` presets in turn; α log-uniform in [0.05, 0.5]; Beckmann and GGX in turn."""
    plugin: dict[str, Any] = {"type": "roughconductor", "distribution": ("beckmann", "ggx")[index % 2]}
    if index % 4 == 3:
        plugin["eta"] = _rgb_spectrum(rng.uniform(0.2, 2.5, 3))
        plugin["k"] = _rgb_spectrum(rng.uniform(2.0, 6.0, 3))
    else:
        plugin["material"] = METALS[(index - index // 4) % len(METALS)]
    plugin["alpha"] = _number(_log_uniform(rng, 0.05, 0.5))
    return plugin


def _roughplastic(rng: np.random.Generator, index: int) -> dict:
    """Mitsuba's ``roughplastic``: coloured diffuse reflectance up to 0.85 under a rough dielectric coat of
    index 1.3–1.7, α log-uniform in [0.05, 0.4], Beckmann and GGX in turn; a third ``nonlinear`` (Mitsuba's
    internal-scattering colour shift)."""
    return {
        "type": "roughplastic",
        "distribution": ("beckmann", "ggx")[index % 2],
        "diffuse_reflectance": _rgb_spectrum(_colour(rng, 0.02, 0.85)),
        "alpha": _number(_log_uniform(rng, 0.05, 0.4)),
        "int_ior": _number(rng.uniform(1.3, 1.7)),
        "nonlinear": bool(rng.random() < 1 / 3),
    }


def _principled(rng: np.random.Generator, index: int) -> dict:
    """Mitsuba's ``principled`` (Burley, "Physically-based shading at Disney", 2012), isotropic: metallic 0 (60%),
    1 (25%) or in between, specular 0.2–0.8, sheen (0.2–1) on every fourth.

    Two in three have a strong clear coat (``clearcoat`` 0.5–1, ``clearcoat_gloss`` 0.6–0.97) over a rough base
    (roughness 0.3–0.8, GGX α = roughness² ≈ 0.09–0.64): the coat is a GTR1 lobe of α = lerp(0.1, 0.001, gloss)
    ≈ 0.04–0.004 (a peak ≈ 0.15–18 1/sr above the base at normal incidence; Mitsuba 3 weighs it by ``clearcoat``
    alone, without Disney's factor 1/4), the layered look of car paints that one analytic lobe cannot fit. The
    others have roughness 0.1–0.8.
    """
    coated = index % 3 != 2
    draw = rng.random()
    metallic = 0.0 if draw < 0.6 else 1.0 if draw < 0.85 else rng.uniform(0.2, 0.8)
    plugin: dict[str, Any] = {
        "type": "principled",
        "base_color": _rgb_spectrum(_colour(rng, 0.03, 0.9)),
        "roughness": _number(rng.uniform(0.3 if coated else 0.1, 0.8)),
        "metallic": _number(metallic),
        "specular": _number(rng.uniform(0.2, 0.8)),
        "anisotropic": 0.0,
    }
    if index % 4 == 3:
        plugin["sheen"] = _number(rng.uniform(0.2, 1.0))
        plugin["sheen_tint"] = _number(rng.uniform(0.0, 1.0))
    if coated:
        plugin["clearcoat"] = _number(rng.uniform(0.5, 1.0))
        plugin["clearcoat_gloss"] = _number(rng.uniform(0.6, 0.97))
    return plugin


#: Mitsuba plugins and how to draw one; ``index`` counts the plugin's materials.
MITSUBA_RECIPES: dict[str, Callable[[np.random.Generator, int], dict]] = {
    "principled": _principled,
    "roughconductor": _roughconductor,
    "roughplastic": _roughplastic,
}


def mitsuba_split(n_mitsuba: int) -> dict[str, int]:
    """How many of each Mitsuba plugin ``n_mitsuba`` materials hold: :data:`PRINCIPLED_SHARE` principled
    (rounded), the rest split between roughconductor and roughplastic (conductors take the odd one)."""
    principled = round(PRINCIPLED_SHARE * n_mitsuba)
    conductors = (n_mitsuba - principled + 1) // 2
    return {"principled": principled, "roughconductor": conductors, "roughplastic": n_mitsuba - principled - conductors}


def _generator(seed: int, stream: int, index: int) -> np.random.Generator:
    """The generator of one material: ``default_rng((seed, stream, index))``, so a material depends only on the
    seed, its recipe and its place among that recipe's materials (a smaller library is a prefix of a larger)."""
    return np.random.default_rng((seed, stream, index))


def library_materials(n_analytic: int, n_mitsuba: int, seed: int = 0) -> list[Material]:
    """A deterministic, varied library: ``n_analytic`` brdffit materials cycling through
    :data:`ANALYTIC_RECIPES`, then ``n_mitsuba`` Mitsuba materials split by :func:`mitsuba_split`.

    Names: ``<model>-NNN`` (numbered per model) and ``mitsuba-<plugin>-NNN``.
    """
    if n_analytic < 0 or n_mitsuba < 0 or seed < 0:
        raise ValueError(f"counts and seed must be ≥ 0, got {n_analytic}, {n_mitsuba}, {seed}")
    materials: list[Material] = []
    counts: dict[str, int] = {}
    for position in range(n_analytic):
        model, _, draw = ANALYTIC_RECIPES[position % len(ANALYTIC_RECIPES)]
        params, options = draw(_generator(seed, position % len(ANALYTIC_RECIPES), position // len(ANALYTIC_RECIPES)))
        number = counts[model] = counts.get(model, -1) + 1
        materials.append(Material(f"{model}-{number:03d}", "brdffit", model, {"params": params, "options": options}))
    for stream, (plugin, count) in enumerate(mitsuba_split(n_mitsuba).items(), start=len(ANALYTIC_RECIPES)):
        draw_bsdf = MITSUBA_RECIPES[plugin]
        for index in range(count):
            bsdf = draw_bsdf(_generator(seed, stream, index), index)
            materials.append(Material(f"mitsuba-{plugin}-{index:03d}", "mitsuba", plugin, {"bsdf": bsdf}))
    return materials


# ---------------------------------------------------------------------- writing
def write_library(folder: str | os.PathLike, materials: list[Material], *, progress: bool = True) -> list[dict]:
    """Write ``<name>.binary`` (a MERL table, :func:`brdffit.data.merl.write_merl_table`) for each material into
    ``folder`` (created if needed), then the manifest ``library.json``, atomically: a JSON list of
    ``{name, file, source, kind, parameters}``, which it returns.

    Resuming: a table already there with a MERL file's size is kept when the previous run's list (``library.json``,
    or ``.library-pending.json`` while a run is under way) gives it the same parameters, or when the folder has no
    list at all; other tables are written again. Every file is written atomically, so an interrupted run resumes
    where it stopped. ``progress``: one line per material on stdout, with its time.
    """
    names = [material.name for material in materials]
    if len(set(names)) != len(names):
        raise ValueError("material names must be unique")
    if any(material.source == "mitsuba" for material in materials):
        mitsuba()  # a missing Mitsuba fails now, before any table is written
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    entries = [material.entry(f"{material.name}.binary") for material in materials]
    _start_run(folder, entries)
    directions: tuple[np.ndarray, np.ndarray] | None = None  # the bins' (wi, wo), made on first need
    for position, (material, entry) in enumerate(zip(materials, entries, strict=True), start=1):
        path = folder / entry["file"]
        start = time.perf_counter()
        if path.is_file() and path.stat().st_size == FILE_BYTES:
            done = "kept (already written)"
        else:
            if directions is None:
                directions = bin_directions()
            write_merl_table(_tabulate(material, *directions), path)
            done = f"{time.perf_counter() - start:6.2f} s"
        if progress:
            print(f"[{position:3d}/{len(materials)}] {material.name:28s} {material.kind:14s} {done}", flush=True)
    write_text_atomic(folder / MANIFEST, _json(entries))
    (folder / PENDING).unlink()
    return entries


def _json(entries: list[dict]) -> str:
    return json.dumps(entries, indent=1) + "\n"


def _start_run(folder: Path, entries: list[dict]) -> None:
    """Remove the tables in ``folder`` that the previous run's list does not give ``entries``' parameters, and
    ``library.json`` unless it is ``entries``; then record ``entries`` in ``.library-pending.json``."""
    previous = None
    for name in (PENDING, MANIFEST):
        if (folder / name).is_file():
            previous = {entry["name"]: entry for entry in json.loads((folder / name).read_text(encoding="utf-8"))}
            break
    if previous is not None:
        for entry in entries:
            if previous.get(entry["name"]) != entry:
                (folder / entry["file"]).unlink(missing_ok=True)
    manifest = folder / MANIFEST
    if manifest.is_file() and manifest.read_text(encoding="utf-8") != _json(entries):
        manifest.unlink()
    write_text_atomic(folder / PENDING, _json(entries))


# ---------------------------------------------------------------------- command line
def main(argv: list[str] | None = None) -> int:
    """``python -m brdffit.data_synth.library OUT_FOLDER [--analytic N] [--mitsuba N] [--seed S] [--only-analytic]``."""
    parser = argparse.ArgumentParser(
        prog="python -m brdffit.data_synth.library", description="Write a library of MERL BRDF tables and its manifest."
    )
    parser.add_argument("folder", metavar="OUT_FOLDER", help="where the tables and library.json go")
    parser.add_argument("--analytic", type=int, default=50, metavar="N", help="brdffit materials (default 50)")
    parser.add_argument("--mitsuba", type=int, default=40, metavar="N", help="Mitsuba materials (default 40)")
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the parameters (default 0)")
    parser.add_argument("--only-analytic", action="store_true", help="no Mitsuba materials (--mitsuba 0)")
    arguments = parser.parse_args(argv)
    try:
        materials = library_materials(
            arguments.analytic, 0 if arguments.only_analytic else arguments.mitsuba, arguments.seed
        )
        start = time.perf_counter()
        write_library(arguments.folder, materials)
    except (ImportError, ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    size = sum(path.stat().st_size for path in Path(arguments.folder).glob("*.binary"))
    print(
        f"{len(materials)} materials in {arguments.folder} ({size / 1e9:.2f} GB), {time.perf_counter() - start:.0f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
