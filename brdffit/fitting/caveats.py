"""What a user must know before trusting a fit, one line each: the result's ``fit.warnings``.

* the samples as read are not reciprocal (``data/reciprocity.py``): their quantity is probably wrong;
* a lobe contributes less than :data:`DEAD_SHARE` of the model at every sample: it fits nothing;
* a parameter lies beyond its plausible range (``physics/domains.py``: a roughness above 2, an exponent
  above 10⁴, an albedo above 1, a dielectric index within 10⁻⁶ of 1), or a bounded one (Schlick's ``f0``)
  ends on an end of its domain: the optimum is against the bound;
* the model's directional albedo exceeds 1 at some incidence: it reflects more light than it receives (one line
  per channel);
* a fit with more lobes ends worse than one with fewer: it stopped in a local minimum.
"""

import jax
import jax.numpy as jnp
import numpy as np

from .._jax import float64, jit
from ..data.reciprocity import reciprocity
from ..data.samples import Samples
from ..physics.domains import UnitInterval
from ..physics.geometry import above_horizon, mirror_direction, spherical_to_direction
from ..physics.models import Model, Params

#: A lobe whose share of the model stays below this at every sample and channel contributes nothing.
DEAD_SHARE = 1e-3
#: A parameter of a bounded domain this close to one of its ends ended against it.
EDGE = 1e-6
#: Incidence zeniths (degrees) at which the directional albedo is checked.
ALBEDO_INCIDENCE = (0.0, 30.0, 60.0, 80.0)
#: A directional albedo counts as above 1 beyond this (quadrature rounds), and only where two grids agree.
ALBEDO_LIMIT = 1.005
#: The screening grid's n (n × 2n viewing directions per incidence), and the bound (``_screen_bound``) below which
#: the fine grid is not evaluated: 5% under the limit, for the bound's own guesswork.
SCREEN_GRID = 64
SCREEN_BELOW = 0.95
#: The screen's allowance for a lobe its grid samples too sparsely: the BRDF's peak over this many cells.
SCREEN_PEAK_CELLS = 16


@float64
def caveats(
    model: Model,
    samples: Samples,
    params: Params,
    cost: float | None = None,
    fewer_lobes_cost: float | None = None,
    *,
    albedo_open: tuple[float, ...] | None = None,
) -> list[str]:
    """Every caveat of ``model`` fitted to ``samples`` with ``params`` (numpy), ``cost`` its Σr²;
    ``fewer_lobes_cost``: the cost the same model with one lobe less reached on the same samples;
    ``albedo_open``: the incidences the albedo screen left open, if the caller has them (:func:`albedo_screens`)."""
    found = _not_reciprocal(samples)
    found += _dead_lobes(model, params, samples)
    found += _implausible(model, params, samples.channels)
    found += _albedo_above_one(model, params, samples.channels, albedo_open)
    if cost is not None and fewer_lobes_cost is not None and cost > fewer_lobes_cost * (1 + 1e-9):
        found.append(
            f"the fit ends at cost {cost:.6g}, worse than the {fewer_lobes_cost:.6g} of {model.n_lobes - 1} lobe(s):"
            " it stopped in a local minimum"
        )
    return found


def lobe_name(model: Model, params: Params, k: int) -> str:
    """How a message names lobe ``k``: ``lobe 2 (cxy +0.577, cz 0.577, n 1.8e+03)``, or the specular lobe."""
    if not model.lobes_as_list:
        return f"the specular lobe ({model.specular_name})"
    shape = ", ".join(f"{name} {float(params.shape[name][k]):.3g}" for name in model.lobe.names)
    return f"lobe {k + 1} ({shape})"


def _not_reciprocal(samples: Samples) -> list[str]:
    found = reciprocity(samples)
    if found is None or found.reciprocal:
        return []
    return [
        f"the samples as read ({found.in_force}) are not reciprocal: over {found.pairs} reciprocal pairs the median"
        f" of f(a→b)/f(b→a) is {found.as_read:.3g}; read as {found.best} it is {found.ratios[found.best]:.3g}"
        f": read them with --quantity {found.best} (quantity='{found.best}' in Python)"
    ]


def _dead_lobes(model: Model, params: Params, samples: Samples) -> list[str]:
    if not model.n_lobes:
        return []
    shares = np.asarray(_lobe_shares(model, params, samples.wi, samples.wo))
    return [
        f"{lobe_name(model, params, k)} contributes less than {DEAD_SHARE:.1%} of the model at every sample"
        f" (at most {share:.2g}): it fits nothing; fit with one lobe less"
        for k, share in enumerate(shares)
        if share < DEAD_SHARE
    ]


@jit(static_argnums=0)
def _lobe_shares(model: Model, params: Params, wi, wo):
    """Each lobe's largest share of the model over the samples and channels, (K,)."""
    visible, wi, wo = above_horizon(wi, wo)
    contributions = model.lobe_values(params.shape, wi, wo)[:, :, None] * params.specular[:, None, :]  # (K, N, C)
    total = params.diffuse / jnp.pi + contributions.sum(axis=0)
    share = contributions / jnp.maximum(total, jnp.finfo(total.dtype).tiny)
    return (share * visible[None, :, None]).max(axis=(1, 2))


def _implausible(model: Model, params: Params, channels: tuple[str, ...]) -> list[str]:
    values = np.asarray(model.physical.from_params(params))
    found = []
    for label, value, domain in zip(
        model.physical.labels(channels), values, model.physical.domains(len(channels)), strict=True
    ):
        low, high = domain.plausible
        if isinstance(domain, UnitInterval) and min(value, 1.0 - value) < EDGE:
            found.append(
                f"{label} = {value:.10g} lies on an end of its domain {domain.text}: the fit ended against the bound,"
                " where the model may not describe the data"
            )
        elif value > high:
            found.append(f"{label} = {value:.4g} is beyond its plausible range (≤ {high:g})")
        elif value < low:
            found.append(f"{label} = {value:.10g} is below its plausible range (≥ {low:.10g})")
    return found


def _albedo_above_one(
    model: Model, params: Params, channels: tuple[str, ...], open_incidences: tuple[float, ...] | None = None
) -> list[str]:
    """The directional albedo ``∫ f cos θo dωo`` by midpoint quadrature in ``(cos θo, φo)``; a value above
    :data:`ALBEDO_LIMIT` counts only where the grid's even points alone (a grid half as fine) agree within 1%,
    i.e. where the grid resolves the lobe.

    The fine grid (256 × 512 viewing directions per incidence; half that for an isotropic model) is evaluated only
    at the incidences where a screen (:func:`_screen_bound`, 64 × 128 directions) cannot rule an albedo above the
    limit out; ``open_incidences``: those incidences, when :func:`albedo_screens` screened many fits at once."""
    if open_incidences is None:
        screened = _screen_bound(model, params) if _screenable(model) else None
        open_incidences = ALBEDO_INCIDENCE if screened is None else _open_incidences(np.asarray(screened))
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


def albedo_screens(model: Model, params: list[Params]) -> list[tuple[float, ...]]:
    """For each of ``params`` (numpy, one shape), the incidences the albedo screen leaves open
    (:func:`_screen_bound`; none: cleared): the screens of a whole bucket of fits in one program."""
    if not _screenable(model):
        return [ALBEDO_INCIDENCE] * len(params)
    stacked = jax.tree.map(lambda *leaves: np.stack(leaves), *params)
    return [_open_incidences(bounds) for bounds in np.asarray(_screen_bounds(model, stacked))]


def _open_incidences(bounds: np.ndarray) -> tuple[float, ...]:
    """The incidences whose screen bound (incidences, C) reaches :data:`SCREEN_BELOW` in some channel."""
    return tuple(theta for theta, bound in zip(ALBEDO_INCIDENCE, bounds, strict=True) if np.any(bound >= SCREEN_BELOW))


def _screenable(model: Model) -> bool:
    """Whether the screen applies: a model with lobes, each peaking at the mirror direction (not Lafortune's)."""
    return bool(model.n_lobes) and not model.lobes_as_list


@jit(static_argnums=0)
def _screen_bounds(model: Model, stacked: Params):
    """:func:`_screen_bound` of each of a stack of parameters (leading axis D), one after another."""
    return jax.lax.map(lambda params: _screen_bound(model, params), stacked)


@jit(static_argnums=0)
def _screen_bound(model: Model, params: Params):
    """A generous bound (incidences, C) on the directional albedo, from a :data:`SCREEN_GRID` × 2·SCREEN_GRID grid:
    its estimate, plus three times its disagreement with its even points alone (the quadrature's error shrinks as
    the grid refines; the even points err at least as much), plus the BRDF's peak (at the mirror direction, where
    a lobe of these models peaks) times :data:`SCREEN_PEAK_CELLS` cells' ``d cos θo dφo`` (a lobe narrower than
    4 × 4 cells, which the grid samples too sparsely to judge, adds at most about that). A heuristic, not a proof:
    it is checked against the fine grid, incidence by incidence, on 750 random materials of the five models whose
    lobes peak at the mirror direction (``tests/fitting/test_caveats.py``: 200 of them); Lafortune's lobes are
    checked on the fine grid always."""
    fine, coarse = _model_quadrature(model, params, SCREEN_GRID)
    wi = spherical_to_direction(jnp.asarray(np.radians(ALBEDO_INCIDENCE)), jnp.zeros(len(ALBEDO_INCIDENCE)))
    wo = mirror_direction(wi)
    peak = model.brdf(params, wi, wo) * wo[:, 2:3]
    return fine + 3.0 * jnp.abs(fine - coarse) + SCREEN_PEAK_CELLS * peak * (np.pi / SCREEN_GRID**2)


@jit(static_argnums=(0, 2, 3))
def _albedo_estimates(model: Model, params: Params, n: int, incidences: tuple[float, ...] = ALBEDO_INCIDENCE):
    """:func:`albedo_quadrature` of ``model`` with ``params`` on the n × 2n grid at ``incidences`` (degrees), in one
    program (the directions are made inside it, so no array of 2n² directions crosses from the host)."""
    return _model_quadrature(model, params, n, incidences)


def _model_quadrature(model: Model, params: Params, n: int, incidences: tuple[float, ...] = ALBEDO_INCIDENCE):
    """:func:`albedo_quadrature` of ``model`` (traced). An isotropic model, lit at azimuth 0, is symmetric in
    ``φo → −φo``: it is evaluated on the half grid ``φo < π`` alone, which gives the same sums for half the work."""
    half = model.isotropic
    directions = albedo_directions(n, jnp, half=half, incidences=incidences)
    return albedo_quadrature(model.brdf(params, *directions), n, half=half)


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
