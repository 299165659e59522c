"""The Lambertian (perfectly diffuse) model, ``rho_d / π``: Lambert, *Photometria*, 1760."""

from .model import Model


def lambert() -> Model:
    return Model("lambert", "perfectly diffuse, rho_d/π")
