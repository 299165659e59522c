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


def beckmann_lambda(cos_theta, m):
    """Smith's ``Λ`` for the Beckmann distribution at a direction of zenith cosine ``cos_theta`` (exact, ``erf``)."""
    floor = 1.0 / (BECKMANN_A_MAX * m)  # tan θ below it: a at its maximum (the sqrt never sees 0: finite slopes)
    a = 1.0 / (m * jnp.sqrt(jnp.maximum(tan2_from_cos(cos_theta), floor * floor)))
    return 0.5 * (jnp.exp(-a * a) / (a * jnp.sqrt(jnp.pi)) - jsp.erfc(a))


def ggx_lambda(cos_theta, m):
    """Smith's ``Λ`` for the GGX distribution: ``(−1 + sqrt(1 + m² tan²θ))/2``."""
    return 0.5 * (jnp.sqrt(1.0 + m * m * tan2_from_cos(cos_theta)) - 1.0)


@dataclass(frozen=True)
class Distribution:
    """A microfacet distribution: ``density(cos θh, m)`` in 1/sr and Smith's ``smith_lambda(cos θ, m)``."""

    summary: str
    density: Callable
    smith_lambda: Callable


#: The distributions, by the name the ``distribution`` option takes; the first is the default.
DISTRIBUTIONS = {
    "beckmann": Distribution("Beckmann 1963", beckmann_distribution, beckmann_lambda),
    "ggx": Distribution("GGX (Trowbridge-Reitz 1975)", ggx_distribution, ggx_lambda),
}


def v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta):
    """Torrance-Sparrow V-groove masking-shadowing ``min(1, 2 ch co/(wo·h), 2 ch ci/(wo·h))``; ``cos_beta = wo·h``."""
    return jnp.minimum(1.0, 2.0 * cos_theta_h * jnp.minimum(cos_i, cos_o) / cos_beta)


def shadowing(kind: str, distribution: Distribution, m, cos_i, cos_o, cos_theta_h, cos_beta):
    """The masking-shadowing term ``kind`` (:data:`SHADOWING`) of ``distribution`` with roughness ``m``."""
    if kind == "v-groove":
        return v_groove_shadowing(cos_i, cos_o, cos_theta_h, cos_beta)
    lambda_i, lambda_o = distribution.smith_lambda(cos_i, m), distribution.smith_lambda(cos_o, m)
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
