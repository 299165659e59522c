"""Fresnel reflectance of a smooth interface, unpolarised, as a function of ``cos β``, and the registry of kinds.

``cos β = wi·h`` is the cosine of the angle between the light and the microfacet normal. All functions
return a value in [0, 1] and have finite derivatives for ``cos β ∈ (0, 1]``. :data:`FRESNEL` maps the
names Cook-Torrance's ``fresnel`` option takes to a :class:`Fresnel`: its parameters (with their domains
and the values the fit starts from) and its reflectance.
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._jax import jnp
from .domains import UNIT_INTERVAL, GreaterThan, MappedDomain, Positive


def fresnel_schlick(cos_beta, f0):
    """Schlick 1994: ``F = f0 + (1 - f0)(1 - cos β)⁵``, ``f0 ∈ [0, 1]`` the normal-incidence reflectance."""
    return f0 + (1.0 - f0) * (1.0 - cos_beta) ** 5


def fresnel_dielectric(cos_beta, eta):
    """Exact unpolarised Fresnel reflectance of a dielectric with relative index ``eta > 1``.

    Cook & Torrance 1982, eq. in their appendix::

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


#: A conductor's refractive index: metals in the visible lie within 0.05–5 (silver to titanium); above 10 the
#: interface is a mirror at every angle (F → 1), which a fit reaches when the data want no Fresnel term at all.
CONDUCTOR_INDEX = Positive(plausible_max=10.0)
#: A conductor's extinction coefficient: 0 for a dielectric, up to ~10 for metals in the visible (aluminium).
CONDUCTOR_EXTINCTION = Positive(allow_zero=True, plausible_max=20.0)


@dataclass(frozen=True)
class Fresnel:
    """A kind of Fresnel term: its parameters ``(name, domain, starting values)`` and ``reflectance(cos β, shape)``.

    ``per_channel``: the parameters that take one value per channel (a conductor's complex index, which disperses),
    the last of ``parameters``; ``reflectance`` broadcasts them against ``cos β`` (``cos β[:, None]`` and values
    (C,) give (N, C)).
    """

    summary: str
    parameters: tuple[tuple[str, MappedDomain, tuple[float, ...]], ...]
    reflectance: Callable[[Any, Mapping[str, Any]], Any]
    #: The reflectance at normal incidence of a shape of numbers (numpy, never traced; Pharr, Jakob & Humphreys,
    #: *PBRT* §8.2: ``((η − 1)² + k²)/((η + 1)² + k²)``, Schlick's ``f0``): where it is 0 the lobe reflects nothing.
    at_normal: Callable[[Mapping[str, Any]], Any] = lambda shape: 1.0
    per_channel: tuple[str, ...] = ()


def _conductor_at_normal(eta, k):
    """A conductor's reflectance at normal incidence, ``((η − 1)² + k²)/((η + 1)² + k²)`` (numpy)."""
    return ((eta - 1.0) ** 2 + k * k) / ((eta + 1.0) ** 2 + k * k)


#: The kinds of Fresnel term, by the name the ``fresnel`` option takes; the first is the default.
FRESNEL = {
    "schlick": Fresnel(
        "Schlick 1994",
        (("f0", UNIT_INTERVAL, (0.04, 0.3, 0.9)),),
        lambda c, shape: fresnel_schlick(c, shape["f0"]),
        lambda shape: np.asarray(shape["f0"], float),
    ),
    "dielectric": Fresnel(
        "exact, real index eta",
        (("eta", GreaterThan(1.0, plausible_margin=1e-6), (1.5, 3.0)),),
        lambda c, shape: fresnel_dielectric(c, shape["eta"]),
        lambda shape: ((np.asarray(shape["eta"], float) - 1.0) / (np.asarray(shape["eta"], float) + 1.0)) ** 2,
    ),
    "conductor": Fresnel(
        "exact, complex index eta + i k per channel",
        # Starts: metals (eta < 1.5, k of 1 to 6) and, with k = 0, dielectric-like interfaces, where a fit of a
        # material that is no metal ends (the pickled-oak example: eta 19, k 0, cost 2.98 where the metal starts
        # alone stopped at eta → ∞, i.e. F = 1, cost 4.38). With ks held at 1 the albedos no longer absorb a wrong
        # index, so the grid is finer than the 3 × 3 (0.5, 1.5, 4 × 0, 1, 4) it was: on 12 random per-channel
        # metals (1% noise) that grid's default fit missed the best cost once, this one never; the search also
        # starts from measured metals (metals.py, Lobe.channel_grid).
        (
            ("eta", CONDUCTOR_INDEX, (0.2, 0.5, 1.0, 1.5, 2.5, 4.0)),
            ("k", CONDUCTOR_EXTINCTION, (0.0, 1.0, 2.0, 3.0, 4.0, 6.0)),
        ),
        lambda c, shape: fresnel_conductor(c, shape["eta"], shape["k"]),
        lambda shape: _conductor_at_normal(np.asarray(shape["eta"], float), np.asarray(shape["k"], float)),
        per_channel=("eta", "k"),
    ),
    "none": Fresnel("F = 1", (), lambda c, shape: jnp.ones_like(c)),
}
