"""Fresnel reflectance of a smooth interface, unpolarised, as a function of ``cos β``.

``cos β = wi·h`` is the cosine of the angle between the light and the
microfacet normal (SPEC section 1). All functions return a value in [0, 1] and
have finite derivatives for ``cos β ∈ (0, 1]``.
"""

import jax.numpy as jnp

from .. import _jax  # noqa: F401  (float64 before any array)


def fresnel_schlick(cos_beta, f0):
    """Schlick 1994: ``F = f0 + (1 - f0)(1 - cos β)⁵``, ``f0 ∈ [0, 1]`` the normal-incidence reflectance."""
    return f0 + (1.0 - f0) * (1.0 - cos_beta) ** 5


def fresnel_dielectric(cos_beta, eta):
    """Exact unpolarised Fresnel reflectance of a dielectric with relative index ``eta > 1``.

    Cook & Torrance 1982, eq. in their appendix (SPEC section 2)::

        g = sqrt(eta² + c² - 1)
        F = ½ (g-c)²/(g+c)² · (1 + (c(g+c) - 1)² / (c(g-c) + 1)²)
    """
    c = cos_beta
    g = jnp.sqrt(eta * eta + c * c - 1.0)
    ratio = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * ((g - c) / (g + c)) ** 2 * (1.0 + ratio * ratio)


def fresnel_conductor(cos_beta, eta, k):
    """Exact unpolarised Fresnel reflectance for a complex index ``eta + i k`` (``eta > 0``, ``k ≥ 0``).

    The real-arithmetic form of the complex Fresnel equations (Born & Wolf;
    as written in Pharr, Jakob & Humphreys, *PBRT* 3rd ed., §8.2.1,
    ``FrConductor``), with ``a² + b² = |n̂² - sin²β|`` and ``a = Re sqrt(n̂² - sin²β)``::

        Rs = (a² + b² - 2a c + c²) / (a² + b² + 2a c + c²)
        Rp = Rs (c²(a² + b²) - 2a c s² + s⁴) / (c²(a² + b²) + 2a c s² + s⁴)
        F  = (Rs + Rp) / 2
    """
    c = cos_beta
    cos2 = c * c
    sin2 = 1.0 - cos2
    t0 = eta * eta - k * k - sin2
    a2_plus_b2 = jnp.sqrt(t0 * t0 + 4.0 * eta * eta * k * k)
    # a = 0 only for k = 0 and eta ≤ sin β (total reflection); keep its derivative finite.
    tiny = jnp.finfo(jnp.result_type(c)).tiny
    a = jnp.sqrt(jnp.maximum(0.5 * (a2_plus_b2 + t0), tiny))
    t1 = a2_plus_b2 + cos2
    t2 = 2.0 * c * a
    rs = (t1 - t2) / (t1 + t2)
    t3 = cos2 * a2_plus_b2 + sin2 * sin2
    t4 = t2 * sin2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)
