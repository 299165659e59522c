"""Every result brdffit writes is read back by everything that reads results, wherever the fit ended."""

import json
import warnings

import jax.numpy as jnp
import numpy as np
import pytest
from catalogue import anisotropic, case_params
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from paths import EXAMPLE

from brdffit import (
    BrdfInputError,
    FitWarning,
    UncertaintyWarning,
    data_synth,
    evaluate,
    fit,
    get_model,
    laplace_uncertainty,
    load_result,
)
from brdffit.cli import main
from brdffit.fitting.objective.losses import get_loss
from brdffit.fitting.options import MAX_STEPS
from brdffit.fitting.single.outcome import result_of
from brdffit.fitting.solver.compiled import Solved

GEOMETRY = data_synth.uniform_random(200, seed=4)


@pytest.mark.parametrize("case", case_params(as_one=True))
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(edge=st.lists(st.sampled_from([-800.0, -40.0, -5.0, 0.0, 2.0]), min_size=12, max_size=12))
def test_a_result_at_any_edge_is_read_back_by_every_command(case, edge, tmp_path):
    """Unconstrained coordinates far below put parameters on their domains' lower edges, where rounding would leave
    them outside (``1 + exp(-800)`` is exactly 1, outside ``eta > 1``; ``exp(-800)`` is 0, outside ``alpha > 0``):
    the result file must still hold values every reader accepts: ``load_result``, ``evaluate``, ``synth
    --params``, ``fit --start``, uncertainty, ``convert``. (Far above, a shape is implausible: the fit warns, and a
    start there is refused, ``test_fit.py``.)"""
    name, options, params = case
    model = get_model(name, **options)
    samples = data_synth.synthesize(name, params, *GEOMETRY, noise=0.01, seed=1, **options)
    theta = model.unconstrained.from_params(model.dictionary.to_params(params))
    theta = np.where(np.arange(theta.size) % 2 == 0, np.resize(edge, theta.size), theta)  # half the coordinates
    solved = Solved(theta, 1.0, 1, 0, True, model.unconstrained.to_params(jnp.asarray(theta), 3), 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", (FitWarning, UncertaintyWarning, RuntimeWarning))
        result = result_of(model, get_loss("log"), samples, solved, MAX_STEPS, "float64")
        path = tmp_path / "result.json"
        result.save(path)
        back = load_result(path)
        values = evaluate(back.model, back.params, samples.wi, samples.wo, **back.model_options)
        assert np.all(np.isfinite(values))
        data_synth.synthesize(back.model, back.params, *GEOMETRY, **back.model_options)
        fit(samples, back.model, start=back.params, max_steps=1, **back.model_options)
        laplace_uncertainty(back, samples)
        # a MERL table holds an isotropic BRDF: an isotropic result is written; an anisotropic one is refused (one
        # line), unless its edges left it isotropic (both roughnesses on one edge). Its own parameters say which: the
        # edges may free principled's anisotropic (0 in the case)
        status = main(["convert", str(path), str(tmp_path / "table.binary")])
        assert status in (0, 2) if anisotropic((name, options, back.params)) else status == 0
    json.loads(path.read_text())  # strict JSON: no NaN or infinity


def test_a_fresnel_at_its_edges_is_representable(tmp_path):
    """f0 → 1 (the logistic rounds to exactly 1) and eta → 1 (1 + exp(u) rounds to exactly 1) write values the
    reader takes back."""
    for options, coordinate in (({"fresnel": "schlick"}, 40.0), ({"fresnel": "dielectric"}, -40.0)):
        model = get_model("cook-torrance", **options)
        samples = data_synth.synthesize("lambert", {"rho_d": [0.2]}, *GEOMETRY)
        theta = np.array([np.log(0.2), np.log(0.5), np.log(0.2), coordinate])
        solved = Solved(theta, 1.0, 1, 0, True, model.unconstrained.to_params(jnp.asarray(theta), 1), 0.1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FitWarning)
            result = result_of(model, get_loss("log"), samples, solved, MAX_STEPS, "float64")
        result.save(tmp_path / "edge.json")
        back = load_result(tmp_path / "edge.json")
        fresnel = back.params.get("f0", back.params.get("eta"))
        assert fresnel == pytest.approx(1.0, abs=1e-11)
        model.dictionary.to_params(back.params)  # accepted


@pytest.mark.parametrize(
    ("entry", "value", "piece"),
    [
        ("stderr", [0.1, 0.2], "uncertainty.stderr must be a JSON object"),
        ("covariance", "none", "uncertainty.covariance must be a JSON object"),
        ("diagnostics", 3, "uncertainty.diagnostics must be a JSON object"),
        ("warnings", {"a": 1}, "uncertainty.warnings must be a JSON list"),
        ("warning_codes", [1, 2], "uncertainty.warning_codes must be a JSON list of strings"),
    ],
)
def test_a_malformed_uncertainty_block_is_one_line(tmp_path, capsys, entry, value, piece):
    """Issue 29, item 7: the uncertainty block's types are checked (the check once compared types by identity,
    ``dict[str, Any] is dict[str, Any]``, which is never true, and let every block through)."""
    content = fit(EXAMPLE, "lambert", uncertainty="laplace").to_dict()
    content["uncertainty"][entry] = value
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(content))
    with pytest.raises(BrdfInputError, match=piece):
        load_result(path)
    status = main(["export", str(path), "--to", "merl", "-o", str(tmp_path / "t.binary")])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and piece in err, err
    assert not (tmp_path / "t.binary").exists()
