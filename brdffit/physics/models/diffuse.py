"""The diffuse term every lobe model has: a component like a lobe, with albedo ``rho_d`` per channel.

Lambert, *Photometria* (1760): a perfectly diffuse surface reflects ``rho_d/π`` in every direction, so its term of
unit albedo is ``1/π`` (1/sr). It is a :class:`~brdffit.physics.models.lobe.Lobe` without shape parameters, and
every part of brdffit that needs the diffuse term asks it: a model's evaluation (``model.py``), the linear basis of
the fit's Jacobian (``fitting/objective/jacobian.py``), the start search (``fitting/starts/grid.py``) and the
caveats' lobe shares (``fitting/single/caveats.py``). A diffuse term with shape parameters of its own (Oren-Nayar's
roughness) is not supported yet: ``LobeModel`` refuses one.
"""

from dataclasses import dataclass
from typing import final

from ..._jax import jnp
from ..domains import ALBEDO
from .lobe import MappedLobe


@final
@dataclass(frozen=True)
class Lambertian(MappedLobe):
    """The perfectly diffuse term of unit albedo, ``1/π`` (Lambert 1760)."""

    summary = "perfectly diffuse, 1/π"
    albedo_domain = ALBEDO
    peaks_at_mirror = True  # constant: its peak is everywhere, the mirror direction included

    @property
    def parameters(self):
        return ()

    @property
    def grid(self):
        return ({},)

    def __call__(self, shape, wi, wo):
        return jnp.full(wi.shape[:1], 1.0 / jnp.pi, wi.dtype)


#: The diffuse term of every built-in model.
LAMBERTIAN = Lambertian()
