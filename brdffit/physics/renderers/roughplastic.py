"""Mitsuba 3's ``roughplastic`` BSDF (its ``eval``, ``nonlinear=false``), in JAX, as Mitsuba 3.9.1 computes it.

A diffuse base under a rough dielectric coating of relative index ``η = int_ior/ext_ior`` (Weidlich & Wilkie,
"Arbitrarily layered micro-facet surfaces", GRAPHITE 2007; the energy bookkeeping of Kelemen & Szirmay-Kalos,
"A microfacet based coupled specular-matte BRDF model with importance sampling", Eurographics 2001). With
``ci = wi_z`` (the light), ``co = wo_z`` (the viewer), ``h = normalize(wi + wo)``, the BRDF in 1/sr is::

    f = ks · F(wi·h, η) D(h) G1(wi) G1(wo) / (4 ci co)  +  kd / (1 − Ri(α)) · T(α, ci) T(α, co) / (π η²)

Mitsuba's ``eval`` returns ``f · cos θ`` of the direction it is handed; this module returns ``f``, and 0 where
``ci ≤ 0`` or ``co ≤ 0``. The sources, in Mitsuba 3.9.1:

* ``src/bsdfs/roughplastic.cpp``, ``eval``: the formula above, with ``si.wi`` the viewer and the ``wo`` it is
  handed the light; both terms are symmetric in the two, so the plugin is reciprocal (to float32 rounding);
* ``include/mitsuba/render/microfacet.h``: ``D`` (Beckmann, GGX; Walter et al., "Microfacet models for refraction
  through rough surfaces", EGSR 2007), zeroed where ``D · h_z ≤ 1e-20``; ``α`` clamped below at ``1e-4``; Smith's
  separable ``G1`` — GGX's exact ``2/(1 + sqrt(1 + α² tan²θ))``, Beckmann's **not** the exact one of
  ``microfacet.py`` but Walter's rational approximation (eq. 27, < 0.35 % from it), :func:`beckmann_walter_g1`;
* ``include/mitsuba/render/fresnel.h``, ``fresnel``: the exact unpolarised dielectric reflectance, which is
  :func:`~brdffit.physics.fresnel.fresnel_dielectric` for ``η > 1`` (and ``wi·h > 0``, always true here).

``T(α, μ)``, the rough interface's transmittance from outside at ``cos θ = μ``, and ``Ri(α)``, its reflectance
from inside averaged over a cosine-weighted hemisphere, are what Mitsuba precomputes for the one ``α`` it is given
(``parameters_changed``; ``eval_transmittance`` and ``eval_reflectance`` in ``microfacet.h``): on
``MI_ROUGH_TRANSMITTANCE_RES = 64`` cosines ``μ_j = max(1e-6, j/63)``, a 32 × 32 (``η > 1``; 128 × 128 for the
internal ``1/η < 1``) Gauss-Legendre product rule over Heitz & d'Eon's visible-normal sampling of ``wi``::

    T(μ_j) = Σ w_a w_b / 4 · (1 − F(wi·m)) G1(wt, m),    m = sample_visible(wi, (1 + x_a)/2, (1 + x_b)/2),
    Ri     = 2 · mean_j μ_j Σ w_a w_b / 4 · F(wi·m, 1/η) G1(wr, m)     (wt refracted, wr reflected; 0 below)

and ``eval`` interpolates ``T`` *linearly* in ``μ`` between those 64 nodes (``lerp_gather``), as this module does.
A fit changes ``α``, so :func:`rough_dielectric_table` runs that quadrature — the same nodes, weights, sampling
routine (Beckmann's three Newton steps on Giles' ``erfinv`` approximation, GGX's concentric-disk projection) and
formulas, in float64 — at :data:`ALPHA_NODES` roughnesses evenly spaced in ``ln α`` over :data:`ALPHA_RANGE`, once per
``(distribution, η)``, and ``eval`` interpolates it in ``ln α`` by a not-a-knot cubic spline (continuous slope and
curvature in ``α``).

What is exact and what is not. The specular term is Mitsuba's formula in the caller's precision; Mitsuba's
``scalar_rgb`` evaluates it in float32, and the two agree to 5e-6 relative (measured: 360 pairs to 89°, near-mirror ones
included, ``α`` 0.01 to 1, both distributions, ``η`` 1.49 and 1.6). At a node the tables reproduce Mitsuba's float32
sums to 6e-6 (the diffuse term at the cosines ``j/63``, all 48 nodes, both distributions). Between nodes the spline
departs from the quadrature by at most 5e-4 in ``T`` and 1.7e-3 in ``Ri`` (relative, at every midpoint of the grid, both
distributions, ``η`` 1.3 to 1.6): 1.8e-3 at most in the diffuse term, which :data:`DIFFUSE_TABLE_ERROR` bounds; against
Mitsuba itself at 150 random roughnesses from 1e-4 to 2 the diffuse term was within 3.3e-4 (Beckmann) and 1.3e-3 (GGX),
with a median of 8e-6 and 3e-5. ``T``'s error falls as the fourth power of the spacing (1.6e-4 with 64 nodes); ``Ri``'s
does not, for Mitsuba's ``Ri(α)`` itself ripples by ~8e-4 (relative, with a period of ~0.2 in ``ln α``; most likely
where its fixed 128² nodes meet the moving kink of total internal reflection), which no smooth interpolation follows.
Outside :data:`ALPHA_RANGE` the tables hold their end values: below ``1e-4`` that is Mitsuba's own value, as it clamps
``α`` there itself; above 2, the plausible end of brdffit's roughness (``domains.ROUGHNESS``), the diffuse term stops
following ``α`` (its derivative in ``α`` is 0 there) rather than costing more nodes at every start.
"""

import functools
import math
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..._jax import jnp
from ...checks import choice
from ...errors import BrdfInputError
from ..fresnel import fresnel_dielectric
from ..geometry import above_horizon, half_vector, tan2_from_cos
from ..microfacet import DISTRIBUTIONS

#: Mitsuba's default indices of the coating (polypropylene) and of the air outside it (``int_ior``, ``ext_ior``).
DEFAULT_INT_IOR = 1.49
EXT_IOR = 1.000277
#: The rows of the tables at Mitsuba's default index, shipped (:func:`write_shipped_rows`).
SHIPPED_ROWS = Path(__file__).with_name("roughplastic_rows.npz")
#: ``MI_ROUGH_TRANSMITTANCE_RES``: the cosines Mitsuba tabulates the transmittance at, ``max(1e-6, j/63)``.
COSINE_NODES = 64
#: Mitsuba's floor on ``α`` (``MicrofacetDistribution::configure``).
MITSUBA_MIN_ALPHA = 1e-4
#: The roughnesses the tables cover (ends included); outside, each table holds its end value (module docstring).
ALPHA_RANGE = (MITSUBA_MIN_ALPHA, 2.0)
#: Roughnesses tabulated, evenly spaced in ``ln α`` over :data:`ALPHA_RANGE` (0.21 apart in ``ln α``).
ALPHA_NODES = 48
#: The diffuse term's largest relative departure from Mitsuba's own that the table brings (module docstring).
DIFFUSE_TABLE_ERROR = 2e-3
#: Mitsuba zeroes ``D`` where ``D · h_z`` is at most this (``MicrofacetDistribution::eval``).
DENSITY_FLOOR = 1e-20
#: Walter's Beckmann ``G1`` is 1 from ``a = 1/(α tan θ) ≥ 1.6`` on, i.e. for ``α² tan²θ ≤ 1/1.6²``.
WALTER_A_MAX = 1.6


def roughplastic_brdf(params, wi, wo, *, distribution="beckmann", int_ior=DEFAULT_INT_IOR, ext_ior=EXT_IOR):
    """(N, C) BRDF in 1/sr of Mitsuba 3's ``roughplastic`` (``nonlinear=false``), WITHOUT the cosine Mitsuba's
    ``eval`` includes; 0 where ``wi_z ≤ 0`` or ``wo_z ≤ 0``.

    ``params``: ``alpha`` (scalar, Mitsuba's ``alpha``), ``diffuse_reflectance`` and ``specular_reflectance`` ((C,)
    each). ``wi`` towards the light, ``wo`` towards the viewer: unit vectors (N, 3) in the surface frame (z the
    normal). ``distribution``: ``beckmann`` (Mitsuba's default) or ``ggx``; ``int_ior``, ``ext_ior``: the indices
    (Mitsuba's defaults: polypropylene, air), ``int_ior > ext_ior``. JAX-traceable, differentiable in ``params``,
    in the precision of ``wi``. The formula and what is exact: the module docstring.
    """
    choice("distribution", distribution, DISTRIBUTIONS, verb="is not known")
    eta = float(int_ior) / float(ext_ior)
    if not eta > 1.0:
        raise BrdfInputError(f"int_ior={int_ior} must exceed ext_ior={ext_ior}: a plastic coating is the denser")
    visible, wi, wo = above_horizon(wi, wo)
    alpha = jnp.maximum(params["alpha"], MITSUBA_MIN_ALPHA)
    cos_i, cos_o = wi[:, 2], wo[:, 2]
    h = half_vector(wi, wo)
    density = DISTRIBUTIONS[distribution].density(h[:, 2], alpha)
    density = jnp.where(density * h[:, 2] > DENSITY_FLOOR, density, 0.0)
    masking = smith_g1(distribution, cos_i, alpha) * smith_g1(distribution, cos_o, alpha)
    fresnel = fresnel_dielectric(jnp.sum(wi * h, axis=-1), eta)
    specular = fresnel * density * masking / (4.0 * cos_i * cos_o)

    transmittance, internal_reflectance = rough_dielectric_table(distribution, eta).at(alpha, wi.dtype)
    diffuse = transmittance_at(transmittance, cos_i) * transmittance_at(transmittance, cos_o)
    diffuse = diffuse / (jnp.pi * eta * eta * (1.0 - internal_reflectance))
    value = specular[:, None] * params["specular_reflectance"] + diffuse[:, None] * params["diffuse_reflectance"]
    return jnp.where(visible[:, None], value, 0.0)


def beckmann_walter_g1(slope2):
    """Mitsuba's Beckmann ``G1`` of ``slope2 = α² tan²θ``: Walter et al. 2007's rational approximation (eq. 27),
    ``(3.535 a + 2.181 a²)/(1 + 2.276 a + 2.577 a²)`` with ``a = 1/sqrt(slope2)``, 1 for ``a ≥ 1.6``."""
    # a held at 1.6 where it is larger: the branch the `where` drops never sees 1/sqrt(0)
    a = 1.0 / jnp.sqrt(jnp.maximum(slope2, 1.0 / (WALTER_A_MAX * WALTER_A_MAX)))
    rational = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return jnp.where(a >= WALTER_A_MAX, 1.0, rational)


def smith_g1(distribution: str, cos_theta, alpha):
    """Mitsuba's ``smith_g1`` at a direction of zenith cosine ``cos_theta`` (its microfacet normal on the same side):
    GGX's exact ``1/(1 + Λ)``, Beckmann's :func:`beckmann_walter_g1`."""
    if distribution == "ggx":
        return 1.0 / (1.0 + DISTRIBUTIONS["ggx"].smith_lambda(cos_theta, alpha))
    return beckmann_walter_g1(alpha * alpha * tan2_from_cos(cos_theta))


def transmittance_at(transmittance, cos_theta):
    """``T`` at ``cos_theta`` (N,) from its values (64,) at ``j/63``, as Mitsuba's ``lerp_gather``: linear between
    the two nodes about it (``cos θ = 1`` at the end of the last interval)."""
    position = cos_theta * (COSINE_NODES - 1)
    index = jnp.minimum(jnp.floor(position), COSINE_NODES - 2).astype(jnp.int32)
    fraction = position - index
    return transmittance[index] * (1.0 - fraction) + transmittance[index + 1] * fraction


class RoughDielectricTable(NamedTuple):
    """``T(α, μ_j)`` (64 columns) and ``Ri(α)`` (the last column) at :data:`ALPHA_NODES` roughnesses, as the not-a-knot
    cubic spline in ``ln α`` through them: ``coefficients`` (4, ALPHA_NODES − 1, 65), highest power first, of the
    interval starting at ``ln α_k = log_alpha_start + k · log_alpha_step``."""

    coefficients: np.ndarray
    log_alpha_start: float
    log_alpha_step: float

    def at(self, alpha, dtype):
        """``T`` (64,) and ``Ri`` (scalar) at ``alpha`` (clamped to :data:`ALPHA_RANGE`), in ``dtype``."""
        intervals = self.coefficients.shape[1]
        log_alpha = jnp.log(jnp.clip(alpha, *ALPHA_RANGE))
        position = (log_alpha - self.log_alpha_start) / self.log_alpha_step
        index = jnp.clip(jnp.floor(position), 0, intervals - 1).astype(jnp.int32)
        offset = (position - index) * self.log_alpha_step
        cubic, square, linear, constant = jnp.asarray(self.coefficients, dtype=dtype)[:, index]
        row = ((cubic * offset + square) * offset + linear) * offset + constant
        return row[:COSINE_NODES], row[COSINE_NODES]


@functools.cache
def rough_dielectric_table(distribution: str, eta: float) -> RoughDielectricTable:
    """Mitsuba's ``T`` and ``Ri`` for ``distribution`` and relative index ``eta``, at :data:`ALPHA_NODES` roughnesses
    evenly spaced in ``ln α`` over :data:`ALPHA_RANGE`, splined in ``ln α`` (once a process): the quadrature's rows
    shipped for Mitsuba's default index (:data:`SHIPPED_ROWS`), else computed (~2 s for each distribution)."""
    from scipy.interpolate import CubicSpline  # scipy only where a table is built: importing it costs ~0.2 s

    log_alphas = tabulated_log_alphas()
    rows = shipped_rows(distribution, eta)
    if rows is None:
        rows = tabulated_rows(distribution, eta)
    spline = CubicSpline(log_alphas, rows, axis=0)
    return RoughDielectricTable(spline.c, float(log_alphas[0]), float(log_alphas[1] - log_alphas[0]))


def shipped_rows(distribution: str, eta: float) -> np.ndarray | None:
    """The shipped :func:`tabulated_rows` of ``distribution`` where ``eta`` is Mitsuba's default index (computed as
    the model computes it: ``DEFAULT_INT_IOR / EXT_IOR``), else None."""
    if float(eta) != DEFAULT_INT_IOR / EXT_IOR:
        return None
    with np.load(SHIPPED_ROWS) as shipped:
        return np.array(shipped[distribution]) if distribution in shipped.files else None


def tabulated_log_alphas() -> np.ndarray:
    """The ``ln α`` of the table's rows: :data:`ALPHA_NODES`, evenly spaced over :data:`ALPHA_RANGE`."""
    return np.linspace(math.log(ALPHA_RANGE[0]), math.log(ALPHA_RANGE[1]), ALPHA_NODES)


def tabulated_rows(distribution: str, eta: float) -> np.ndarray:
    """:func:`rough_dielectric_terms` at every roughness of :func:`tabulated_log_alphas`: (ALPHA_NODES, 65)."""
    return np.stack([rough_dielectric_terms(distribution, math.exp(x), eta) for x in tabulated_log_alphas()])


def write_shipped_rows(path: Path = SHIPPED_ROWS) -> None:
    """Write :data:`SHIPPED_ROWS`: :func:`tabulated_rows` of each distribution at Mitsuba's default index, one array a
    distribution (ALPHA_NODES, 65). Run ``python -m brdffit.physics.renderers.roughplastic`` after changing the
    quadrature or the table's nodes; a test checks that the shipped rows are the quadrature's."""
    rows: dict[str, Any] = {  # savez keywords, whose stubs take allow_pickle among them
        distribution: tabulated_rows(distribution, DEFAULT_INT_IOR / EXT_IOR) for distribution in DISTRIBUTIONS
    }
    with open(path, "wb") as file:
        np.savez(file, **rows)


# ---------------------------------------------------------------------------------- Mitsuba's quadrature, numpy


def rough_dielectric_terms(distribution: str, alpha: float, eta: float) -> np.ndarray:
    """``(T(μ_0), …, T(μ_63), Ri)`` (65,) at one ``alpha``, by Mitsuba's own quadrature (``eval_transmittance``,
    ``eval_reflectance``, ``RoughPlastic::parameters_changed``), in float64."""
    cosines = np.maximum(1e-6, np.linspace(0.0, 1.0, COSINE_NODES))
    transmittance = _interface_quadrature(distribution, alpha, eta, cosines, reflect=False)
    reflectance = _interface_quadrature(distribution, alpha, 1.0 / eta, cosines, reflect=True)
    return np.append(transmittance, 2.0 * np.mean(reflectance * cosines))


def _interface_quadrature(distribution, alpha, eta, cosines, *, reflect):
    """``Σ w_a w_b / 4 · G1(w, m) · (F or 1 − F)`` at each of ``cosines`` (``wi = (sin, 0, cos)``), with ``w`` ``wi``
    reflected (``reflect``) or refracted about the visible normal ``m`` sampled at the Gauss-Legendre nodes; ``n`` of
    them on each axis, 32 for ``eta > 1``, else 128 (``microfacet.h``).

    ``wi`` lies in the ``xz`` plane, so the integrand is even in ``m_y``, which is odd in the second sample
    (Beckmann's ``erfinv(2 u_b − 1)``) or in the first (GGX's disk ``x``): the sum runs over the upper half of that
    sample's nodes with their weights doubled, Mitsuba's sum in another order (and twice as fast).
    """
    n = 32 if eta > 1.0 else 128
    nodes, weights = _gauss_legendre(n)
    samples, upper = 0.5 * nodes + 0.5, slice(n // 2, n)
    full, folded = (samples, weights), (samples[upper], 2.0 * weights[upper])
    (u_a, weight_a), (u_b, weight_b) = (full, folded) if distribution == "beckmann" else (folded, full)
    sin_i = np.sqrt(1.0 - cosines * cosines)[:, None, None]
    cos_i = cosines[:, None, None]
    # Heitz & d'Eon: stretch wi by alpha; its azimuth is 0 (cos φ = 1, sin φ = 0), so the slopes only scale back
    slope_x, slope_y = _visible_slopes_11(distribution, cos_i / np.hypot(alpha * sin_i, cos_i), u_a[:, None], u_b)
    m_x, m_y = -alpha * slope_x, -alpha * slope_y  # m = normalize(m_x, m_y, 1)
    length = np.sqrt(m_x * m_x + m_y * m_y + 1.0)
    m = (m_x / length, m_y / length, 1.0 / length)
    cos_im = sin_i * m[0] + cos_i * m[2]
    fresnel, cos_t, eta_ti = _mitsuba_fresnel(cos_im, eta)
    if reflect:
        scale, shift, kept = 2.0 * cos_im, 1.0, fresnel
    else:
        scale, shift, kept = cos_im * eta_ti + cos_t, eta_ti, 1.0 - fresnel
    w = (scale * m[0] - shift * sin_i, scale * m[1], scale * m[2] - shift * cos_i)
    # reflected below the horizon, or refracted not below it: 0
    value = _mitsuba_g1(distribution, alpha, w, m) * kept
    value[(w[2] <= 0.0) if reflect else (w[2] >= 0.0)] = 0.0
    return np.einsum("jab,a,b->j", value, weight_a, weight_b) * 0.25


@functools.cache
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``n``-point Gauss-Legendre rule on ``[−1, 1]``: nodes ascending, weights (Mitsuba's ``quad::gauss_legendre``,
    which rounds them to float32)."""
    return np.polynomial.legendre.leggauss(n)


def _visible_slopes_11(distribution, cos_theta, u_a, u_b):
    """Mitsuba's ``sample_visible_11``: the slopes of a visible normal of the ``α = 1`` distribution seen from zenith
    cosine ``cos_theta``, for the sample ``(u_a, u_b)``; broadcast."""
    with np.errstate(divide="ignore"):  # cos θ = 1: tan θ = 0, cot θ = ∞, erf(∞) = 1, as in float32
        tan_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0)) / cos_theta
        cot_theta = 1.0 / tan_theta
    if distribution == "beckmann":
        from scipy.special import erf

        u_a, u_b = np.clip(u_a, 1e-6, 1.0 - 1e-6), np.clip(u_b, 1e-6, 1.0 - 1e-6)
        largest = erf(cot_theta)
        x = largest - (largest + 1.0) * erf(np.sqrt(-np.log(u_a)))
        target = u_a * (1.0 + largest + tan_theta * np.exp(-cot_theta * cot_theta) / math.sqrt(math.pi))
        for _ in range(3):  # Mitsuba's three Newton steps, not run to convergence: the same map, not the exact one
            slope = _erfinv_giles(x)
            value = 1.0 + x + tan_theta * np.exp(-slope * slope) / math.sqrt(math.pi) - target
            x = x - value / (1.0 - slope * tan_theta)
        return _erfinv_giles(x), _erfinv_giles(2.0 * u_b - 1.0)
    # GGX (Heitz 2018): a point of the concentric disk, projected onto the side wi sees
    disk_x, disk_y = _square_to_disk_concentric(u_a, u_b)
    stretch = 0.5 * (1.0 + cos_theta)
    disk_y = np.sqrt(np.maximum(1.0 - disk_x * disk_x, 0.0)) * (1.0 - stretch) + disk_y * stretch
    disk_z = np.sqrt(np.maximum(1.0 - disk_x * disk_x - disk_y * disk_y, 0.0))
    sin_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0))
    norm = 1.0 / (sin_theta * disk_y + cos_theta * disk_z)
    return (cos_theta * disk_y - sin_theta * disk_z) * norm, disk_x * norm


def _square_to_disk_concentric(u_a, u_b):
    """Mitsuba's ``warp::square_to_uniform_disk_concentric`` (Shirley & Chiu's map, Cline's branchless form)."""
    x, y = np.broadcast_arrays(2.0 * u_a - 1.0, 2.0 * u_b - 1.0)
    steep = np.abs(x) < np.abs(y)
    radius, other = np.where(steep, y, x), np.where(steep, x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = 0.25 * np.pi * other / radius
    phi = np.where(steep, 0.5 * np.pi - phi, phi)
    phi = np.where((x == 0.0) & (y == 0.0), 0.0, phi)
    return radius * np.cos(phi), radius * np.sin(phi)


#: Giles, "Approximating the erfinv function" (GPU Computing Gems, 2011): the single-precision polynomials in
#: ``w = −ln(1 − x²)``, lowest power first, for ``w < 5`` (in ``w − 2.5``) and beyond (in ``sqrt(w) − 3``); drjit's
#: ``erfinv``.
GILES_CENTRAL = (1.50140941, 0.246640727, -0.00417768164, -0.00125372503, 0.00021858087, -4.39150654e-06,
                 -3.5233877e-06, 3.43273939e-07, 2.81022636e-08)  # fmt: skip
GILES_TAIL = (2.83297682, 1.00167406, 0.00943887047, -0.0076224613, 0.00573950773, -0.00367342844, 0.00134934322,
              0.000100950558, -0.000200214257)  # fmt: skip


def _erfinv_giles(x):
    """drjit's ``erfinv``: Giles' approximation (relative error ~1e-7 against the true inverse)."""
    w = -np.log((1.0 - x) * (1.0 + x))
    central = np.polynomial.polynomial.polyval(w - 2.5, GILES_CENTRAL)
    tail = np.polynomial.polynomial.polyval(np.sqrt(w) - 3.0, GILES_TAIL)
    return np.where(w < 5.0, central, tail) * x


def _mitsuba_fresnel(cos_theta_i, eta):
    """Mitsuba's ``fresnel`` (``fresnel.h``): ``(F, cos θt, η_ti)`` for light arriving at cosine ``cos_theta_i``
    (negative: from inside) on an interface of relative index ``eta``; ``F = 1`` past the critical angle. Not
    :func:`~brdffit.physics.fresnel.fresnel_dielectric`, which is for ``η > 1`` from outside and returns ``F`` alone:
    the internal reflectance needs total reflection and the transmittance the refracted cosine."""
    outside = cos_theta_i >= 0.0
    if outside.all():  # visible normals face wi: the quadrature's case, where scalars spare three array selections
        eta_it, eta_ti, sign = eta, 1.0 / eta, -1.0
    else:
        eta_it, eta_ti, sign = (
            np.where(outside, eta, 1.0 / eta),
            np.where(outside, 1.0 / eta, eta),
            2.0 * ~outside - 1.0,
        )
    cos_t = np.sqrt(np.maximum(1.0 - (1.0 - cos_theta_i * cos_theta_i) * (eta_ti * eta_ti), 0.0))
    cos_i = np.abs(cos_theta_i)
    with np.errstate(divide="ignore", invalid="ignore"):
        a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t)
        a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i)
    reflectance = 0.5 * (a_s * a_s + a_p * a_p)
    reflectance[cos_i == 0.0] = 1.0
    return reflectance, sign * cos_t, eta_ti


def _mitsuba_g1(distribution, alpha, v, m):
    """Mitsuba's ``smith_g1(v, m)`` (isotropic), numpy, ``v`` and ``m`` as their components ``(x, y, z)``: 1 at ``v``
    along the normal, 0 where ``v`` sees the back of ``m``; Beckmann's is Walter's rational approximation."""
    tangential2 = alpha * alpha * (v[0] * v[0] + v[1] * v[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        slope2 = tangential2 / (v[2] * v[2])
        if distribution == "beckmann":
            a = 1.0 / np.sqrt(slope2)
            result = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
            result[a >= WALTER_A_MAX] = 1.0
        else:
            result = 2.0 / (1.0 + np.sqrt(1.0 + slope2))
    result[tangential2 == 0.0] = 1.0
    result[(v[0] * m[0] + v[1] * m[1] + v[2] * m[2]) * v[2] <= 0.0] = 0.0
    return result


if __name__ == "__main__":
    write_shipped_rows()
