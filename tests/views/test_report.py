"""The HTML report: one self-contained file (embedded images, no outside reference), and what a browser shows."""

import re
import shutil
import subprocess

import numpy as np
import pytest

from brdffit import BrdfInputError, data_synth, save_samples
from brdffit.cli import main
from brdffit.views.report import report

pytestmark = pytest.mark.slow  # its module fixture compares models and writes a report: ~20 s

PARAMS = {"rho_d": [0.2, 0.15, 0.1], "rho_s": [0.05, 0.05, 0.05], "alpha": 0.15}


@pytest.fixture(scope="module")
def samples():
    return data_synth.synthesize("ward", PARAMS, *data_synth.hemisphere_grid(6, 9, 12), noise=0.01, seed=1)


@pytest.fixture(scope="module")
def page(samples, tmp_path_factory):
    path = tmp_path_factory.mktemp("report") / "report.html"
    text = report(samples, ["lambert", "ward"], folds=3, uncertainty="laplace", path=path)
    assert path.read_text() == text
    return path


def test_the_report_is_one_self_contained_file(page):
    text = page.read_text()
    images = re.findall(r'<img [^>]*src="([^"]+)"', text)
    assert len(images) >= 4 and all(src.startswith("data:image/png;base64,") for src in images)
    # No reference to anything outside the file: no URL, no linked style sheet, script or font.
    outside_images = re.sub(r'src="data:image/png;base64,[A-Za-z0-9+/=]+"', "", text)
    assert not re.search(r"(https?:|//[a-z]|<link|<script|@import|url\()", outside_images, re.I)
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")


def test_the_report_says_what_the_data_are_which_model_and_its_errors(page, samples):
    text = page.read_text()
    assert "<h2>The data</h2>" in text and "648 samples × 3 channel(s)" in text
    ranking = re.findall(r'<tr class="(best|near|)"><td>(\d+)</td><td class="name">([^<]+)</td>', text)
    assert [spec for _, _, spec in ranking] == ["ward", "lambert"] and ranking[0][0] == "best"
    assert "<h3>1. <code>ward</code></h3>" in text and "<h3>2. <code>lambert</code></h3>" in text
    assert re.search(r"<td>0\.\d+ ± 0\.\d+</td>", text)  # a value with its Laplace error
    assert "± Laplace standard errors" in text or "± Laplace robust errors, for every parameter" in text


def test_bad_arguments_write_nothing(samples, tmp_path):
    with pytest.raises(BrdfInputError, match=r"path=.*report.txt: the report must end in \.html, \.htm"):
        report(samples, ["lambert"], path=tmp_path / "report.txt")
    with pytest.raises(BrdfInputError, match="uncertainty='bayes' is not allowed"):
        report(samples, ["lambert"], uncertainty="bayes")
    assert list(tmp_path.iterdir()) == []


def test_the_command_checks_its_output_before_any_fit(samples, tmp_path, capsys):
    data = tmp_path / "ward.csv"
    save_samples(samples, data)
    before = data.read_bytes()
    for output, message in ((data, "is the input"), (tmp_path / "r.pdf", "-o " + str(tmp_path / "r.pdf"))):
        assert main(["report", str(data), "-o", str(output)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
    assert data.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["ward.csv"]


BROWSER = next(
    (shutil.which(name) for name in ("chromium", "chromium-browser", "google-chrome") if shutil.which(name)), None
)


@pytest.mark.skipif(BROWSER is None, reason="no Chromium on this machine (apt install chromium) to render the report")
def test_a_headless_browser_shows_the_table_and_the_images(page, tmp_path):
    """Chromium renders the page offline; the screenshot is not blank and has the table's and the images' colours."""
    from PIL import Image

    shot = tmp_path / "report.png"
    subprocess.run(
        [BROWSER, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--window-size=1200,3000",
         f"--screenshot={shot}", page.as_uri()],
        check=True, capture_output=True, timeout=120,
    )  # fmt: skip
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.shape == (3000, 1200, 3) and pixels.std() > 20
    best_row = np.all(np.abs(pixels - [0xE8, 0xF4, 0xE8]) < 3, axis=-1)  # the best model's highlighted row
    assert best_row.sum() > 10_000
    coloured = np.ptp(pixels, axis=-1) > 60  # saturated pixels: the figures' data, curves and spheres
    assert coloured.sum() > 5_000


def test_report_takes_the_samplers_settings_as_fit_does(samples, tmp_path, capsys):
    """Issue 29: a short chain's warning says "run N steps or more", but ``report`` had no ``--steps``. It takes
    ``--walkers``, ``--steps``, ``--burn`` and ``--thin`` as ``fit`` does, and the page says what ran; without
    ``--uncertainty mcmc`` they are refused, before any work."""
    data = tmp_path / "ward.csv"
    save_samples(samples, data)
    output = tmp_path / "r.html"
    settings = ["--walkers", "8", "--steps", "60", "--burn", "20", "--thin", "2"]
    argv = ["report", str(data), "--models", "lambert", "--folds", "2", *settings, "-o", str(output)]
    assert main(argv) == 2
    assert "--walkers applies only to --uncertainty mcmc" in capsys.readouterr().err and not output.exists()
    assert main([*argv, "--uncertainty", "mcmc"]) == 0, capsys.readouterr().err
    assert "± posterior standard deviation (emcee: 8 walkers × 60 steps, 20 burn-in;" in output.read_text()
