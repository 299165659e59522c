"""The export targets' file names (``export/targets.py``): a file without the target's suffix is refused."""

import pytest

import brdffit
from brdffit import BrdfInputError, FitResult
from brdffit.export.targets import check_suffix

WARD = {"rho_d": [0.14, 0.09, 0.05], "rho_s": [0.036, 0.031, 0.022], "alpha": 0.15}


def test_a_file_without_the_targets_suffix_is_refused_before_anything_is_written(tmp_path):
    # XML in a .json file (a typo for -o fit.xml) would read as a broken result everywhere else: refused, one line.
    result = FitResult("ward", {}, ("r", "g", "b"), WARD, "log", 0.0, 0.0, 0, 0, True)
    for to, name in [("mitsuba", "oak.json"), ("gltf", "oak.obj"), ("merl", "oak.csv"), ("mitsuba", "oak.py")]:
        with pytest.raises(BrdfInputError, match=rf"^path=\S*/{name}: a {to} export is written to a \.") as error:
            brdffit.export(result, to, tmp_path / name)
        assert "\n" not in str(error.value)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(BrdfInputError, match="'blender' is not allowed"):
        check_suffix("blender", "oak.xml")
    with pytest.raises(BrdfInputError, match="path=-: a mitsuba export"):  # in Python "-" is a file named so
        brdffit.export(result, "mitsuba", "-")


def test_the_targets_suffixes_and_standard_output_pass(tmp_path):
    check_suffix("mitsuba", "-", standard_output=True)  # the command's -o -: a temporary file with the suffix, copied
    for to, name in [("mitsuba", "oak.XML"), ("mitsuba", "oak.mitsuba.py"), ("gltf", "oak.glb"), ("merl", "o.binary")]:
        check_suffix(to, tmp_path / name)
