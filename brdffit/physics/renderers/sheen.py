"""KHR_materials_sheen's sheen lobe and its directional albedo ``E(μ, sheen_roughness)``, numpy or JAX.

**The lobe** (the extension's "Implementation Notes", non-normative; the Khronos glTF Sample Viewer's ``brdf.glsl``:
``D_Charlie``, ``V_Sheen``, ``BRDF_specularSheen``), in 1/sr, with ``α_g = sheen_roughness²`` (the ratified text and
the viewer square it; the extension's first draft did not) and no Fresnel term::

    f_sheen = sheen_color · D · V
    D       = (2 + 1/α_g) · sin²θh^(1/(2 α_g)) / (2π)                     ("Charlie": Estevez & Kulla 2017)
    V       = min(1, 1 / ((1 + Λ(N·V) + Λ(N·L)) · 4 N·V N·L))               (Charlie's visibility, the viewer's clamp)
    Λ(μ)    = exp(l(μ))                      for μ < 0.5
            = exp(2 l(0.5) − l(1 − μ))       for μ ≥ 0.5
    l(x)    = a/(1 + b x^c) + d x + e,   (a, b, c, d, e) = mix(p₀, p₁, (1 − α_g)²)   (Estevez & Kulla's fit)

``D`` is normalised, ``∫ D cos θh dω_h = 1``. Like the viewer, the roughness is floored at :data:`MIN_SHEEN_ROUGHNESS`
(10⁻⁶); ``sin²θh`` at :data:`MIN_SIN2_H` (its power underflows to 0 long before: a half vector on the normal keeps
finite derivatives).

**The albedo** ``E(μ, r) = ∫ f_sheen(sheen_color = 1) cos θL dω_L``, the lobe's directional albedo seen from ``μ = N·V``
(the lobe is reciprocal, so ``E`` is the same seen from the light). The extension's albedo-scaling layering (Conty
Estevez & Kulla 2017) dims the base by it (``gltf.py``). The viewer reads ``E`` from a precomputed table
(``assets/images/lut_sheen_E.png``, looked up at ``(N·V, sheen_roughness)``); brdffit computes its own by quadrature
of the lobe above, clamp included (:func:`albedo_quadrature`), stores it on a grid (``sheen_table.py``) and
interpolates it with Catmull-Rom cubics (:func:`sheen_albedo`): smooth (C¹), with finite derivatives everywhere, within
10⁻³ of the quadrature for ``μ`` and ``r`` from 0.02 to 1 (median 10⁻⁵; ``tests/physics/test_sheen.py``). ``E`` exceeds
1 at grazing views of smooth sheens (1.61 at ``μ = 0.01``, ``r = 0.05``; 1.36 at ``r = 0.1``): the interpolated ``E`` is
clipped to 1 there, so that the scaling never turns negative. The viewer's table is an image
(``lut_sheen_E.png``), whose values lie in [0, 1] as well; brdffit could not read its numbers from a stored source, so
how close the two are elsewhere is not measured: this module matches the extension's definition of ``E`` (the
directional albedo of the sheen BRDF with Charlie's visibility), not the viewer's table.
"""

import math
from pathlib import Path

import numpy as np

from ..._jax import namespace
from .sheen_table import NODES, SHEEN_ALBEDO

#: The viewer's floor on the sheen roughness (``D_Charlie``, ``V_Sheen``: ``max(sheenRoughness, 0.000001)``).
MIN_SHEEN_ROUGHNESS = 1e-6
#: ``sin²θh`` is floored here before its power: at a half vector on the normal the power is 0 all the same (it is
#: at most ``(10⁻³⁰⁰)^(1/2) = 10⁻¹⁵⁰`` for ``α_g ≤ 1``), and its derivatives stay finite.
MIN_SIN2_H = 1e-300
#: Estevez & Kulla's fit of their sheen's ``Λ`` (the extension's ``l``): ``(a, b, c, d, e)`` at ``α_g = 1`` (``p₀``)
#: and ``α_g = 0`` (``p₁``), mixed by ``(1 − α_g)²``.
LAMBDA_FIT = (
    (21.5473, 3.82987, 0.19823, -1.97760, -4.32054),
    (25.3245, 3.32435, 0.16801, -1.27393, -4.85967),
)
#: The viewer's ceiling on the sheen visibility ``V`` (``V_Sheen``'s ``clamp(…, 0, 1)``).
MAX_SHEEN_VISIBILITY = 1.0
#: The ceiling on the interpolated ``E``: the quadrature's ``E`` exceeds 1 at grazing views of smooth sheens, where the
#: albedo scaling ``1 − max(sheen_color) · E`` would turn negative and subtract the base (a negative BRDF near the
#: mirror, where the sheen's lobe is 0); an image, the viewer's table holds ``E`` in [0, 1].
MAX_SHEEN_ALBEDO = 1.0


def sheen_alpha(sheen_roughness):
    """``α_g = max(sheen_roughness, 10⁻⁶)²``."""
    xp = namespace(sheen_roughness)
    roughness = xp.maximum(sheen_roughness, MIN_SHEEN_ROUGHNESS)
    return roughness * roughness


def charlie_distribution(cos_h, alpha):
    """Estevez & Kulla's (2017) "Charlie" distribution ``(2 + 1/α_g) sin²θh^(1/(2α_g)) / (2π)`` at ``cos_h = N·H``,
    computed as the exponential of its logarithm (a power of 10⁶ and more for smooth sheens)."""
    xp = namespace(cos_h, alpha)
    sin2_h = xp.maximum(1.0 - cos_h * cos_h, MIN_SIN2_H)
    return xp.exp(xp.log(2.0 + 1.0 / alpha) + (0.5 / alpha) * xp.log(sin2_h)) / (2.0 * math.pi)


def _l(x, alpha):
    """The extension's ``l(x, α_g) = a/(1 + b x^c) + d x + e`` for ``x`` in [0, 1]; ``x^c`` is 0 at ``x = 0`` with a
    derivative in ``c`` of 0 (a plain power's would be ``0 · log 0``)."""
    xp = namespace(x, alpha)
    t = (1.0 - alpha) ** 2
    a, b, c, d, e = (p0 + (p1 - p0) * t for p0, p1 in zip(*LAMBDA_FIT, strict=True))
    positive = x > 0.0
    safe = xp.where(positive, x, 1.0)
    power = xp.where(positive, safe**c, 0.0)
    return a / (1.0 + b * power) + d * x + e


def sheen_lambda(cos_theta, alpha):
    """The sheen's ``Λ(μ)``: ``exp(l(μ))`` below ``μ = 0.5``, ``exp(2 l(0.5) − l(1 − μ))`` from there on."""
    xp = namespace(cos_theta, alpha)
    low = xp.minimum(cos_theta, 0.5)  # each branch evaluated where it is finite; the other is discarded
    high = xp.maximum(cos_theta, 0.5)
    return xp.where(
        cos_theta < 0.5, xp.exp(_l(low, alpha)), xp.exp(2.0 * _l(0.5 + 0.0 * alpha, alpha) - _l(1.0 - high, alpha))
    )


def sheen_visibility(cos_i, cos_o, alpha):
    """Charlie's visibility ``min(1, 1/((1 + Λ(N·V) + Λ(N·L)) · 4 N·V N·L))`` (the viewer's ``V_Sheen``)."""
    xp = namespace(cos_i, cos_o, alpha)
    unclamped = 1.0 / ((1.0 + sheen_lambda(cos_o, alpha) + sheen_lambda(cos_i, alpha)) * (4.0 * cos_o * cos_i))
    return xp.minimum(unclamped, MAX_SHEEN_VISIBILITY)


def sheen_lobe(cos_i, cos_o, cos_h, sheen_roughness):
    """``D · V`` (1/sr) of the sheen of roughness ``sheen_roughness`` at ``N·L``, ``N·V``, ``N·H`` (each (N,), both
    cosines in (0, 1]): the sheen of colour 1 (module docstring)."""
    alpha = sheen_alpha(sheen_roughness)
    return charlie_distribution(cos_h, alpha) * sheen_visibility(cos_i, cos_o, alpha)


def albedo_quadrature(cos_o: float, sheen_roughness: float, n: int = 400) -> float:
    """``E(μ, r)`` of the lobe (numpy, float64) seen from ``μ = cos_o`` (at least 10⁻⁶): the midpoint rule on an
    n × n grid in ``(t, φ)``, ``cos θL = t²`` (rows crowded towards the horizon, where a smooth sheen's lobe lies)
    and ``φ`` in (0, π) (the lobe is symmetric about the plane of incidence), ``cos θL dω = 2 t³ dt dφ``.
    n = 400 agrees with n = 800 to 10⁻⁴ over the table's nodes (``tests/physics/test_sheen.py`` checks)."""
    cos_o = max(float(cos_o), 1e-6)
    t = (np.arange(n) + 0.5) / n
    cos_i = (t * t)[:, None]
    phi = ((np.arange(n) + 0.5) * np.pi / n)[None, :]
    sin_i = np.sqrt(1.0 - cos_i * cos_i)
    wi = np.stack(np.broadcast_arrays(sin_i * np.cos(phi), sin_i * np.sin(phi), cos_i), axis=-1)
    wo = np.array([math.sqrt(1.0 - cos_o * cos_o), 0.0, cos_o])
    summed = wi + wo
    cos_h = summed[..., 2] / np.linalg.norm(summed, axis=-1)
    lobe = sheen_lobe(np.broadcast_to(cos_i, cos_h.shape), np.full(cos_h.shape, cos_o), cos_h, sheen_roughness)
    weight = (2.0 * t**3 / n)[:, None] * (np.pi / n)
    return float(2.0 * np.sum(lobe * weight))


def _catmull_rom(values, position):
    """Catmull-Rom interpolation along the last axis of ``values`` (…, M) at ``position`` (…,) in node units, clamped
    to [0, M − 1]; the end intervals take a mirrored node beyond the end (a linear extrapolation). C¹: its
    derivative is finite and continuous."""
    xp = namespace(values, position)
    m = values.shape[-1]
    position = xp.clip(position, 0.0, m - 1.0)
    k = xp.clip(xp.floor(position), 0, m - 2).astype(int)
    s = position - k
    padded = xp.concatenate(
        [2 * values[..., :1] - values[..., 1:2], values, 2 * values[..., -1:] - values[..., -2:-1]], axis=-1
    )
    p0, p1, p2, p3 = (xp.take_along_axis(padded, (k + j)[..., None], axis=-1)[..., 0] for j in range(4))
    return p1 + 0.5 * s * (p2 - p0 + s * (2 * p0 - 5 * p1 + 4 * p2 - p3 + s * (3 * (p1 - p2) + p3 - p0)))


def sheen_albedo(cos_theta, sheen_roughness):
    """``E(μ, r)``: the stored table (``sheen_table.py``, nodes uniform in ``sqrt μ`` and ``sqrt r``) interpolated by
    Catmull-Rom cubics in both, at ``μ = cos_theta`` (N,) and ``r = sheen_roughness`` (a number); clipped to [0, 1]
    (:data:`MAX_SHEEN_ALBEDO`)."""
    xp = namespace(cos_theta, sheen_roughness)
    table = xp.asarray(np.asarray(SHEEN_ALBEDO))  # (roughness nodes, cosine nodes)
    n_roughness, n_cosine = table.shape
    row = xp.sqrt(xp.clip(sheen_roughness, MIN_SHEEN_ROUGHNESS, 1.0)) * (n_roughness - 1)
    along_roughness = _catmull_rom(table.T, xp.broadcast_to(row, (n_cosine,)))  # (cosine nodes,): E at r
    column = xp.sqrt(xp.clip(cos_theta, 1e-12, 1.0)) * (n_cosine - 1)
    rows = xp.broadcast_to(along_roughness, (*xp.shape(column), n_cosine))
    return xp.clip(_catmull_rom(rows, column), 0.0, MAX_SHEEN_ALBEDO)


#: Where ``sheen_table.py``'s table starts: a regeneration (:func:`write_table`) rewrites the file from there.
_TABLE_START = "# fmt: off\n"


def table_text(rows) -> str:
    """The ``SHEEN_ALBEDO`` assignment of ``rows`` (lists of numbers), six numbers a line, to 12 decimals."""
    lines = [_TABLE_START.rstrip("\n"), "SHEEN_ALBEDO = ("]
    for row in rows:
        numbers = [f"{value:.12f}".rstrip("0").rstrip(".") + "," for value in row]
        lines += ["    (", *("        " + " ".join(numbers[k : k + 6]) for k in range(0, len(numbers), 6)), "    ),"]
    return "\n".join([*lines, ")", "# fmt: on"]) + "\n"


def computed_table(nodes: int = NODES) -> list[list[float]]:
    """``E`` at ``r = (i/(nodes − 1))²``, ``μ = (j/(nodes − 1))²`` by :func:`albedo_quadrature` (rows ``i``)."""
    return [
        [albedo_quadrature((j / (nodes - 1)) ** 2, (i / (nodes - 1)) ** 2) for j in range(nodes)] for i in range(nodes)
    ]


def write_table() -> None:
    """Rewrite ``sheen_table.py``'s table from :func:`computed_table` (its docstring and ``NODES`` kept)."""
    path = Path(__file__).with_name("sheen_table.py")
    text = path.read_text()
    path.write_text(text[: text.rindex(_TABLE_START)] + table_text(computed_table()))


if __name__ == "__main__":
    write_table()
