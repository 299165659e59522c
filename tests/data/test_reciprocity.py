"""Reciprocal pairs tell what a file's values are: the real tape, ALTA's cosine header, and made-up quantities."""

import math

import numpy as np
import pytest
from paths import TAPE

import data_synth
from brdffit import load_samples, save_samples
from brdffit.cli import main
from brdffit.data.quantities import stored_factor
from brdffit.data.reciprocity import MIN_PAIRS, RECIPROCAL, reciprocity
from brdffit.data.samples import Samples
from brdffit.physics.geometry import spherical_to_direction

#: A sharp retro lobe beside a forward one: values that differ by orders of magnitude between a pair's two
#: directions if the quantity is read wrong.
TAPE_LIKE = {
    "rho_d": [0.3],
    "lobes": [
        {"rho_s": [0.25], "cxy": 0.577, "cz": 0.578, "n": 300.0},
        {"rho_s": [0.2], "cxy": -0.58, "cz": 0.571, "n": 37.0},
    ],
}


def isotropic_pairs():
    """A gonioreflectometer grid whose light zeniths are among its view zeniths: many reciprocal pairs."""
    theta = np.radians([10.0, 25.0, 40.0, 55.0, 70.0])
    phi = np.radians(np.arange(0.0, 181.0, 15.0))
    light, view, azimuth = np.meshgrid(theta, theta, phi, indexing="ij")
    wi = spherical_to_direction(light.ravel(), 0 * light.ravel())
    wo = spherical_to_direction(view.ravel(), azimuth.ravel())
    return wi, wo


@pytest.fixture(scope="module")
def brdf_values():
    return data_synth.synthesize("lafortune", TAPE_LIKE, *isotropic_pairs(), noise=0.0, lobes=2)


def test_brdf_values_are_reciprocal_and_cosine_readings_are_not(brdf_values):
    found = reciprocity(brdf_values)
    assert found.pairs >= MIN_PAIRS and found.reciprocal and found.best == "brdf"
    # Every model here is exactly reciprocal: the median ratio is 1 to rounding.
    assert found.ratios["brdf"] == pytest.approx(1.0, rel=1e-12)
    assert found.ratios["cosine-weighted-in"] < RECIPROCAL[0] < RECIPROCAL[1] < found.ratios["cosine-weighted-out"]


@pytest.mark.parametrize("quantity", ["cosine-weighted-in", "cosine-weighted-out", "reflectance-factor"])
def test_a_file_of_any_quantity_reads_reciprocal_under_its_own(brdf_values, quantity, tmp_path):
    stored = brdf_values.values * stored_factor(quantity, brdf_values.wi, brdf_values.wo)
    path = tmp_path / "values.csv"
    save_samples(Samples.from_arrays(brdf_values.wi, brdf_values.wo, stored), path)
    as_brdf = reciprocity(load_samples(path))
    right = reciprocity(load_samples(path, quantity=quantity))
    assert right.reciprocal and right.as_read == pytest.approx(1.0, rel=1e-9)
    reading = "brdf" if quantity == "reflectance-factor" else quantity
    assert as_brdf.best == reading and (as_brdf.reciprocal == (quantity == "reflectance-factor"))


def test_an_alta_file_with_the_cosine_header_loads_reciprocal(brdf_values, tmp_path):
    """ALTA's INV_STERADIAN_COSINE_FACTOR is the BRDF times the view's cosine: read as such, the pairs agree."""
    stored = brdf_values.values * brdf_values.wo[:, 2:3]
    theta_l = np.arccos(brdf_values.wi[:, 2])
    theta_v = np.arccos(brdf_values.wo[:, 2])
    phi_v = np.arctan2(brdf_values.wo[:, 1], brdf_values.wo[:, 0])
    rows = np.column_stack([theta_l, 0 * theta_l, theta_v, phi_v, stored])
    path = tmp_path / "cosine.dat"
    header = "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n"
    path.write_text(header + "".join(" ".join(f"{x:.17g}" for x in row) + "\n" for row in rows))
    loaded = load_samples(path)
    assert loaded.provenance.quantity == "cosine-weighted-out"
    found = reciprocity(loaded)
    assert 0.9 <= found.as_read <= 1.1
    np.testing.assert_allclose(loaded.values, brdf_values.values, rtol=1e-12)


def test_the_real_tape_is_cosine_weighted_by_the_view():
    """The gray tape has no #PARAM_OUT line; its reciprocal pairs say its values are f·cos θv (issue 11: 0.61 as
    stored, 0.35 divided by cos θl, 1.06 divided by cos θv)."""
    stored = reciprocity(load_samples(TAPE))
    assert not stored.reciprocal and stored.best == "cosine-weighted-out"
    assert stored.ratios["brdf"] == pytest.approx(0.61, abs=0.02)
    assert stored.ratios["cosine-weighted-in"] == pytest.approx(0.35, abs=0.02)
    read_right = reciprocity(load_samples(TAPE, quantity="cosine-weighted-out"))
    assert 0.9 <= read_right.as_read <= 1.1 and read_right.reciprocal


def test_info_on_the_tape_names_the_quantity_and_what_was_dropped(capsys):
    assert main(["info", str(TAPE)]) == 0
    out = capsys.readouterr().out
    assert "read them with --quantity cosine-weighted-out" in out
    assert "dropped: 86 with the light or the viewer at or below the horizon" in out
    assert "values read as brdf (by default): taken as they are" in out
    assert main(["info", str(TAPE), "--quantity", "cosine-weighted-out"]) == 0
    out = capsys.readouterr().out
    assert "divided by cos θo (the view's cosine)" in out and "the values as read are reciprocal" in out


def test_too_few_pairs_say_nothing():
    wi, wo = data_synth.uniform_random(500, seed=1)
    assert reciprocity(data_synth.synthesize("lambert", {"rho_d": [0.5]}, wi, wo)) is None


def test_the_cosine_readings_are_the_cosines():
    """A pair (a → b) and (b → a) of a Lambertian surface stored times the light's cosine: ratio cos a / cos b."""
    a, b = math.radians(20.0), math.radians(60.0)
    wi = np.array([[math.sin(a), 0, math.cos(a)], [math.sin(b), 0, math.cos(b)]] * MIN_PAIRS)
    wo = np.array([[-math.sin(b), 0, math.cos(b)], [-math.sin(a), 0, math.cos(a)]] * MIN_PAIRS)
    stored = np.full((2 * MIN_PAIRS, 1), 0.1) * wi[:, 2:3]
    found = reciprocity(Samples.from_arrays(wi, wo, stored))
    assert found.pairs == MIN_PAIRS and found.ratios["brdf"] == pytest.approx(math.cos(a) / math.cos(b), rel=1e-12)
    assert found.ratios["cosine-weighted-in"] == pytest.approx(1.0, rel=1e-12)
