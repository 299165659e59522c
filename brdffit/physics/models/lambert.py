"""The Lambertian (perfectly diffuse) model, ``rho_d / π``: Lambert, *Photometria*, 1760: the diffuse term alone."""

from .model import LobeModel, ModelEntry


def lambert() -> LobeModel:
    return LobeModel("lambert", "perfectly diffuse, rho_d/π")


#: Exact in Mitsuba as its ``diffuse`` BSDF (``brdffit/export/mitsuba.py``).
LAMBERT = ModelEntry(lambert, compare=("lambert",), exports={"mitsuba": "brdffit.export.mitsuba:lambert_bsdf"})
