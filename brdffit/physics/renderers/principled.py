"""Mitsuba 3's ``principled`` BSDF, reflection only, evaluated in JAX exactly as Mitsuba 3.9.1 evaluates it.

Sources: Mitsuba 3.9.1, ``src/bsdfs/principled.cpp`` (``Principled::eval`` and the plugin's documentation),
``src/bsdfs/principledhelpers.h`` (``calc_dist_params``, ``principled_fresnel``, ``calc_schlick``,
``schlick_weight``, ``schlick_R0_eta``, ``GTR1Isotropic``, ``clearcoat_G``, ``smith_ggx1``),
``include/mitsuba/render/microfacet.h`` (GGX ``eval``, ``smith_g1``, ``G``), ``include/mitsuba/render/fresnel.h``
(``fresnel``), ``include/mitsuba/core/spectrum.h`` (``luminance``); after Burley, "Physically-based shading at
Disney" (SIGGRAPH 2012 course) and "Extending the Disney BRDF to a BSDF with integrated subsurface scattering"
(SIGGRAPH 2015 course). Only the opaque plugin: ``spec_trans = 0`` (no transmission lobe), ``flatness = 0`` (no
fake subsurface), not ``principledthin``. Values in 1/sr, per channel of ``base_color``.

Directions: unit vectors in the shading frame, ``z`` the normal, ``+x`` the tangent (Mitsuba's ``s``, along which
``alpha_u`` lies); ``wi`` towards the light, ``wo`` towards the viewer. Mitsuba's ``eval(ctx, si, wo)`` takes them
the other way round: ``si.wi`` is the viewer (here ``wo``), its argument the light (here ``wi``), and it returns
``f · cos θ`` of the light, which this module leaves out. With ``ci = wi_z``, ``co = wo_z``,
``h = normalize(wi + wo)``, ``ch = h_z``, ``cd = wi·h = wo·h`` (but see Reciprocity) and Schlick's weight
``S(c) = (1 − c)⁵``, ``f`` is the sum of four lobes:

* **diffuse with retro-reflection** (Burley 2015's diffuse model), with the raw ``roughness``, not ``α``::

      (1 − metallic) · base_color/π · [(1 − S(ci)/2)(1 − S(co)/2) + R (S(ci) + S(co) + S(ci) S(co) (R − 1))],
      R = 2 roughness cd²

* **sheen** (Burley 2012; no 1/π, as in Burley's BRDF Explorer shader ``disney.brdf``)::

      sheen · (1 − metallic) · S(cd) · lerp(1, tint, sheen_tint),   tint = base_color / luminance(base_color)

  (``tint = 1`` where the luminance is 0);

* **specular**, anisotropic GGX with separable Smith shadowing (``microfacet.py``; Mitsuba's
  ``MicrofacetDistribution`` GGX ``eval`` and ``G``)::

      F · D(h) · G1(wi) G1(wo) / (4 ci co),
      D = 1 / (π αu αv (h_x²/αu² + h_y²/αv² + ch²)²),   G1(w) = 2 / (1 + sqrt(1 + (αu² w_x² + αv² w_y²)/w_z²)),
      αu = max(0.001, roughness²/aspect),   αv = max(0.001, roughness² · aspect),   aspect = sqrt(1 − 0.9 anisotropic)

  (Burley 2012's aspect mapping; the 0.001 floor is Mitsuba's ``calc_dist_params``; ``MicrofacetDistribution``
  would clamp at 1e-4, never reached). Its Fresnel term blends a dielectric, a metal and a tinted dielectric
  (``principled_fresnel``)::

      F = (1 − metallic)(1 − spec_tint) Fd(cd, η) + metallic · Sch(cd, base_color)
          + (1 − metallic) spec_tint · Sch(cd, tint · R0),
      Sch(c, f0) = f0 + (1 − f0) S(c),   R0 = ((η − 1)/(η + 1))² = 0.08 specular,
      η = 2 / (1 − sqrt(0.08 specular)) − 1

  with ``Fd`` the exact unpolarised dielectric Fresnel (``fresnel.py``'s :func:`fresnel_dielectric`, equal to
  Mitsuba's ``fresnel()`` for ``η ≥ 1`` and ``cd > 0``). ``specular ∈ [0, 1]`` spans ``η ∈ [1, 1.789]``; Mitsuba's
  ``eta`` may replace ``specular`` (never both), ``specular = ((η − 1)/(η + 1))² / 0.08``: this module takes
  ``specular``. Mitsuba drops the whole lobe, its metal and tint parts too, where ``Fd = 0``: at ``specular = 0``
  (``η = 1``, index-matched; its mask ``F_spec_dielectric > 0``), which is reproduced. (Mitsuba's
  ``parameters_changed``, after an update of ``specular`` through ``traverse``, turns 0 into 1e-3; a loaded
  scene keeps 0.)

* **clearcoat**, GTR1 with a fixed-roughness Smith term (``GTR1Isotropic``, ``clearcoat_G``)::

      0.25 clearcoat · Sch(cd, 0.04) · D1(ch) · G1(wi; 0.25) G1(wo; 0.25),
      D1 = (α² − 1) / (π ln(α²) (1 + (α² − 1) ch²)),   α = lerp(0.1, 0.001, clearcoat_gloss)

  with ``G1(w; 0.25)`` the isotropic GGX ``G1`` of ``α = 0.25`` (Burley 2012's fixed coat shadowing). Mitsuba's
  coat has no ``1/(4 ci co)``: Burley's shader writes ``smithG_GGX = 1/(c + sqrt(α² + c² − α² c²)) = G1/(2c)``,
  which carries it; Mitsuba's ``smith_ggx1`` is the plain ``G1``. Mitsuba's coat is therefore ``4 ci co`` times
  Burley's (4× at normal incidence, less towards grazing); this module follows Mitsuba.

Reciprocity. Mitsuba takes each direction in its own role: the Fresnel terms (specular and clearcoat) at the
viewer's ``wo·h`` (its ``dot(si.wi, wh)``), the retro-reflection's and the sheen's ``cd`` at the light's ``wi·h``
(its ``dot(wh, wo)``), the specular lobe over ``4 |cos θ|`` of the viewer times the light's ``cos θ``, and
``front_side`` (the lobes' mask) from the viewer's ``cos θ``; this module keeps each choice. For unit directions
above the horizon ``wi·h = wo·h`` and every lobe is symmetric in ``ci``, ``co`` (the diffuse, retro-reflection and
Smith terms are products or sums of one function of each), so ``f(wi, wo) = f(wo, wi)``: opaque, Mitsuba's
principled is reciprocal. Directions a rounding leaves off unit length (float32 files, Mitsuba's ``Vector3f``) break
it slightly, the same way in both: ``wi·h − wo·h = (|wi|² − |wo|²)/|wi + wo|``, about 4e-6 in ``cd`` (and
relatively as much in ``f``) for a mirror pair at 89°, where ``|wi + wo|`` is small. The viewer's side matters
otherwise only below the horizon, where for ``spec_trans = 0`` every lobe is 0 (the specular one is
``bsdf · Fd = 0`` on the back side, the others need ``front_side``): this function returns 0 wherever ``wi_z ≤ 0``
or ``wo_z ≤ 0``.

Parameters outside [0, 1]. Mitsuba also masks lobes whose weight is not positive (``(1 − metallic) > 0``,
``sheen > 0``, ``clearcoat > 0``); their weight is then a factor of the lobe, 0 at the bound, so the formulas
above equal Mitsuba's on the whole of :data:`PARAMETERS`' box without those masks, and keep the one-sided
derivatives at its bounds (at ``metallic = 1`` the diffuse lobe's derivative is ``−diffuse``, not 0). Below
``specular ≈ 1e-14`` Mitsuba's float32 ``η`` rounds to 1 and drops the specular lobe; float64 keeps it.

Channels: ``base_color`` (C,), C = 3 (linear RGB, Mitsuba's ``*_rgb`` variants: luminance with
:data:`LUMINANCE_WEIGHTS`) or C = 1 (Mitsuba's ``*_mono`` variants, where the luminance is the value itself, so the
tints are 1). Spectral variants weigh the luminance by CIE ȳ at the sampled wavelengths, which C channels alone do
not determine: other C are refused.
"""

from collections.abc import Mapping
from typing import Any

from ..._jax import jnp
from ...checks import choice
from ...errors import Argument, BrdfInputError
from ..fresnel import fresnel_dielectric, fresnel_schlick
from ..geometry import above_horizon, half_vector
from ..microfacet import anisotropic_slope2, ggx_anisotropic_distribution, ggx_lambda, ggx_slope_lambda, smith_shadowing

#: Mitsuba's default of each parameter (``Principled``'s constructor; ``base_color`` 0.5 in every channel).
DEFAULTS: dict[str, Any] = {  # numbers, and base_color's (r, g, b)
    "base_color": (0.5, 0.5, 0.5),
    "roughness": 0.5,
    "metallic": 0.0,
    "specular": 0.5,
    "spec_tint": 0.0,
    "anisotropic": 0.0,
    "sheen": 0.0,
    "sheen_tint": 0.0,
    "clearcoat": 0.0,
    "clearcoat_gloss": 0.0,
}

#: ``(name, per_channel, lower, upper)`` of each parameter: "all of the parameters except sampling rates and eta
#: should take values between 0.0 and 1.0" (the plugin's documentation, ``principled.cpp``).
PARAMETERS = tuple((name, name == "base_color", 0.0, 1.0) for name in DEFAULTS)

#: Mitsuba's luminance of a linear RGB colour (``spectrum.h``, ``luminance(Color3f)``: the Y row of linear
#: Rec. 709 / sRGB to CIE XYZ).
LUMINANCE_WEIGHTS = (0.212671, 0.715160, 0.072169)

#: The floor of the specular lobe's ``αu``, ``αv`` (``calc_dist_params``).
ALPHA_MIN = 0.001
#: The clearcoat's GTR1 ``α`` at ``clearcoat_gloss`` 0 and 1 (``lerp(0.1, 0.001, clearcoat_gloss)``).
CLEARCOAT_ALPHA_RANGE = (0.1, 0.001)
#: The clearcoat's fixed Smith roughness (``clearcoat_G(…, 0.25)``) and normal-incidence reflectance (``0.04``).
CLEARCOAT_SHADOWING_ALPHA = 0.25
CLEARCOAT_F0 = 0.04


def principled_brdf(params: Mapping, wi, wo):
    """Mitsuba 3's ``principled`` BRDF (N, C) in 1/sr, without the cosine Mitsuba's ``eval`` includes; 0 where
    ``wi_z ≤ 0`` or ``wo_z ≤ 0``.

    ``params``: ``base_color`` (C,) and the scalars of :data:`PARAMETERS` (each missing one at its
    :data:`DEFAULTS`); ``wi`` towards the light, ``wo`` towards the viewer, unit (N, 3) in the shading frame,
    tangent ``+x``. JAX-traceable and differentiable in every parameter; float32 or float64 as its inputs. The
    lobes, their sources and the directions' roles: the module docstring.
    """
    for name in params:
        choice("parameter", name, DEFAULTS, verb="is not a principled parameter")
    wi, wo = jnp.asarray(wi), jnp.asarray(wo)
    dtype = jnp.result_type(wi, wo)
    p = {name: _floating(params[name]) if name in params else jnp.asarray(DEFAULTS[name], dtype) for name in DEFAULTS}
    base_color = p["base_color"]
    luminance = _luminance(base_color)

    visible, wi, wo = above_horizon(wi, wo)
    h = half_vector(wi, wo)
    # wi·h = wo·h for unit directions; Mitsuba takes the light's for the retro-reflection and the sheen, the viewer's
    # for the Fresnel terms, which differ where rounding leaves the directions off unit length
    cos_d_light, cos_d_viewer = jnp.sum(wi * h, axis=-1), jnp.sum(wo * h, axis=-1)
    weight_i, weight_o = _schlick_weight(wi[:, 2]), _schlick_weight(wo[:, 2])
    dielectric = 1.0 - p["metallic"]

    retro = 2.0 * p["roughness"] * cos_d_light * cos_d_light
    diffuse = (1.0 - 0.5 * weight_i) * (1.0 - 0.5 * weight_o)
    diffuse += retro * (weight_i + weight_o + weight_i * weight_o * (retro - 1.0))
    value = (dielectric / jnp.pi) * diffuse[:, None] * base_color

    sheen_colour = 1.0 + p["sheen_tint"] * (_tint(base_color, luminance) - 1.0)
    value += (p["sheen"] * dielectric) * _schlick_weight(cos_d_light)[:, None] * sheen_colour

    value += _specular(p, base_color, luminance, wi, wo, h, cos_d_viewer)
    value += _clearcoat(p, wi, wo, h, cos_d_viewer)[:, None]
    return jnp.where(visible[:, None], value, 0.0)


def eta_of_specular(specular):
    """Mitsuba's relative index ``η = 2 / (1 − sqrt(0.08 specular)) − 1`` of ``specular`` (the inverse of
    ``specular = ((η − 1)/(η + 1))² / 0.08``, Burley 2012's normal-incidence reflectance ``0.08 specular``)."""
    # sqrt's slope is infinite at 0; the floor keeps it finite (the lobe is dropped at specular = 0 anyway)
    tiny = jnp.finfo(_floating(specular).dtype).tiny
    return 2.0 / (1.0 - jnp.sqrt(jnp.maximum(0.08 * specular, tiny))) - 1.0


def schlick_r0(eta):
    """Normal-incidence reflectance ``((η − 1)/(η + 1))²`` of a relative index ``η`` (``schlick_R0_eta``)."""
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def principled_alphas(roughness, anisotropic):
    """The specular lobe's GGX ``(αu, αv)`` (``calc_dist_params``): ``max(0.001, roughness²/aspect)`` along the
    tangent, ``max(0.001, roughness² · aspect)`` across it, ``aspect = sqrt(1 − 0.9 anisotropic)``."""
    aspect = jnp.sqrt(1.0 - 0.9 * anisotropic)
    alpha2 = roughness * roughness
    return jnp.maximum(ALPHA_MIN, alpha2 / aspect), jnp.maximum(ALPHA_MIN, alpha2 * aspect)


def gtr1_distribution(cos_theta_h, alpha):
    """Burley's GTR1 (2012, GTR with γ = 1) ``(α² − 1) / (π ln(α²) (1 + (α² − 1) ch²))``, in 1/sr, ``0 < α < 1``
    (``GTR1Isotropic::eval``)."""
    alpha2 = alpha * alpha
    return (alpha2 - 1.0) / (jnp.pi * jnp.log(alpha2) * (1.0 + (alpha2 - 1.0) * cos_theta_h * cos_theta_h))


def _floating(value):
    """``value`` as a JAX array of a floating type: its own, or the default float for integers and Python numbers
    (weakly typed, so that float32 directions keep float32)."""
    value = jnp.asarray(value)
    return value.astype(jnp.result_type(value, float))


def _schlick_weight(cos):
    """Schlick's weight ``(1 − cos)⁵`` (``schlick_weight``; ``fresnel_schlick`` with ``f0 = 0``)."""
    return fresnel_schlick(cos, 0.0)


def _luminance(base_color):
    """Mitsuba's luminance of ``base_color`` (C,): :data:`LUMINANCE_WEIGHTS` for C = 3, the value for C = 1."""
    shape = tuple(base_color.shape)
    if shape == (3,):
        return jnp.sum(base_color * jnp.asarray(LUMINANCE_WEIGHTS, dtype=base_color.dtype))
    if shape == (1,):
        return base_color[0]
    raise BrdfInputError(
        Argument("base_color"),
        f" has shape {shape}; give 3 channels (linear RGB) or 1 (monochrome), the two whose luminance Mitsuba knows",
    )


def _tint(base_color, luminance):
    """``base_color / luminance``, 1 where the luminance is not positive (``c_tint``)."""
    positive = luminance > 0.0
    return jnp.where(positive, base_color / jnp.where(positive, luminance, 1.0), 1.0)


def _specular(p, base_color, luminance, wi, wo, h, cos_d):
    """The anisotropic GGX lobe with the principled Fresnel blend, (N, C); 0 at ``specular = 0``."""
    alpha_u, alpha_v = principled_alphas(p["roughness"], p["anisotropic"])
    density = ggx_anisotropic_distribution(h[:, 0], h[:, 1], h[:, 2], alpha_u, alpha_v)
    lambda_i = ggx_slope_lambda(anisotropic_slope2(wi, alpha_u, alpha_v))
    lambda_o = ggx_slope_lambda(anisotropic_slope2(wo, alpha_u, alpha_v))
    unit = density * smith_shadowing("smith", lambda_i, lambda_o) / (4.0 * wi[:, 2] * wo[:, 2])

    metallic, spec_tint = p["metallic"], p["spec_tint"]
    eta = eta_of_specular(p["specular"])
    cos_d = cos_d[:, None]
    fresnel = ((1.0 - metallic) * (1.0 - spec_tint)) * fresnel_dielectric(cos_d, eta)
    fresnel += metallic * fresnel_schlick(cos_d, base_color)
    fresnel += ((1.0 - metallic) * spec_tint) * fresnel_schlick(cos_d, _tint(base_color, luminance) * schlick_r0(eta))
    # Mitsuba's mask F_spec_dielectric > 0: no lobe at all where the dielectric is index-matched
    return jnp.where(p["specular"] > 0.0, fresnel * unit[:, None], 0.0)


def _clearcoat(p, wi, wo, h, cos_d):
    """The clearcoat lobe (N,): ``0.25 clearcoat · Sch(cd, 0.04) · GTR1 · G1 G1`` (α 0.25), no ``1/(4 ci co)``."""
    low, high = CLEARCOAT_ALPHA_RANGE
    alpha = low + p["clearcoat_gloss"] * (high - low)
    lambda_i = ggx_lambda(wi[:, 2], CLEARCOAT_SHADOWING_ALPHA)
    lambda_o = ggx_lambda(wo[:, 2], CLEARCOAT_SHADOWING_ALPHA)
    shadowing = smith_shadowing("smith", lambda_i, lambda_o)
    return (
        (0.25 * p["clearcoat"]) * fresnel_schlick(cos_d, CLEARCOAT_F0) * gtr1_distribution(h[:, 2], alpha) * shadowing
    )
