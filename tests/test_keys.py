"""Cache keys (``brdffit/_programs/keys.py``): a stored program is found by the keys of its static arguments, so two
models, losses or holds that compute differently never share one, nor does another brdffit version."""

import hashlib
import itertools
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

import brdffit
from brdffit._programs import stored
from brdffit._programs.keys import class_key, key_of
from brdffit._version import __version__
from brdffit.datadriven.model import PcaModel
from brdffit.fitting.objective.losses import LOSSES, Loss
from brdffit.fitting.solver.hold import Hold
from brdffit.physics.fresnel import FRESNEL
from brdffit.physics.microfacet import DISTRIBUTIONS, SHADOWING
from brdffit.physics.models.lafortune import MAX_LOBES
from brdffit.physics.models.registry import MODELS, get_model


def every_model():
    """Every model brdffit builds without a file: each with every value of its options."""
    models = [get_model(name) for name, entry in MODELS.items() if not entry.listing and not entry.choices]
    models += [get_model("lafortune", lobes=lobes) for lobes in range(2, MAX_LOBES + 1)]
    for fresnel, distribution, shadowing in itertools.product(FRESNEL, DISTRIBUTIONS, SHADOWING):
        models.append(get_model("cook-torrance", fresnel=fresnel, distribution=distribution, shadowing=shadowing))
    return models


def test_two_models_or_losses_never_share_a_key():
    values = [*every_model(), *LOSSES.values()]
    keys = [json.dumps(key_of(value)) for value in values]
    assert "null" not in keys
    assert len(set(keys)) == len(values) == len(set(values))


def test_what_no_key_names_is_never_stored():
    own = Loss("log", "a loss of one's own under a built-in name", lambda v, y, ci: v)
    assert key_of(own) is None  # its transform is a function no key names
    assert key_of(PcaModel("pca", "data-driven")) is None  # its programs call back into Python
    assert key_of(object()) is None
    assert key_of(np.int64(3)) is None  # not a plain value


class OwnLobe:
    """A class defined outside brdffit, whose author keeps a version."""

    cache_version = "1"


class Unversioned:
    """A class defined outside brdffit without a version: what it calls elsewhere may change unseen."""


def test_a_class_outside_brdffit_is_keyed_by_its_version_and_source():
    assert class_key(type(get_model("ward").lobe)) == ["brdffit.physics.models.ward", "WardLobe"]  # brdffit's source
    module, name, version, digest = class_key(OwnLobe)
    assert (module, name, version) == (__name__, "OwnLobe", "1")
    assert digest == hashlib.sha256(Path(__file__).read_bytes()).hexdigest()  # a changed file: another key
    assert class_key(Unversioned) is None  # never stored
    assert class_key(object) is None  # no source file
    local = type("Local", (), {"__qualname__": "f.<locals>.Local"})
    assert class_key(local) is None  # defined in a function


def test_a_changed_version_hold_or_option_gives_another_signature():
    assert stored._environment()[0] == __version__
    identity = ["m.f", ["tuple", []]]
    theta, values = np.zeros(3), np.zeros((4, 3))
    hold = Hold(*(np.zeros(3) for _ in range(5)))
    signatures = {
        stored._signature(identity, (get_model("ward"), theta, values, None), (0,)),
        stored._signature(identity, (get_model("ward"), theta, values, hold), (0,)),
        stored._signature(identity, (get_model("ward-duer"), theta, values, None), (0,)),
        stored._signature(identity, (get_model("cook-torrance", fresnel="none"), theta, values, None), (0,)),
        stored._signature(identity, (get_model("cook-torrance", fresnel="dielectric"), theta, values, None), (0,)),
        stored._signature(["m.g", ["tuple", []]], (get_model("ward"), theta, values, None), (0,)),
    }
    assert None not in signatures and len(signatures) == 6


def test_a_brdffit_version_names_its_programs(monkeypatch):
    identity = ["m.f", ["tuple", []]]
    before = stored._signature(identity, (np.zeros(3),), ())
    environment = stored._environment()
    monkeypatch.setattr(stored, "_environment", lambda: ["0.0.0", *environment[1:]])
    assert stored._signature(identity, (np.zeros(3),), ()) != before
    assert brdffit.__version__ == __version__


def test_a_model_whose_parts_have_no_key_has_none():
    model = get_model("ward")
    assert key_of(replace(model, options=(("scale", np.int64(1)),))) is None  # not a plain value
    assert key_of(replace(model, n_lobes=np.int64(1))) is None
    assert json.dumps(key_of(model))  # JSON, whatever the model
