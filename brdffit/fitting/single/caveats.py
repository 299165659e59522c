"""What a user must know before trusting a fit, one line each: the result's ``fit.warnings``.

* the samples as read are not reciprocal (``data/reciprocity.py``): their quantity is probably wrong (named as the
  file's header's mistake where the header said it);
* a lobe contributes less than :data:`DEAD_SHARE` of the model at every sample: it fits nothing;
* a parameter lies beyond its plausible range (``physics/domains.py``: a roughness above 2, an exponent
  above 10⁴, an albedo above 1, a dielectric index within 10⁻⁶ of 1), or a bounded one (Schlick's ``f0``)
  ends on an end of its domain: the optimum is against the bound;
* the model's directional albedo exceeds 1 at some incidence: it reflects more light than it receives (one line
  per channel);
* a fit with more lobes ends worse than one with fewer: it stopped in a local minimum;
* an anisotropic model fitted to data whose every direction lies in one plane of incidence: the data cannot
  determine its anisotropy (an anisotropic Cook-Torrance lobe's tangent azimuth ``phi_t``, named; a freed one of an
  isotropic model's, ``Lobe.anisotropy_names``, alike);
* a clear coat fitted to data of one incidence: the data cannot tell it from the base's lobe;
* a sheen fitted to data of one incidence near the normal: the data cannot tell it from the base.
"""

import functools
import re
from collections.abc import Sequence
from dataclasses import replace
from typing import NamedTuple, TypeGuard

import jax
import jax.numpy as jnp
import numpy as np

from ..._jax import float64
from ..._programs import jit
from ...data.reciprocity import Reciprocity, ReciprocityAhead, header_contradiction, reciprocity
from ...data.samples import Samples
from ...physics.domains import Positive, UnitInterval
from ...physics.geometry import NORMAL, above_horizon, mirror_direction, spherical_to_direction
from ...physics.models.model import LobeModel, Model
from ...physics.models.params import Params, albedo_size, lobe_family
from ..objective.problem import padded_size, stacked_directions

#: A lobe whose share of the model stays below this at every sample and channel contributes nothing.
DEAD_SHARE = 1e-3
#: The lobes' shares are screened at this many samples of a larger dataset (drawn with a seed, :func:`_screened_at`):
#: a lobe whose share reaches :data:`DEAD_SHARE` at one of them contributes; only a dataset where some lobe stays
#: under it there is looked at whole (:func:`_confirmed_shares`). A MERL-size fit's caveats then no longer copy its
#: 1.4 million pairs of directions for the screen (~0.1 s) nor pass over them (~0.08 s). A power of two: a bucket's
#: datasets are all of at most this many samples or all of more (``problem.padded_size``).
SHARE_SAMPLES = 2**12
#: A parameter of a bounded domain this close to one of its ends ended against it.
EDGE = 1e-6
#: Incidence zeniths (degrees) at which the directional albedo is checked.
ALBEDO_INCIDENCE = (0.0, 30.0, 60.0, 80.0)
#: A directional albedo counts as above 1 beyond this (quadrature rounds), and only where two grids agree.
ALBEDO_LIMIT = 1.005
#: The screening grid's n (n × 2n viewing directions per incidence), and the bound (``_refined``) below which
#: the fine grid is not evaluated: 5% under the limit, for the bound's own guesswork.
SCREEN_GRID = 64
SCREEN_BELOW = 0.95
#: The first screen's n: a grid 16 times cheaper than :data:`SCREEN_GRID`'s, which clears most fitted materials
#: (every texel of the spatially varying benchmark's Ward capture); only what it leaves open pays for the second.
FIRST_SCREEN_GRID = 16
#: The screen's allowance for a lobe its grid samples too sparsely: the BRDF's peak over this many cells.
SCREEN_PEAK_CELLS = 16
#: Directions whose azimuths all lie within this many degrees of one plane through the normal lie in that plane
#: (a gonioreflectometer's in-plane scan, with its positioning jitter).
IN_PLANE_DEGREES = 0.5
#: One incidence within this many degrees of the normal cannot determine a sheen (``_sheen_undetermined``).
SHEEN_NORMAL_DEGREES = 10.0


@float64
def caveats(
    model: Model,
    samples: Samples,
    params: Params,
    cost: float | None = None,
    fewer_lobes_cost: float | None = None,
    *,
    screened: "Screened | None" = None,
    held: frozenset[str] = frozenset(),
    reciprocal: ReciprocityAhead | None = None,
) -> list[str]:
    """Every caveat of ``model`` fitted to ``samples`` with ``params`` (numpy), ``cost`` its Σr²;
    ``fewer_lobes_cost``: the cost the same model with one lobe less reached on the same samples;
    ``screened``: what :func:`screen_bucket` found for this fit, when the caller screened many fits at once;
    ``reciprocal``: the reciprocity of ``samples`` when the caller started its check earlier (``ReciprocityAhead``)."""
    found = _not_reciprocal(reciprocity(samples) if reciprocal is None else reciprocal.result())
    found += _anisotropy_undetermined(model, samples, held)
    found += _coat_undetermined(model, samples, held) + _sheen_undetermined(model, samples, held)
    checked = as_fitted(model, params)
    if checked is not model:  # screened by the caller as the isotropic model its fit is not: again, as it is
        model, screened = checked, None
    if not isinstance(model, LobeModel):  # no lobes to share the model, none peaked at the mirror to screen
        screened = Screened(ALBEDO_INCIDENCE, np.zeros(0))
    elif screened is None:
        (screened,) = screen_bucket(model, [params], [samples], 1)
    if isinstance(model, LobeModel):  # the data-driven kind has no lobes (its shares are none)
        found += _dead_lobes(model, params, screened.lobe_shares)
    found += _implausible(model, params, samples.channels, held)
    found += _albedo_above_one(model, params, samples.channels, screened.albedo_open)
    worse = cost is not None and fewer_lobes_cost is not None and cost > fewer_lobes_cost * (1 + 1e-9)
    if worse and isinstance(model, LobeModel):  # fewer lobes: only a lobe model has them
        found.append(
            f"the fit ends at cost {cost:.6g}, worse than the {fewer_lobes_cost:.6g} of {model.n_lobes - 1} lobe(s):"
            " it stopped in a local minimum"
        )
    return found


def lobe_name(model: LobeModel, params: Params, k: int) -> str:
    """How a message names lobe ``k``: ``lobe 2 (cxy +0.577, cz 0.577, n 1.8e+03)``, or the specular lobe."""
    if not model.lobes_as_list:
        return f"the specular lobe ({model.specular_name})"
    shape = ", ".join(f"{name} {float(params.shape[name][k]):.3g}" for name in lobe_family(model).names)
    return f"lobe {k + 1} ({shape})"


def _not_reciprocal(found: Reciprocity | None) -> list[str]:
    """The caveat of samples whose values as read are not reciprocal, from what their check found."""
    if found is None or found.reciprocal:
        return []
    advice = f"read them with --quantity {found.best} (quantity='{found.best}' in Python)"
    if found.header_contradicted and found.in_force == found.header:
        return [f"{header_contradiction(found)}: {advice}"]
    return [
        f"the samples as read ({found.in_force}) are not reciprocal: over {found.pairs} reciprocal pairs the median"
        f" of f(a→b)/f(b→a) is {found.as_read:.3g}; read as {found.best} it is {found.ratios[found.best]:.3g}"
        f": {advice}"
    ]


def as_fitted(model: Model, params: Params) -> Model:
    """``model`` as its fit with ``params`` (numpy) is checked: an isotropic model whose lobe's anisotropy
    (``Lobe.anisotropy_names``: glTF's) lies off the values the model holds it at (a user freed it, or fixed it
    elsewhere) as the anisotropic model it then is, whose albedo the screens compute without an isotropic model's
    shortcuts (:func:`_model_quadrature`: half the grid, one azimuth at normal incidence); else ``model`` itself."""
    if not isinstance(model, LobeModel) or not model.isotropic or model.lobe is None:
        return model
    defaults = dict(model.held)
    names = model.lobe.anisotropy_names
    if all(np.all(np.asarray(params.shape[name]) == defaults.get(name)) for name in names):
        return model
    return replace(model, isotropic=False)


def _anisotropy_undetermined(model: Model, samples: Samples, held: frozenset[str] = frozenset()) -> list[str]:
    """An anisotropic lobe model fitted to directions that all lie in one plane of incidence: such data see the lobe
    in that plane alone, where a tangent and its mirror image about the plane look alike and the two roughnesses
    enter only in combination. An isotropic model whose lobe's anisotropy the fit freed (``Lobe.anisotropy_names``,
    not ``held``) is one."""
    if not isinstance(model, LobeModel) or model.lobe is None:
        return []
    anisotropy = model.lobe.anisotropy_names
    if model.isotropic and all(name in held for name in anisotropy):
        return []
    plane = _plane_of_incidence(np.concatenate([samples.wi, samples.wo]))
    if plane is None:
        return []
    names = model.lobe.names
    if "phi_t" in names:
        what = "phi_t, the tangent's azimuth (its mirror image about that plane fits alike), nor alpha_u, alpha_v apart"
    else:
        what = f"its anisotropy ({', '.join(anisotropy or names)})"
    return [
        f"every direction lies in one plane of incidence (azimuth {plane:.3g}°): the data cannot determine {what};"
        " measure out of that plane, or fit an isotropic model"
    ]


def _coat_undetermined(model: Model, samples: Samples, held: frozenset[str]) -> list[str]:
    """A clear coat fitted (``principled``'s or ``gltf``'s ``clearcoat``, not held) to data of one incidence: the coat
    and the base's specular lobe are told apart by how each changes with the incidence (the coat's Fresnel term and
    its own narrow shape), which one incidence does not show."""
    if not isinstance(model, LobeModel) or model.lobe is None or "clearcoat" not in model.lobe.names:
        return []
    if "clearcoat" in held:
        return []
    incidences, _ = samples.light_directions()
    if len(incidences) > 1:
        return []
    theta = float(np.degrees(np.arccos(np.clip(incidences[0, 2], -1.0, 1.0))))
    coat = [name for name in model.lobe.names if name.startswith("clearcoat")]  # the coat's weight and its shape
    return [
        f"every sample has one incidence (θi = {theta:.3g}°): the data cannot tell {' and '.join(coat)}"
        " from the base's specular lobe; measure more incidences, or hold the coat (--fix clearcoat=0)"
    ]


def _sheen_undetermined(model: Model, samples: Samples, held: frozenset[str]) -> list[str]:
    """A sheen fitted (``gltf``'s ``sheen_color``, not held) to data of one incidence within
    :data:`SHEEN_NORMAL_DEGREES` of the normal: lit along the normal, an isotropic material is one curve of ``θo``,
    which the sheen and the base's diffuse and specular terms trace alike. Measured (velvet: sheen 0.5 of roughness 0.5
    over a base of roughness 0.8, one in-plane scan of 45 viewers, 1% noise): lit at 5° from the normal the fitted
    sheen colour is off by up to 60%; at 10°, 6%; at 20°, 4%; at 45°, 1% — one incidence away from the normal
    determines it, an in-plane one included, as do directions all within 60° of the normal."""
    if not isinstance(model, LobeModel) or model.lobe is None or "sheen_color" not in model.lobe.names:
        return []
    if "sheen_color" in held:
        return []
    incidences, _ = samples.light_directions()
    theta = float(np.degrees(np.arccos(np.clip(incidences[0, 2], -1.0, 1.0))))
    if len(incidences) > 1 or theta > SHEEN_NORMAL_DEGREES:
        return []
    sheen = [name for name in model.lobe.names if name.startswith("sheen_")]
    return [
        f"every sample has one incidence, θi = {theta:.3g}° (within {SHEEN_NORMAL_DEGREES:g}° of the normal): the"
        f" data cannot tell {' and '.join(sheen)} from the base; measure at an incidence farther from the normal, or"
        " hold the sheen (its default)"
    ]


def _plane_of_incidence(directions: np.ndarray) -> float | None:
    """The azimuth (degrees, in [0, 180)) of the one plane through the normal that holds every direction (N, 3)
    within :data:`IN_PLANE_DEGREES`, or None where there is none; directions along the normal lie in every plane."""
    horizontal = directions[:, :2]
    length = np.hypot(horizontal[:, 0], horizontal[:, 1])
    horizontal = horizontal[length > 1e-9] / length[length > 1e-9, None]
    if not len(horizontal):
        return None
    # The plane's direction: the principal axis of the horizontal unit vectors (a line: u and −u alike).
    axis = np.linalg.eigh(horizontal.T @ horizontal)[1][:, -1]
    off = np.abs(horizontal[:, 0] * axis[1] - horizontal[:, 1] * axis[0])  # |sin| of each one's angle to the plane
    if np.max(off) > np.sin(np.radians(IN_PLANE_DEGREES)):
        return None
    return float(np.degrees(np.arctan2(axis[1], axis[0])) % 180.0)


def _dead_lobes(model: LobeModel, params: Params, shares: np.ndarray) -> list[str]:
    """The lobes whose largest ``shares`` (K,) of the model stay under :data:`DEAD_SHARE`."""
    return [
        f"{lobe_name(model, params, k)} contributes less than {DEAD_SHARE:.1%} of the model at every sample"
        f" (at most {share:.2g}): it fits nothing; fit with one lobe less"
        for k, share in enumerate(shares)
        if share < DEAD_SHARE
    ]


@jit(static_argnums=0)
def _lobe_shares(model: LobeModel, params: Params, wi, wo, real):
    """Each lobe's largest share of the model over the samples (those ``real``, (N,) bool) and channels, (K,)."""
    if not model.n_lobes:
        return jnp.zeros(0)
    visible, wi, wo = above_horizon(wi, wo)
    lobes = model.lobe_values(params.shape, wi, wo)  # (K, N), or (K, N, C) with per-channel shape parameters
    contributions = (lobes if lobes.ndim == 3 else lobes[:, :, None]) * params.specular[:, None, :]  # (K, N, C)
    total = model.diffuse({}, wi, wo)[:, None] * params.diffuse + contributions.sum(axis=0)
    share = contributions / jnp.maximum(total, jnp.finfo(total.dtype).tiny)
    return (share * (visible & real)[None, :, None]).max(axis=(1, 2))


def _implausible(
    model: Model, params: Params, channels: tuple[str, ...], held: frozenset[str] = frozenset()
) -> list[str]:
    """A line for each parameter on an end of its domain or beyond its plausible range; not for those ``held`` (the
    fit did not move them) nor those whose ends are values of their own (``Lobe.meaningful_ends``)."""
    values = np.asarray(model.physical.from_params(params))
    table = _domain_table(model, channels)
    on_end = (table.unit_interval & (np.minimum(values, 1.0 - values) < EDGE)) | (table.zero_end & (values < EDGE))
    suspect = table.checked & (on_end | (values > table.high) | (values < table.low))
    if not suspect.any():  # the common case, decided for every parameter at once
        return []
    found = []
    for index in np.flatnonzero(suspect):
        label, name, domain, value = table.labels[index], table.names[index], table.domains[index], values[index]
        if name in held:
            continue
        low, high = domain.plausible
        if on_end[index]:
            found.append(
                f"{label} = {value:.10g} lies on an end of its domain {domain.text}: the fit ended against the bound,"
                " where the model may not describe the data"
            )
        elif value > high:
            found.append(f"{label} = {value:.4g} is beyond its plausible range (≤ {high:g})")
        else:
            found.append(f"{label} = {value:.10g} is below its plausible range (≥ {low:.10g})")
    return found


class DomainTable(NamedTuple):
    """What :func:`_implausible` checks of each entry of a model's physical vector (``labels`` order): its label,
    its name without a channel (``specular_reflectance[r]`` → ``specular_reflectance``), its domain, its plausible
    range (``low``, ``high``), whether it is checked at all (not a parameter whose ends are values of their own),
    whether its domain is the unit interval, and whether its lower end is 0 as an end of the fit (``zero_end``)."""

    labels: list[str]
    names: list[str]
    domains: list
    low: np.ndarray
    high: np.ndarray
    checked: np.ndarray
    unit_interval: np.ndarray
    zero_end: np.ndarray


@functools.lru_cache(maxsize=64)
def _domain_table(model: Model, channels: tuple[str, ...]) -> DomainTable:
    """:class:`DomainTable` of ``model`` in ``channels``, made once: a fit per texel checks thousands alike."""
    labels = model.physical.labels(channels)
    domains = model.physical.domains(len(channels))
    # The albedos come first; a shape parameter of a domain ≥ 0 (a conductor's k) ends on its lower end as an
    # albedo of 0 does not: its map exp(u) reaches 0 only in the limit, where the fit compensates elsewhere.
    n_albedos = albedo_size(model, len(channels)) if isinstance(model, LobeModel) else len(labels)
    meaningful_ends = model.lobe.meaningful_ends if isinstance(model, LobeModel) and model.lobe is not None else ()
    names = [re.sub(r"\[[^\]]*\]$", "", label) for label in labels]
    return DomainTable(
        labels,
        names,
        domains,
        np.array([domain.plausible[0] for domain in domains], float),
        np.array([domain.plausible[1] for domain in domains], float),
        np.array([name not in meaningful_ends for name in names]),
        np.array([isinstance(domain, UnitInterval) for domain in domains]),
        np.array(
            [
                index >= n_albedos and isinstance(domain, Positive) and domain.allow_zero
                for index, domain in enumerate(domains)
            ]
        ),
    )


def _albedo_above_one(
    model: Model, params: Params, channels: tuple[str, ...], open_incidences: tuple[float, ...]
) -> list[str]:
    """The directional albedo ``∫ f cos θo dωo`` by midpoint quadrature in ``(cos θo, φo)``; a value above
    :data:`ALBEDO_LIMIT` counts only where the grid's even points alone (a grid half as fine) agree within 1%,
    i.e. where the grid resolves the lobe.

    The fine grid (256 × 512 viewing directions per incidence; half that for an isotropic model) is evaluated only
    at ``open_incidences``, those where the screen (:func:`screen_bucket`: 16 × 32 directions, then 64 × 128) cannot
    rule an albedo above the limit out."""
    if not open_incidences:
        return []
    fine, coarse = (np.asarray(estimate) for estimate in _albedo_estimates(model, params, 256, open_incidences))
    above = (fine > ALBEDO_LIMIT) & (np.abs(fine - coarse) <= 0.01 * fine)  # (incidences, C)
    found = []
    for c, channel in enumerate(channels):
        where = [f"{fine[i, c]:.3g} at θi = {theta:g}°" for i, theta in enumerate(open_incidences) if above[i, c]]
        if where:
            found.append(
                f"the directional albedo in channel {channel} exceeds 1: {', '.join(where)}"
                " (the model reflects more light than it receives)"
            )
    return found


class Screened(NamedTuple):
    """What :func:`screen_bucket` found for one fit: the incidences its albedo screen left open (:func:`_refined`;
    none: cleared; all of them for a model the screen does not apply to), each lobe's largest share (K,): over every
    sample where one stays under :data:`DEAD_SHARE`, else over the screened ones (:func:`_confirmed_shares`)."""

    albedo_open: tuple[float, ...]
    lobe_shares: np.ndarray


def screen_bucket(model: LobeModel, params: list[Params], samples: Sequence[Samples], stack: int) -> list[Screened]:
    """The screens of a whole bucket of fits, ``params`` (numpy, one shape) of ``samples`` (one padded size), in one
    program, stacked to ``stack`` datasets as the bucket's problems are (``problem.stacked_directions``): every
    batch of a bucket runs the same program, which :func:`screen_program` compiles ahead. The fits whose first
    screen leaves an incidence open are screened again on the finer grid (:func:`_refined`)."""
    rows = [*params, *[params[0]] * (stack - len(params))]
    stacked = jax.tree.map(lambda *leaves: np.stack(leaves), *rows)
    directions = stacked_directions([_screened_at(one) for one in samples], "float64", stack)
    bounds, shares = (np.asarray(out) for out in _screens_program(stack)(model, stacked, *directions))
    shares = _confirmed_shares(model, params, samples, shares[: len(params)])
    if not _screenable(model):
        return [Screened(ALBEDO_INCIDENCE, shares[d]) for d in range(len(params))]
    bounds = _refined(model, stacked, bounds[: len(params)])
    patterns = _open_patterns(bounds)  # the whole bucket's at once: one comparison, not one a fit
    return [Screened(_incidences_of(pattern), shares[d]) for d, pattern in enumerate(patterns)]


def screen_program(model: LobeModel, samples: Sequence[Samples], stack: int) -> tuple:
    """:func:`screen_bucket`'s program followed by its arguments (the model, the shapes of the others) for
    ``samples`` stacked to ``stack`` datasets, to compile it ahead (``stacked.compile_in_background``)."""
    n_channels, size = samples[0].n_channels, padded_size(_screened_count(samples[0].n_samples))
    vector = np.zeros((stack, model.unconstrained.size(n_channels)))
    params = jax.eval_shape(jax.vmap(lambda v: model.unconstrained.to_params(v, n_channels)), vector)
    directions = jax.ShapeDtypeStruct((stack, size, 3), np.float64)
    real = jax.ShapeDtypeStruct((stack, size), bool)
    return _screens_program(stack), model, params, directions, directions, real


def _screens_program(stack: int):
    """:func:`_bucket_screens` compiled for a stack of ``stack`` fits: unoptimised for one (``jit(optimised=False)``:
    a single fit's screens, small grids and at most :data:`SHARE_SAMPLES` samples, are traced and compiled in 0.27 s
    instead of 0.40 s for a Cook-Torrance fit, 0.22 s instead of 0.37 s for Ward's, and take ~1.5 ms either way);
    optimised for more, whose run a spatially varying fit repeats for every batch of texels (1,024 texels of 32
    samples: 0.13 s optimised, 0.17 s not)."""
    return _one_fit_screens if stack == 1 else _stacked_screens


def _bucket_screens(model: LobeModel, stacked: Params, wi, wo, real):
    """The first screen's bound (:func:`_grid_bound` on the :data:`FIRST_SCREEN_GRID` grid; zeros where the screen
    does not apply) and :func:`_lobe_shares` of each of a stack of fits (leading axis D), one after another."""

    def one(arguments):
        params, wi, wo, real = arguments
        shares = _lobe_shares(model, params, wi, wo, real)
        if not _screenable(model):
            return jnp.zeros((len(ALBEDO_INCIDENCE), params.diffuse.shape[-1])), shares
        return _grid_bound(model, params, FIRST_SCREEN_GRID), shares

    return jax.lax.map(one, (stacked, wi, wo, real))


def _screened_count(n_samples: int) -> int:
    """How many samples of a dataset of ``n_samples`` the screen looks at: all of them, at most :data:`SHARE_SAMPLES`
    (:func:`_screened_at`; :func:`screen_program` compiles for this many, padded)."""
    return min(n_samples, SHARE_SAMPLES)


def _screened_at(samples: Samples) -> Samples:
    """The samples whose lobe shares the screen looks at: :func:`_screened_count` of them, all of a small dataset, else
    drawn with a seed (a sample drawn twice counts once in a largest share)."""
    count = _screened_count(samples.n_samples)
    if count == samples.n_samples:
        return samples
    return samples.select(np.random.default_rng(0).integers(0, samples.n_samples, count))


def _confirmed_shares(
    model: LobeModel, params: list[Params], samples: Sequence[Samples], shares: np.ndarray
) -> np.ndarray:
    """``shares`` (D, K), each lobe's largest share at the screened samples (:func:`_screened_at`) of each fit: a
    lower bound of its largest share at every sample, so a lobe at :data:`DEAD_SHARE` or above there contributes.
    A fit where a lobe stays under it is looked at whole: its shares at every sample (a program of the dataset's
    padded size, as the fits' problems are: one program for the datasets of a bucket)."""
    confirmed = shares.copy()
    for d in np.flatnonzero((shares < DEAD_SHARE).any(axis=1)).tolist():
        if _screened_count(samples[d].n_samples) < samples[d].n_samples:  # else every sample was screened
            wi, wo, real = (stacked[0] for stacked in stacked_directions([samples[d]], "float64", 1))
            confirmed[d] = np.asarray(_lobe_shares(model, params[d], wi, wo, real))
    return confirmed


_stacked_screens = jit(_bucket_screens, static_argnums=0)
_one_fit_screens = jit(_bucket_screens, static_argnums=0, optimised=False)


def _open_patterns(bounds: np.ndarray) -> list[tuple[bool, ...]]:
    """For each of a stack of screen bounds (D, incidences, C), which incidences reach :data:`SCREEN_BELOW` in some
    channel."""
    reached = np.any(np.asarray(bounds) >= SCREEN_BELOW, axis=2)  # (D, incidences)
    return [tuple(bool(value) for value in row) for row in reached]


@functools.cache
def _incidences_of(pattern: tuple[bool, ...]) -> tuple[float, ...]:
    """The incidences (degrees) a pattern (:func:`_open_patterns`) leaves open: one of few, made once each."""
    return tuple(theta for theta, is_open in zip(ALBEDO_INCIDENCE, pattern, strict=True) if is_open)


def _screenable(model: Model) -> TypeGuard[LobeModel]:
    """Whether the screen applies: a model with lobes, each peaking at the mirror direction (not Lafortune's)."""
    return isinstance(model, LobeModel) and model.lobe is not None and model.lobe.peaks_at_mirror


def _refined(model: LobeModel, stacked: Params, bounds: np.ndarray) -> np.ndarray:
    """``bounds`` (D, incidences, C), the first screen's of the first D fits of ``stacked`` (numpy, leading axis ≥ D),
    where it cleared every incidence; for a fit where it left one open, the smaller of it and the bound on the
    :data:`SCREEN_GRID` grid (both are bounds). The second grid is a program of its own, run on those fits alone,
    their count padded (with the first of them) to a power of two, at most the stack's: a program for each of a few
    shapes, compiled the first time one is needed. As a branch of the first screen's program it doubled that
    program's compilation (a MERL-size Ward fit's screens: 0.77 s of tracing and compiling, 0.40 s without it), and
    most fits never take it."""
    rows = np.flatnonzero(np.any(bounds >= SCREEN_BELOW, axis=(1, 2)))
    if not len(rows):
        return bounds
    size = min(1 << (len(rows) - 1).bit_length(), len(jax.tree.leaves(stacked)[0]))
    chosen = np.concatenate([rows, np.repeat(rows[:1], size - len(rows))])
    second = np.asarray(_grid_bounds(model, jax.tree.map(lambda leaf: leaf[chosen], stacked), SCREEN_GRID))
    refined = bounds.copy()
    refined[rows] = np.minimum(bounds[rows], second[: len(rows)])
    return refined


@jit(static_argnums=(0, 2))
def _grid_bounds(model: LobeModel, stacked: Params, n: int):
    """:func:`_grid_bound` on the n × 2n grid of each of a stack of fits (leading axis D), one after another."""
    return jax.lax.map(lambda params: _grid_bound(model, params, n), stacked)


def _grid_bound(model: LobeModel, params: Params, n: int):
    """A generous bound (incidences, C) on the directional albedo (traced), from an n × 2n grid:
    its estimate, plus three times its disagreement with its even points alone (the quadrature's error shrinks as
    the grid refines; the even points err at least as much), plus the BRDF's peak (at the mirror direction, where
    a lobe of these models peaks) times :data:`SCREEN_PEAK_CELLS` cells' ``d cos θo dφo`` (a lobe narrower than
    4 × 4 cells, which the grid samples too sparsely to judge, adds at most about that). A heuristic, not a proof:
    it is checked against the fine grid, incidence by incidence, for both screen grids: on 200 random materials
    whose albedos straddle 1 of the five classic models and on 400 materials over the whole domain of each model
    the screen applies to (``tests/fitting/test_caveats.py``, the latter marked heavy); Lafortune's lobes are
    checked on the fine grid always."""
    fine, coarse = _model_quadrature(model, params, n)
    wi = spherical_to_direction(jnp.asarray(np.radians(ALBEDO_INCIDENCE)), jnp.zeros(len(ALBEDO_INCIDENCE)))
    wo = mirror_direction(wi)
    peak = model.brdf(params, wi, wo) * wo[:, 2:3]
    # A cell's d cos θo dφo: π/n² on the grid; on the axial rule's rows of width h around the normal, π h².
    axial = np.array([_is_axial(model, theta) for theta in ALBEDO_INCIDENCE])[:, None]
    cell = np.where(axial, np.pi * _axial_row_width(n) ** 2, np.pi / n**2)
    return fine + 3.0 * jnp.abs(fine - coarse) + SCREEN_PEAK_CELLS * peak * cell


@jit(static_argnums=(0, 2, 3))
def _albedo_estimates(model: Model, params: Params, n: int, incidences: tuple[float, ...] = ALBEDO_INCIDENCE):
    """:func:`albedo_quadrature` of ``model`` with ``params`` on the n × 2n grid at ``incidences`` (degrees), in one
    program (the directions are made inside it, so no array of 2n² directions crosses from the host)."""
    return _model_quadrature(model, params, n, incidences)


def _model_quadrature(model: Model, params: Params, n: int, incidences: tuple[float, ...] = ALBEDO_INCIDENCE):
    """:func:`albedo_quadrature` of ``model`` (traced), (fine, coarse) each (incidences, C), with two symmetries of
    an isotropic model used. Lit at azimuth 0 it is symmetric in ``φo → −φo``: it is evaluated on the half grid
    ``φo < π`` alone, which gives the same sums for half the work. Lit along the normal it is symmetric about the
    normal (rotating both directions about it changes nothing, and the normal does not move): its albedo there is
    a one-dimensional integral over ``θo`` (:func:`_axial_quadrature`), whose rows resolve a lobe around the normal
    that the grid's first row, ``θo`` up to ``acos(1 − 1/n)`` (10° for n = 64), would hold whole."""
    half = model.isotropic
    on_grid = tuple(theta for theta in incidences if not _is_axial(model, theta))
    rows = {}
    if on_grid:
        directions = albedo_directions(n, jnp, half=half, incidences=on_grid)
        fine, coarse = albedo_quadrature(model.brdf(params, *directions), n, half=half)
        rows = {theta: (fine[i], coarse[i]) for i, theta in enumerate(on_grid)}
    if len(on_grid) < len(incidences):
        rows[0.0] = _axial_quadrature(model, params, n)
    return tuple(jnp.stack([rows[theta][part] for theta in incidences]) for part in (0, 1))


#: The axial rule's rows per row of the grid it stands in for (``_axial_quadrature``).
AXIAL_ROWS = 16


def _is_axial(model: Model, theta_i: float) -> bool:
    """Whether the albedo at incidence ``theta_i`` (degrees) is the axial rule's: an isotropic model lit along the
    normal."""
    return model.isotropic and theta_i == 0.0


def _axial_row_width(n: int) -> float:
    """The width ``h = π/(2m)`` (radians of ``θo``) of the axial rule's ``m = AXIAL_ROWS · n`` rows, standing in for
    a grid of ``n`` rows."""
    return np.pi / (2 * AXIAL_ROWS * n)


def _axial_quadrature(model: Model, params: Params, n: int):
    """The directional albedo (C,) at normal incidence of an isotropic model, ``2π ∫ f(θo) cos θo sin θo dθo``
    over ``[0, π/2]`` by the midpoint rule on ``AXIAL_ROWS · n`` rows of width ``h`` (:func:`_axial_row_width`),
    and by its even rows alone (weighted twice), as :func:`albedo_quadrature`'s coarse estimate is."""
    h = _axial_row_width(n)
    theta_o = (jnp.arange(AXIAL_ROWS * n) + 0.5) * h
    wo = spherical_to_direction(theta_o, jnp.zeros(len(theta_o)))
    wi = jnp.broadcast_to(jnp.asarray(NORMAL), wo.shape)
    weighted = model.brdf(params, wi, wo) * (2 * np.pi * h * jnp.cos(theta_o) * jnp.sin(theta_o))[:, None]
    return weighted.sum(axis=0), 2.0 * weighted[::2].sum(axis=0)


def albedo_directions(n: int, xp=np, *, half: bool = False, incidences: tuple[float, ...] = ALBEDO_INCIDENCE):
    """The pairs ``wi``, ``wo`` (incidences · 2n², 3) the albedo quadrature evaluates a BRDF at: each incidence of
    :data:`ALBEDO_INCIDENCE` (azimuth 0) with the viewer at the midpoints of an n × 2n grid in ``(cos θo, φo)``;
    ``half``: the n × n midpoints with ``φo < π`` alone. ``xp``: numpy, or ``jax.numpy`` inside a program."""
    cos_o = (xp.arange(n) + 0.5) / n
    phi_o = (xp.arange(n if half else 2 * n) + 0.5) * np.pi / n
    cos_grid, phi_grid = xp.meshgrid(cos_o, phi_o, indexing="ij")
    wo = spherical_to_direction(xp.arccos(cos_grid.ravel()), phi_grid.ravel())
    wi = spherical_to_direction(xp.asarray(np.radians(incidences)), xp.zeros(len(incidences)))
    return xp.repeat(wi, wo.shape[0], axis=0), xp.tile(wo, (len(incidences), 1))


def albedo_quadrature(values, n: int, *, half: bool = False):
    """The directional albedos (incidences, C) of BRDF ``values`` at :func:`albedo_directions`, by the midpoint rule
    in ``(cos θo, φo)`` (``dω cos θo = d cos θo dφo``), on the whole grid and on its even rows and columns alone.
    ``values``: a numpy or a JAX array. ``half``: values on the half grid of a BRDF symmetric in ``φo → −φo``
    (n even): column ``j`` stands for ``2n − 1 − j`` as well, which is odd where ``j`` is even, so the whole
    grid's sum is twice the half's and its even columns sum to all the half's columns."""
    cos_grid = ((np.arange(n) + 0.5) / n)[:, None]
    weighted = values.reshape(-1, n, n if half else 2 * n, values.shape[-1]) * cos_grid[None, :, :, None]
    fine = weighted.sum(axis=(1, 2)) * (2 if half else 1) / n * (np.pi / n)
    coarse = weighted[:, ::2, :: 1 if half else 2].sum(axis=(1, 2)) * 4 / n * (np.pi / n)
    return fine, coarse
