"""The lit-sphere figure: its panels, titles and images, the measured panel only for dense data, saving, errors."""

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from paths import EXAMPLE, EXAMPLE_PARAMS

from brdffit import BrdfInputError, data_synth, load_samples
from brdffit.fitting.single.result import FitResult
from brdffit.views.sphere import sphere

WARD = {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}
CONDUCTOR = {"kd": [0.01, 0.01, 0.01], "ks": [0.9, 0.8, 0.6], "m": 0.2, "eta": 0.2, "k": 3.9}


def result(model: str, params: dict, channels=("r", "g", "b"), **options) -> FitResult:
    """A result as a fit would write it; only the model, its options, channels and params matter to a sphere."""
    return FitResult(model, options, tuple(channels), params, "log", 0.0, 0.0, 1, 1, True)


@pytest.fixture(scope="module")
def dense_ward():
    """200,000 pairs uniform over both hemispheres: dense enough for the measured panel (test_render.py)."""
    return data_synth.synthesize("ward", WARD, *data_synth.uniform_random(200_000, seed=11))


def image_axes(figure: Figure):
    return [axis for axis in figure.axes if axis.get_images()]


def rendered_rgba(figure: Figure) -> np.ndarray:
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba(), dtype=float)


def test_one_fit_under_a_point_light_is_one_titled_panel():
    figure = sphere(result("ward", WARD), size=64)
    assert isinstance(figure, Figure)
    (axis,) = image_axes(figure)
    assert axis.get_title() == "ward"
    image = axis.get_images()[0].get_array()
    assert image.shape == (64, 64, 4)
    assert np.all(np.isfinite(image)) and np.std(image[..., :3][image[..., 3] > 0]) > 0
    buffer = rendered_rgba(figure)
    assert np.all(np.isfinite(buffer)) and np.std(buffer) > 0


def test_fits_side_by_side_beside_the_dense_measured_sphere_under_both_lightings(dense_ward):
    fits = [result("ward", WARD), result("cook-torrance", CONDUCTOR, fresnel="conductor")]
    figure = sphere(fits, dense_ward, size=64, lights="both")
    axes = image_axes(figure)
    assert len(figure.axes) == 6 and len(axes) == 6  # 2 lightings × (2 fits + measured)
    titles = [axis.get_title() for axis in axes]
    assert titles[:2] == titles[3:5] == ["ward", "cook-torrance:fresnel=conductor"]
    assert all(title.startswith("measured (") for title in (titles[2], titles[5]))
    row_labels = [text.get_text() for axis in figure.axes for text in axis.texts]
    assert row_labels == ["point light", "environment (4 lights)"]
    for axis in axes:
        rgb = axis.get_images()[0].get_array()[..., :3]
        assert np.all(np.isfinite(rgb)) and np.std(rgb) > 0
    assert np.std(rendered_rgba(figure)) > 0


def test_sparse_samples_get_no_measured_panel_and_the_title_says_why():
    figure = sphere(result("ward", WARD), load_samples(EXAMPLE), size=64, lights="environment")
    assert len(image_axes(figure)) == 1
    title = figure.get_suptitle().replace("\n", " ")
    assert title.startswith("measured sphere not shown:") and "(environment)" in title


def test_channels_shown_as_a_grey_mean_are_named_in_the_title():
    spectral = result("lambert", {"rho_d": [0.1, 0.2, 0.3, 0.4, 0.5]}, channels=("400", "500", "600", "700", "800"))
    figure = sphere([spectral, result("ward", WARD)], size=32)
    assert len(image_axes(figure)) == 2
    assert figure.get_suptitle() == "lambert: grey: mean of 5 channels"


def test_the_example_fit_is_saved_as_a_png(tmp_path):
    import json

    fit = result("ward", json.loads(EXAMPLE_PARAMS.read_text()))
    path = tmp_path / "sphere.png"
    figure = sphere(fit, size=48, lights="both", path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(image_axes(figure)) == 2


def test_bad_arguments_are_one_line_errors_naming_them():
    with pytest.raises(BrdfInputError, match=r"^lights='sun' is not allowed; choose one of: point, environment, both$"):
        sphere(result("ward", WARD), lights="sun")
    with pytest.raises(BrdfInputError, match=r"^results must be a FitResult"):
        sphere([])
    with pytest.raises(BrdfInputError, match=r"^samples must be Samples \(from brdffit.load_samples\), got int$"):
        sphere(result("ward", WARD), 3)
    with pytest.raises(BrdfInputError, match=r"^nowhere/samples.csv: no such file$"):  # a path is read
        sphere(result("ward", WARD), "nowhere/samples.csv")


LONG_OPTIONS = {"distribution": "ggx", "shadowing": "smith-correlated", "fresnel": "conductor", "anisotropic": True}
LONG_CONDUCTOR = {
    "kd": [0.01] * 3,
    "ks": [1.0] * 3,
    "alpha_u": 0.2,
    "alpha_v": 0.1,
    "phi_t": 10.0,
    "eta": [0.2, 0.5, 1.4],
    "k": [3.9, 2.5, 1.9],
}


def test_long_specs_wrap_so_that_titles_neither_overlap_nor_leave_the_figure():
    """Issue 29: a 79-character spec (``cook-torrance:distribution=ggx,shadowing=smith-correlated,…``) ran into the
    next panel's title and off the figure. Titles wrap after the spec's ``:`` and ``,``: every title's box, as drawn,
    lies inside the figure and apart from the others."""
    long = result("cook-torrance", LONG_CONDUCTOR, **LONG_OPTIONS)
    figure = sphere([long, long, result("ward", WARD)], size=32)
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    renderer, whole = canvas.get_renderer(), figure.bbox
    boxes = [axis.title.get_window_extent(renderer) for axis in image_axes(figure)]
    assert figure.axes[0].get_title().startswith("cook-torrance:distribution=ggx,\nshadowing=smith-correlated,\n")
    assert all(whole.x0 <= box.x0 and box.x1 <= whole.x1 for box in boxes)
    assert all(not a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1 :])
