"""lmfit's habits: ``fit_report()``'s sections and numbers, and the HTML a notebook shows for a result, samples and a
comparison."""

import re
import warnings
from html.parser import HTMLParser

import numpy as np
import pytest
from paths import EXAMPLE

import brdffit


@pytest.fixture(scope="module")
def oak():
    samples = brdffit.load_samples(EXAMPLE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", brdffit.UncertaintyWarning)  # the robust errors, said
        return samples, brdffit.fit(samples, "ward", uncertainty="laplace", fixed={"alpha": 0.146})


def test_the_report_has_lmfits_sections_and_the_results_own_figures(oak):
    _, result = oak
    report = result.fit_report()
    sections = re.findall(r"^\[\[([\w ]+)\]\]", report, flags=re.M)
    assert sections == ["Model", "Fit Statistics", "Variables", "Correlations"]
    assert f"# data points      = {result.ndata}" in report and f"# variables        = {result.nvarys}" in report
    assert result.nvarys == 6  # alpha held
    assert f"reduced chi-square = {result.redchi:.8g}" in report and f"Akaike info crit   = {result.aic:.8g}" in report
    assert re.search(r"^    alpha:\s+= 0\.146 \(fixed\)$", report, flags=re.M)
    assert re.search(r"^    rho_d\[g\]:\s+0\.09\d+ ± 0\.0000\d+$", report, flags=re.M)
    listed = re.findall(r"C\((\S+), (\S+)\)\s+= ([+-][0-9.]+)", report)
    block = result.uncertainty["correlation"]
    names, matrix = block["names"], np.asarray(block["matrix"], dtype=float)
    expected = sorted(
        (
            (names[i], names[j], matrix[i, j])
            for i in range(len(names))
            for j in range(i + 1, len(names))
            if np.isfinite(matrix[i, j]) and abs(matrix[i, j]) > 0.1
        ),
        key=lambda pair: -abs(pair[2]),
    )
    assert [(a, b) for a, b, _ in listed] == [(a, b) for a, b, _ in expected]
    assert [float(value) for _, _, value in listed] == pytest.approx([value for _, _, value in expected], abs=5e-5)
    assert "[[Correlations]]" not in result.fit_report(min_correlation=0.99)


class _Tags(HTMLParser):
    """The tags an HTML fragment opens and closes, and its text."""

    def __init__(self):
        super().__init__()
        self.open, self.text = [], []

    def handle_starttag(self, tag, attrs):
        if tag != "br":
            self.open.append(tag)

    def handle_endtag(self, tag):
        assert self.open and self.open.pop() == tag, tag

    def handle_data(self, data):
        self.text.append(data)


def _parsed(fragment: str) -> str:
    tags = _Tags()
    tags.feed(fragment)
    assert tags.open == []  # every tag closed, in order
    return " ".join(tags.text)


def test_a_notebook_shows_results_samples_and_comparisons_as_html(oak):
    samples, result = oak
    text = _parsed(result._repr_html_())
    assert "rho_s" in text and "= 0.146" in text and f"ndata {result.ndata}" in text
    assert "10368 × 3 channel(s)" in _parsed(samples._repr_html_())
    comparison = brdffit.compare(samples.select(np.arange(0, samples.n_samples, 8)), ["lambert", "ward"], folds=2)
    assert "ward" in _parsed(comparison._repr_html_()) and comparison._repr_html_().startswith("<pre>")
