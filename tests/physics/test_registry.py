"""The model algebra: an abstract model with final kinds as siblings, the diffuse term as a component, and the
registry's entries, which say what the rest of brdffit needs to know about a model."""

import inspect

import numpy as np
import pytest

import brdffit
from brdffit.datadriven.model import PcaModel
from brdffit.fitting.comparison.compare import default_specs
from brdffit.physics.models.diffuse import LAMBERTIAN
from brdffit.physics.models.model import LobeModel, Model
from brdffit.physics.models.registry import MODELS, get_model, register_model
from brdffit.physics.models.ward import WardLobe


def test_the_kinds_of_model_are_final_siblings_of_one_abstract_model():
    assert inspect.isabstract(Model)
    with pytest.raises(TypeError):
        Model()
    for kind in (LobeModel, PcaModel):
        assert issubclass(kind, Model) and not inspect.isabstract(kind)
    assert not issubclass(LobeModel, PcaModel) and not issubclass(PcaModel, LobeModel)
    assert brdffit.Model is Model and isinstance(get_model("ward"), brdffit.Model)


def test_no_flag_tells_the_kinds_apart():
    """The fit, the batches, the holds and the comparison ask the kind, not ``own_fit``, ``on_host``, ``storable``."""
    for name in ("own_fit", "on_host", "storable"):
        assert not hasattr(LobeModel, name) and not hasattr(PcaModel, name)


def test_every_lobe_model_has_the_one_diffuse_term():
    for name, entry in MODELS.items():
        if not entry.listing:  # the data-driven model needs a basis file to be built
            assert get_model(name).diffuse is LAMBERTIAN
    wi = wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    np.testing.assert_allclose(
        brdffit.evaluate("lambert", {"rho_d": [0.5, 1.0]}, wi, wo), [[0.5 / np.pi, 1 / np.pi]] * 2
    )


def test_a_diffuse_term_with_shape_parameters_is_refused_in_one_line():
    with pytest.raises(brdffit.BrdfInputError, match=r"diffuse term with shape parameters \(alpha\) is not supported"):
        LobeModel("rough-diffuse", "a diffuse term with a roughness", WardLobe(), 1, diffuse=WardLobe())


def test_compare_tries_what_the_entries_say():
    assert default_specs() == [
        "lambert",
        "ward",
        "ward-aniso",
        "ward-duer",
        "cook-torrance:fresnel=schlick",
        "cook-torrance:fresnel=dielectric",
        "cook-torrance:fresnel=conductor,shadowing=smith",
        "cook-torrance:fresnel=none",
        "cook-torrance:fresnel=conductor,distribution=ggx,shadowing=smith",
        "cook-torrance:fresnel=dielectric,distribution=ggx,shadowing=smith",
        "cook-torrance:fresnel=conductor,distribution=ggx,shadowing=smith,anisotropic=true",
        "blinn-phong",
        "phong",
        "lafortune:lobes=1",
        "lafortune:lobes=2",
        "lafortune:lobes=3",
        "gltf",
        "principled",
        "roughplastic",
        "roughplastic:distribution=ggx",
    ]


def test_a_models_exact_export_is_its_entrys():
    assert MODELS["cook-torrance"].exact_export("mitsuba").__name__ == "cook_torrance_bsdf"
    assert MODELS["lambert"].exact_export("mitsuba").__name__ == "lambert_bsdf"
    assert MODELS["ward"].exact_export("mitsuba") is None
    assert MODELS["principled"].exact_export("mitsuba").__name__ == "principled_bsdf"
    assert MODELS["roughplastic"].exact_export("mitsuba").__name__ == "roughplastic_bsdf"
    assert MODELS["gltf"].exact_export("gltf").__name__ == "gltf_of_gltf_fit"
    assert MODELS["gltf"].exact_export("mitsuba") is None


@pytest.mark.parametrize(
    "name, entry, message",
    [
        ("ward", brdffit.ModelEntry(lambda: None), "registered already"),
        ("a:b", brdffit.ModelEntry(lambda: None), "must be a word"),
        ("flat", lambda: None, "must be a ModelEntry"),
    ],
)
def test_bad_registrations_are_one_line_errors(name, entry, message):
    with pytest.raises(brdffit.BrdfInputError, match=message):
        register_model(name, entry)
    assert "flat" not in MODELS


def test_a_registered_model_is_built_by_name(monkeypatch):
    flat = LAMBERTIAN  # a lobe that is the same everywhere: any lobe family will do
    monkeypatch.setitem(MODELS, "flat", brdffit.ModelEntry(lambda: LobeModel("flat", "flat", flat, 1)))
    model = get_model("flat")
    assert isinstance(model, LobeModel) and model.lobe == flat
    with pytest.raises(brdffit.BrdfInputError, match="does not apply to model flat"):
        get_model("flat", lobes=2)
