"""The maps between BRDF values and the space a basis is linear in (Nielsen, Jensen and Ramamoorthi 2015).

With ``w = cos θi · cos θo`` (the cosine weight of the pair) and ``ε`` = :data:`EPSILON` (1/sr):

============  ==============================================  ==============================================
mapping       mapped value ``m(ρ)``                           BRDF ``ρ(m)``
============  ==============================================  ==============================================
log-relative  ``ln((ρ·w + ε) / (ρ_ref·w + ε))``               ``((ρ_ref·w + ε)·eᵐ − ε) / w``
log           ``ln(ρ·w + ε)``                                 ``(eᵐ − ε) / w``
none          ``ρ``                                           ``m``
============  ==============================================  ==============================================

``ρ_ref`` is the library's median at each bin. The logarithm compresses the specular peaks' dynamic range so that
no bin dominates the principal components; the cosine weight puts grazing bins, which a renderer rarely needs and
a measurement rarely gets right, at the floor ``ε``. Log-relative (Nielsen's) is the default. A BRDF is never
below 0: the inverse is clipped there. numpy or JAX.
"""

from .._jax import namespace

MAPPINGS = ("log-relative", "log", "none")
#: ε of the maps, in 1/sr (Nielsen et al. 2015).
EPSILON = 1e-3


def cosine_weight(wi, wo):
    """``cos θi · cos θo`` of the pairs (N,), never below 0."""
    xp = namespace(wi, wo)
    return xp.maximum(wi[..., 2], 0.0) * xp.maximum(wo[..., 2], 0.0)


def mapped(mapping: str, rho, reference, weight):
    """The mapped values ``m(ρ)`` (ρ clipped at 0); ``reference`` and ``weight`` broadcast against ``rho``."""
    xp = namespace(rho, reference, weight)
    rho = xp.maximum(rho, 0.0)
    if mapping == "log-relative":
        return xp.log((rho * weight + EPSILON) / (reference * weight + EPSILON))
    if mapping == "log":
        return xp.log(rho * weight + EPSILON)
    return rho


def unmapped(mapping: str, m, reference, weight):
    """The BRDF ``ρ(m)`` (1/sr), at least 0, finite wherever ``weight > 0``."""
    xp = namespace(m, reference, weight)
    if mapping == "log-relative":
        rho = ((reference * weight + EPSILON) * xp.exp(m) - EPSILON) / weight
    elif mapping == "log":
        rho = (xp.exp(m) - EPSILON) / weight
    else:
        rho = m
    return xp.maximum(rho, 0.0)
