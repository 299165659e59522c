"""Model specs: NAME[:key=value,…], shorthand values, canonical names, lists of specs, one-line errors."""

import pytest

from brdffit import BrdfInputError
from brdffit.physics.models.specs import model_of_spec, spec_of, split_specs


@pytest.mark.parametrize(
    ("spec", "canonical"),
    [
        ("ward", "ward"),
        (" ward ", "ward"),
        ("lafortune:2", "lafortune:lobes=2"),
        ("lafortune:lobes=3", "lafortune:lobes=3"),
        ("cook-torrance", "cook-torrance"),
        ("cook-torrance:fresnel=schlick,distribution=beckmann", "cook-torrance"),
        ("cook-torrance:distribution=ggx,shadowing=smith", "cook-torrance:distribution=ggx,shadowing=smith"),
        ("cook-torrance:ggx,smith-correlated", "cook-torrance:distribution=ggx,shadowing=smith-correlated"),
        ("cook-torrance:conductor", "cook-torrance:fresnel=conductor"),
        ("cook-torrance:fresnel=none", "cook-torrance:fresnel=none"),
    ],
)
def test_specs_name_a_model_and_its_options(spec, canonical):
    model = model_of_spec(spec)
    assert spec_of(model.name, model.model_options) == canonical
    again = model_of_spec(canonical)
    assert again == model


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("wrd", r"^model spec 'wrd': 'wrd' is not a model; choose one of: lambert, ward,"),
        ("ward:2", r"^model spec 'ward:2': no option of ward takes 2; write key=value \(no options\)$"),
        ("lafortune:x", r"^model spec 'lafortune:x': lobes='x' is not allowed; give a whole number from 1 to 8$"),
        ("lafortune:0", r"^model spec 'lafortune:0': lobes=0 is not allowed; give a whole number from 1 to 8$"),
        ("cook-torrance:fresnel=gold", r"^model spec 'cook-torrance:fresnel=gold': fresnel='gold' is not known"),
        ("lafortune:lobes=0", r"^model spec 'lafortune:lobes=0': lobes=0 is not allowed; give a whole number from 1"),
        ("ward:lobes=2", r"^model spec 'ward:lobes=2': lobes does not apply to model ward; it takes no options$"),
    ],
)
def test_bad_specs_say_what_is_allowed(spec, message):
    with pytest.raises(BrdfInputError, match=message):
        model_of_spec(spec)


def test_a_list_of_specs_splits_between_specs_not_inside_one():
    assert split_specs("ward,cook-torrance:fresnel=conductor,lafortune:lobes=2") == [
        "ward",
        "cook-torrance:fresnel=conductor",
        "lafortune:lobes=2",
    ]
    assert split_specs(" lambert , lafortune:2 ,") == ["lambert", "lafortune:2"]
    assert split_specs("") == []
    # A key=value after a comma belongs to the spec before it (models with several options); anything else starts
    # a spec, so a misspelt model is named as written, not glued to the one before it.
    with pytest.raises(BrdfInputError, match=r"^model spec 'cook-torrance:fresnel=conductor,lobes=2': lobes does not"):
        split_specs("cook-torrance:fresnel=conductor,lobes=2,ward")
    for text in ("lambert,wrd", "lafortune:2,wrd"):
        with pytest.raises(BrdfInputError, match=r"^model spec 'wrd': 'wrd' is not a model"):
            split_specs(text)
    with pytest.raises(BrdfInputError, match=r"^model spec 'lafortune:lobes=2' is given twice; give each model once$"):
        split_specs("ward,lafortune:2,lafortune:lobes=2")
