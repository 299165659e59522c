"""Fixtures of the command-line tests."""

import pytest

import brdffit.api
import data_synth
from brdffit import fit, save_samples


@pytest.fixture
def no_fit(monkeypatch):
    """Fail the test if a fit starts: the checks must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("a fit ran before the bad input was reported")

    monkeypatch.setattr(brdffit.api, "fit", refuse)
    monkeypatch.setattr(brdffit.api, "fit_batch", refuse)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small Ward dataset (``ward.csv``, one channel, 432 samples) and its fit (``ward.json``) in a folder."""
    folder = tmp_path_factory.mktemp("ward")
    samples = data_synth.synthesize(
        "ward", {"rho_d": [0.2], "rho_s": [0.05], "alpha": 0.15}, *data_synth.hemisphere_grid(4, 9, 12), noise=0.01
    )
    save_samples(samples, folder / "ward.csv")
    fit(samples, "ward").save(folder / "ward.json")
    return folder
