"""Ward's elliptical Gaussian lobe and Dür's normalisation of it.

Ward, "Measuring and modeling anisotropic reflection", SIGGRAPH 1992, eq. 5
(isotropic) and eq. 4 (anisotropic); Dür, "An improved normalization for the
Ward reflectance model", JGT 2006 (``ward-duer``)::

    ward        rho_s · exp(-tan²θh / α²) / (4π α² sqrt(ci co))
    ward-aniso  rho_s · exp(-((h_x/α_x)² + (h_y/α_y)²) / h_z²) / (4π α_x α_y sqrt(ci co))
    ward-duer   rho_s · exp(-tan²θh / α²) / (4π α² ci co)
"""

from dataclasses import dataclass
from typing import final

from ..._jax import jnp
from ..domains import ALBEDO, ROUGHNESS
from ..geometry import half_vector, tan2_from_cos
from .grids import ROUGHNESS_GRID
from .lobe import MappedLobe
from .model import LobeModel, ModelEntry


@final
@dataclass(frozen=True)
class WardLobe(MappedLobe):
    """Isotropic Ward lobe, roughness ``alpha`` (rms slope); ``duer`` selects Dür's ``ci co`` denominator."""

    duer: bool = False

    @property
    def summary(self) -> str:
        return "Dür's normalisation 4π α² ci co" if self.duer else "Gaussian in tan θh, 4π α² sqrt(ci co)"

    albedo_domain = ALBEDO
    peaks_at_mirror = True

    @property
    def parameters(self):
        return (("alpha", ROUGHNESS),)

    @property
    def grid(self):
        return tuple({"alpha": alpha} for alpha in ROUGHNESS_GRID)

    def __call__(self, shape, wi, wo):
        alpha2 = shape["alpha"] ** 2
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        h = half_vector(wi, wo)
        projected = cos_i * cos_o if self.duer else jnp.sqrt(cos_i * cos_o)
        return jnp.exp(-tan2_from_cos(h[:, 2]) / alpha2) / (4.0 * jnp.pi * alpha2 * projected)


@final
@dataclass(frozen=True)
class AnisotropicWardLobe(MappedLobe):
    """Anisotropic Ward lobe with roughness ``alpha_x`` along the tangent and ``alpha_y`` across it."""

    summary = "anisotropic Gaussian, α_x along the tangent x, α_y along y"

    albedo_domain = ALBEDO
    peaks_at_mirror = True

    @property
    def parameters(self):
        return (("alpha_x", ROUGHNESS), ("alpha_y", ROUGHNESS))

    @property
    def grid(self):
        ratios = (0.5, 1.0, 2.0)
        return tuple({"alpha_x": alpha, "alpha_y": alpha * ratio} for alpha in ROUGHNESS_GRID for ratio in ratios)

    def __call__(self, shape, wi, wo):
        alpha_x, alpha_y = shape["alpha_x"], shape["alpha_y"]
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        h = half_vector(wi, wo)
        exponent = ((h[:, 0] / alpha_x) ** 2 + (h[:, 1] / alpha_y) ** 2) / h[:, 2] ** 2
        return jnp.exp(-exponent) / (4.0 * jnp.pi * alpha_x * alpha_y * jnp.sqrt(cos_i * cos_o))


def ward() -> LobeModel:
    return LobeModel("ward", "Ward 1992, isotropic", WardLobe(), 1)


def ward_aniso() -> LobeModel:
    return LobeModel("ward-aniso", "Ward 1992, anisotropic", AnisotropicWardLobe(), 1, isotropic=False)


def ward_duer() -> LobeModel:
    return LobeModel("ward-duer", "Ward with Dür's 2006 normalisation", WardLobe(duer=True), 1)


WARD = ModelEntry(ward, compare=("ward",))
WARD_ANISO = ModelEntry(ward_aniso, compare=("ward-aniso",))
WARD_DUER = ModelEntry(ward_duer, compare=("ward-duer",))
