"""Fixtures of the command-line tests."""

import pytest

import brdffit.api


@pytest.fixture
def no_fit(monkeypatch):
    """Fail the test if a fit starts: the checks must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("a fit ran before the bad input was reported")

    monkeypatch.setattr(brdffit.api, "fit", refuse)
    monkeypatch.setattr(brdffit.api, "fit_batch", refuse)
