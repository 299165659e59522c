"""Microfacet distributions and masking-shadowing terms, and the registries that name them.

A microfacet lobe is ``F(cos β) · D(h) · G(wi, wo) / (4 ci co)`` (Walter et al., "Microfacet models for
refraction through rough surfaces", EGSR 2007). ``m`` is the roughness: Beckmann's rms slope, GGX's ``α``.

Distributions (each normalised so that ``∫ D(h) cos θh dω_h = 1``):

* ``beckmann``: ``D = exp(−tan²θh/m²) / (π m² cos⁴θh)`` (Beckmann 1963);
* ``ggx``: ``D = m² / (π cos⁴θh (m² + tan²θh)²)`` (Trowbridge & Reitz 1975; Walter et al. 2007).

Masking-shadowing:

* ``v-groove``: ``G = min(1, 2 ch co/(wo·h), 2 ch ci/(wo·h))`` (Torrance & Sparrow 1967; Cook & Torrance 1982);
* ``smith``: separable Smith, ``G = G1(wi) G1(wo)`` with ``G1 = 1/(1 + Λ)``;
* ``smith-correlated``: height-correlated Smith, ``G = 1/(1 + Λ(wi) + Λ(wo))`` (Heitz, "Understanding the
  masking-shadowing function in microfacet-based BRDFs", JCGT 2014, eq. 99).

Smith's ``Λ`` is each distribution's own, exact (Heitz 2014, §5.3 and §5.4; Walter et al. 2007 eq. 27 and 34),
with ``a = 1/(m tan θ)``:

* Beckmann: ``Λ = (erf(a) − 1)/2 + exp(−a²)/(2a√π)``, through ``erf``, not Walter's rational approximation;
* GGX: ``Λ = (−1 + sqrt(1 + 1/a²))/2``.

Each ``Λ`` is one function of ``1/a² = m² tan²θ`` (``*_slope_lambda``), which the isotropic and the anisotropic lobe
both call.

Anisotropic distributions (Heitz 2014, §5.2–5.4): roughness ``αu`` along a tangent ``t``, ``αv`` along the bitangent
``b``; with the half vector's tangent-frame components ``x = h·t``, ``y = h·b`` and
``s = (x²/αu² + y²/αv²)/ch²``:

* Beckmann: ``D = exp(−s) / (π αu αv ch⁴)``;
* GGX: ``D = 1 / (π αu αv ch⁴ (1 + s)²)``.

Their Smith ``Λ`` is the isotropic one with the direction's own roughness ``α(φ) = sqrt(cos²φ αu² + sin²φ αv²)``
(``φ`` its azimuth from ``t``), i.e. ``1/a² = α(φ)² tan²θ = (x² αu² + y² αv²)/z²`` from its tangent-frame components
``(x, y, z)``: no division by ``sin θ``, so normal incidence is finite, with finite slopes. With ``αu = αv = m``
both reduce to the isotropic ones.
"""

from collections.abc import Callable
from dataclasses import dataclass

from .._jax import jnp
from .._jax import jsp_special as jsp
from .geometry import tan2_from_cos

#: Beyond this ``a = 1/(m tan θ)`` the Beckmann Λ is below 1e-270: it is taken as its value there (and its slope as
#: 0), which keeps ``exp(−a²)``'s derivative finite where ``a`` runs to infinity (θ → 0).
BECKMANN_A_MAX = 25.0


def beckmann_distribution(cos_theta_h, m):
    """Beckmann 1963 microfacet distribution ``exp(-tan²θh/m²) / (π m² cos⁴θh)``, in 1/sr."""
    cos2 = cos_theta_h * cos_theta_h
    return jnp.exp(-tan2_from_cos(cos_theta_h) / (m * m)) / (jnp.pi * m * m * cos2 * cos2)


def ggx_distribution(cos_theta_h, m):
    """GGX (Trowbridge-Reitz) distribution ``m² / (π cos⁴θh (m² + tan²θh)²)``, in 1/sr (Walter et al. 2007 eq. 33)."""
    cos2 = cos_theta_h * cos_theta_h
    spread = m * m + tan2_from_cos(cos_theta_h)
    return m * m / (jnp.pi * cos2 * cos2 * spread * spread)


def beckmann_anisotropic_distribution(x, y, cos_theta_h, alpha_u, alpha_v):
    """Anisotropic Beckmann ``exp(−(x²/αu² + y²/αv²)/ch²) / (π αu αv ch⁴)``, in 1/sr; ``x = h·t``, ``y = h·b``."""
    cos2 = cos_theta_h * cos_theta_h
    return jnp.exp(-_slope_spread(x, y, cos2, alpha_u, alpha_v)) / (jnp.pi * alpha_u * alpha_v * cos2 * cos2)


def ggx_anisotropic_distribution(x, y, cos_theta_h, alpha_u, alpha_v):
    """Anisotropic GGX ``1 / (π αu αv ch⁴ (1 + (x²/αu² + y²/αv²)/ch²)²)``, in 1/sr; ``x = h·t``, ``y = h·b``
    (Heitz 2014, eq. 85)."""
    cos2 = cos_theta_h * cos_theta_h
    spread = 1.0 + _slope_spread(x, y, cos2, alpha_u, alpha_v)
    return 1.0 / (jnp.pi * alpha_u * alpha_v * cos2 * cos2 * spread * spread)


def _slope_spread(x, y, cos2, alpha_u, alpha_v):
    """``(x²/αu² + y²/αv²)/ch²``: the half vector's slopes, each over its roughness, squared and summed."""
    return ((x / alpha_u) ** 2 + (y / alpha_v) ** 2) / cos2


def beckmann_slope_lambda(slope2):
    """Smith's ``Λ`` for the Beckmann distribution as a function of ``slope2 = 1/a² = α² tan²θ`` (exact, ``erf``)."""
    # 1/a² below 1/A_MAX²: a at its maximum (the sqrt never sees 0, so the slope stays finite at the normal)
    a = 1.0 / jnp.sqrt(jnp.maximum(slope2, 1.0 / (BECKMANN_A_MAX * BECKMANN_A_MAX)))
    return 0.5 * (jnp.exp(-a * a) / (a * jnp.sqrt(jnp.pi)) - jsp.erfc(a))


def ggx_slope_lambda(slope2):
    """Smith's ``Λ`` for the GGX distribution as a function of ``slope2 = 1/a² = α² tan²θ``:
    ``(−1 + sqrt(1 + slope2))/2``."""
    return 0.5 * (jnp.sqrt(1.0 + slope2) - 1.0)


def beckmann_lambda(cos_theta, m):
    """Smith's ``Λ`` for the Beckmann distribution at a direction of zenith cosine ``cos_theta`` (exact, ``erf``)."""
    return beckmann_slope_lambda(m * m * tan2_from_cos(cos_theta))


def ggx_lambda(cos_theta, m):
    """Smith's ``Λ`` for the GGX distribution: ``(−1 + sqrt(1 + m² tan²θ))/2``."""
    return ggx_slope_lambda(m * m * tan2_from_cos(cos_theta))


def anisotropic_slope2(w, alpha_u, alpha_v):
    """``α(φ)² tan²θ = (x² αu² + y² αv²)/z²`` of directions ``w`` (…, 3) given in the tangent frame: the ``1/a²``
    of the anisotropic Smith ``Λ``."""
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return ((x * alpha_u) ** 2 + (y * alpha_v) ** 2) / (z * z)


@dataclass(frozen=True)
class Distribution:
    """A microfacet distribution: ``density(cos θh, m)`` in 1/sr and Smith's ``smith_lambda(cos θ, m)``; anisotropic,
    ``anisotropic_density(h·t, h·b, cos θh, αu, αv)``; and its ``Λ`` as a function of ``1/a²``, ``slope_lambda``."""

    summary: str
    density: Callable
    smith_lambda: Callable
    anisotropic_density: Callable
    slope_lambda: Callable


#: The distributions, by the name the ``distribution`` option takes; the first is the default.
DISTRIBUTIONS = {
    "beckmann": Distribution(
        "Beckmann 1963",
        beckmann_distribution,
        beckmann_lambda,
        beckmann_anisotropic_distribution,
        beckmann_slope_lambda,
    ),
    "ggx": Distribution(
        "GGX (Trowbridge-Reitz 1975)", ggx_distribution, ggx_lambda, ggx_anisotropic_distribution, ggx_slope_lambda
    ),
}


def v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta):
    """Torrance-Sparrow V-groove masking-shadowing ``min(1, 2 ch co/(wo·h), 2 ch ci/(wo·h))``; ``cos_beta = wo·h``."""
    return jnp.minimum(1.0, 2.0 * cos_theta_h * jnp.minimum(cos_i, cos_o) / cos_beta)


def shadowing(kind: str, distribution: Distribution, m, cos_i, cos_o, cos_theta_h, cos_beta):
    """The masking-shadowing term ``kind`` (:data:`SHADOWING`) of ``distribution`` with roughness ``m``."""
    if kind == "v-groove":
        return v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta)
    return smith_shadowing(kind, distribution.smith_lambda(cos_i, m), distribution.smith_lambda(cos_o, m))


def anisotropic_shadowing(kind: str, distribution: Distribution, alpha_u, alpha_v, wi, wo, cos_theta_h, cos_beta):
    """The masking-shadowing term ``kind`` of an anisotropic ``distribution``; ``wi``, ``wo`` (N, 3) in the tangent
    frame. The V-groove term depends on the half vector alone, not on the roughness: it applies as it is."""
    if kind == "v-groove":
        return v_groove_shadowing(wi[:, 2], wo[:, 2], cos_theta_h, cos_beta)
    lambda_i = distribution.slope_lambda(anisotropic_slope2(wi, alpha_u, alpha_v))
    return smith_shadowing(kind, lambda_i, distribution.slope_lambda(anisotropic_slope2(wo, alpha_u, alpha_v)))


def smith_shadowing(kind: str, lambda_i, lambda_o):
    """Smith's masking-shadowing of ``Λ(wi)``, ``Λ(wo)``: separable (``smith``) or height-correlated."""
    if kind == "smith":
        return 1.0 / ((1.0 + lambda_i) * (1.0 + lambda_o))
    return 1.0 / (1.0 + lambda_i + lambda_o)


#: The masking-shadowing terms, by the name the ``shadowing`` option takes, with what each is; the first is the
#: default.
SHADOWING = {
    "v-groove": "V-groove (Torrance-Sparrow)",
    "smith": "separable Smith G1(wi) G1(wo)",
    "smith-correlated": "height-correlated Smith (Heitz 2014)",
}
