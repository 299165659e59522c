"""Slices through the plane of incidence and the perpendicular plane: panels, the in-plane samples exactly, model
curves equal to ``predict``, the log axis, the legend, drawn pixels, saving, and one-line argument errors."""

import json
import re

import numpy as np
import pytest
from conftest import directions_from_degrees, save_in_radians
from matplotlib.backends.backend_agg import FigureCanvasAgg
from paths import EXAMPLE, EXAMPLE_PARAMS

from brdffit import BrdfInputError, FitResult, data_synth, load_samples
from brdffit.data.samples import Samples
from brdffit.views.slices import PLANE_TOLERANCE, slices

OAK = json.loads(EXAMPLE_PARAMS.read_text())
#: A broad Ward lobe: values stay well above any axis floor, so every curve point is drawn as computed.
BROAD_WARD = {"rho_d": [0.3, 0.2, 0.1], "rho_s": [0.1, 0.08, 0.05], "alpha": 0.3}


def result_of(model: str, params: dict, channels=("r", "g", "b"), loss: str = "log", **options) -> FitResult:
    """A result built from known parameters, without fitting."""
    return FitResult(model, options, tuple(channels), params, loss, 0.0, 0.0, 0, 0, True)


def lines(axis, prefix: str) -> list:
    """The lines a figure drew for ``prefix``: ``data``, ``fit`` or ``floor`` (their gid names what they are)."""
    return [line for line in axis.get_lines() if (line.get_gid() or "").startswith(prefix + ":")]


def title_angle(axis) -> float:
    """The θi a panel's title names (rounded to 3 digits there)."""
    return float(re.match(r"θi = ([0-9.]+)°", axis.get_title()).group(1))


def pixels(figure) -> np.ndarray:
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())


def in_plane_samples(n_incident: int = 4, n_theta: int = 30) -> Samples:
    """Broad Ward values in the plane of incidence only (data_synth's ``in-plane`` geometry)."""
    return data_synth.synthesize("ward", BROAD_WARD, *data_synth.in_plane(n_incident, n_theta))


@pytest.fixture(scope="module")
def ward_and_lambert():
    return [result_of("ward", BROAD_WARD), result_of("lambert", {"rho_d": [0.35, 0.25, 0.12]})]


def test_in_plane_data_give_one_panel_per_incidence_with_exactly_their_samples(ward_and_lambert):
    samples = in_plane_samples()
    figure = slices(ward_and_lambert, samples)
    axes = figure.axes
    assert len(axes) == 4  # 4 incidences ≤ max_panels; no samples in the perpendicular plane: one row
    theta_i_expected = (np.arange(4) + 0.5) * 90 / 4
    # data_synth's signed θo is < 0 on the mirror side; the figure's is > 0 there.
    signed = (np.arange(30) + 0.5) * 180 / 30 - 90
    for axis, theta_i in zip(axes, theta_i_expected, strict=True):
        assert title_angle(axis) == pytest.approx(theta_i, abs=0.051)
        assert axis.get_yscale() == "log"
        assert "> 0 on the mirror side" in axis.get_xlabel()
        data = lines(axis, "data")
        assert [line.get_gid() for line in data] == ["data:r", "data:g", "data:b"]
        assert len(lines(axis, "fit")) == 2 * 3  # one per fit per channel
        assert not lines(axis, "floor")
        np.testing.assert_allclose(np.sort(data[0].get_xdata()), np.sort(-signed), atol=1e-9)
        members = np.isclose(samples.theta_i, theta_i)
        np.testing.assert_allclose(np.sort(data[1].get_ydata()), np.sort(samples.values[members, 1]), rtol=1e-15)


def test_the_curves_are_each_fits_predict_along_the_plane(ward_and_lambert):
    samples = in_plane_samples()
    figure = slices(ward_and_lambert, samples, perpendicular=False)
    axis = figure.axes[1]  # θi = 33.75°
    theta_i = 33.75
    for index, result in enumerate(ward_and_lambert):
        curve = next(line for line in lines(axis, "fit") if line.get_gid() == f"fit:{index}:g")
        theta_o, values = np.asarray(curve.get_xdata()), np.asarray(curve.get_ydata())
        assert theta_o.min() < -85 and theta_o.max() > 85
        assert np.any(theta_o == theta_i) and np.any(theta_o == -theta_i)  # the mirror and retro peaks
        for wanted in (-60.0, -theta_i, 0.0, 20.0, theta_i, 70.0):
            k = int(np.argmin(np.abs(theta_o - wanted)))
            # θo > 0 on the mirror side: azimuth 180° from the light's (at azimuth 0).
            wo = directions_from_degrees(abs(theta_o[k]), 180.0 if theta_o[k] > 0 else 0.0)
            expected = result.predict(directions_from_degrees(theta_i, 0.0), wo)[0, 1]
            assert values[k] == pytest.approx(expected, rel=1e-12)
    assert [line.get_linestyle() for line in lines(axis, "fit")[::3]] == ["-", "--"]


def test_the_legend_names_every_fit_the_data_and_the_channels(ward_and_lambert):
    figure = slices(ward_and_lambert, in_plane_samples())
    (legend,) = figure.legends
    labels = [text.get_text() for text in legend.get_texts()]
    assert labels[:3] == ["ward", "lambert", "data"]
    assert labels[-3:] == ["r", "g", "b"]
    # The same model twice is told apart.
    twice = slices([ward_and_lambert[0], ward_and_lambert[0]], in_plane_samples())
    assert [text.get_text() for text in twice.legends[0].get_texts()][:2] == ["ward (1)", "ward (2)"]


def test_a_hemisphere_grid_adds_the_perpendicular_plane_with_its_samples():
    """The example's grid (8 incidences × 36 θo × 36 φo, 10° apart): 4 of the 8 incidences, evenly chosen, two
    rows. The perpendicular plane's samples are counted here independently: |wo · x| ≤ sin(tolerance), the light
    lying at azimuth 0 (the plane's normal is then the x axis)."""
    samples = load_samples(EXAMPLE)
    figure = slices(result_of("ward", OAK), samples)
    assert len(figure.axes) == 8
    distinct = np.unique(np.round(samples.theta_i, 6))
    chosen = distinct[[0, 2, 5, 7]]
    across = figure.axes[4:]
    for axis, theta_i in zip(across, chosen, strict=True):
        assert title_angle(axis) == pytest.approx(theta_i, abs=0.051)
        assert "φi + 90°" in axis.get_xlabel()
        members = np.isclose(samples.theta_i, theta_i)
        expected = members & (np.abs(samples.wo[:, 0]) <= np.sin(np.radians(PLANE_TOLERANCE)))
        assert lines(axis, "data")[0].get_xdata().size == expected.sum()
        assert expected.sum() > 72  # both halves of the 36 zeniths, and a few near the normal
    two = slices(result_of("ward", OAK), samples, max_panels=2, perpendicular=False).axes
    assert [title_angle(axis) for axis in two] == pytest.approx(distinct[[0, -1]], abs=0.051)


def test_random_data_say_a_panel_is_empty_and_still_draw_the_curves():
    """200 random pairs: almost none lies within 0.5° of an incidence and 0.5° of its plane."""
    samples = data_synth.synthesize("ward", BROAD_WARD, *data_synth.uniform_random(200, seed=3))
    figure = slices(result_of("ward", BROAD_WARD), samples)
    empty = [axis for axis in figure.axes if not lines(axis, "data")]
    assert empty
    for axis in empty:
        assert any(text.get_text() == f"no samples within {PLANE_TOLERANCE:g}° of this plane" for text in axis.texts)
        assert len(lines(axis, "fit")) == 3


def test_given_incidences_and_zero_values_on_the_floor():
    samples = in_plane_samples(n_incident=3)  # θi = 15°, 45°, 75°
    values = samples.values.copy()
    values[::7] = 0.0  # zeros: drawn on the axis floor, not lost to the log scale
    zeroed = Samples.from_arrays(samples.wi, samples.wo, values, samples.channels)
    figure = slices(result_of("ward", BROAD_WARD), zeroed, incidences=[45])
    (axis,) = figure.axes
    assert axis.get_title() == "θi = 45°"
    members = np.isclose(zeroed.theta_i, 45.0)
    floor = lines(axis, "floor")
    assert floor and floor[0].get_xdata().size == np.sum(values[members, 0] == 0)
    assert np.all(np.asarray(floor[0].get_ydata()) == axis.get_ylim()[0])
    assert lines(axis, "data")[0].get_xdata().size + floor[0].get_xdata().size == members.sum()
    assert "data ≤ axis floor" in [text.get_text() for text in figure.legends[0].get_texts()]


def test_the_figure_draws_finite_visible_pixels_and_saves_a_png(ward_and_lambert, tmp_path):
    figure = slices(ward_and_lambert, in_plane_samples(), path=tmp_path / "slices.png")
    image = pixels(figure)
    assert np.all(np.isfinite(image)) and image[..., :3].std() > 0
    assert (tmp_path / "slices.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"results": "ward"}, r"^results must be a FitResult or a non-empty list of them, got str$"),
        ({"results": []}, r"^results must be a FitResult or a non-empty list of them, got an empty list$"),
        (
            {"results": [result_of("lambert", {"rho_d": [0.3]}, ("value",))]},
            r"^results: lambert has channels value but the samples have r, g, b$",
        ),
        ({"samples": np.zeros((3, 3))}, r"^samples must be Samples \(from brdffit.load_samples\), got ndarray$"),
        ({"max_panels": 0}, r"^max_panels=0 is not allowed; give a whole number from 1 to 12$"),
        ({"incidences": [95]}, r"^incidences=\[95\] is not allowed; give light zenith angles in degrees"),
        ({"incidences": "thirty"}, r"^incidences='thirty' is not allowed"),
        ({"perpendicular": "yes"}, r"^perpendicular='yes' is not allowed; give True or False$"),
        ({"path": "slices.jpg"}, r"^path=slices.jpg: the file must end in .png, .pdf, .svg$"),
    ],
)
def test_bad_arguments_give_one_line_naming_the_argument(ward_and_lambert, arguments, message):
    call = {"results": ward_and_lambert, "samples": in_plane_samples(2, 6), **arguments}
    with pytest.raises(BrdfInputError, match=message) as error:
        slices(call.pop("results"), call.pop("samples"), **call)
    assert "\n" not in str(error.value)


def test_a_fit_of_cosine_weighted_values_is_drawn_against_them_read_so():
    """Issue 29: a fit of the tape read as cosine-weighted-out (values f·cos θo, made BRDF by dividing by cos θo)
    was drawn against the file read as brdf (``slices(result, path)`` reads a path with the defaults): f·cos θo on a
    BRDF axis, without a word. A path is read as the result's samples were; Samples read otherwise draw a warning."""
    import warnings

    from paths import TAPE

    from brdffit import InputWarning
    from brdffit.views.figures import checked_samples

    as_fitted = load_samples(TAPE, quantity="cosine-weighted-out")
    result = result_of("lambert", {"rho_d": [0.5]}, channels=as_fitted.channels)
    result = FitResult(**{**result.__dict__, "quantity": "cosine-weighted-out"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read = checked_samples(TAPE, [result])
        slices(result, TAPE)
    assert read.provenance.quantity == "cosine-weighted-out"
    np.testing.assert_array_equal(read.values, as_fitted.values)
    with pytest.warns(
        InputWarning, match=r"lambert was fitted to samples read as cosine-weighted-out; .* is read as brdf"
    ):
        slices(result, load_samples(TAPE, quantity="brdf"))


def test_a_path_is_read_with_the_options_of_the_results_reading(tmp_path):
    """A result that read its CSV in radians (``fit.reading``) has the same path read in radians again: read in
    degrees, every direction would lie within 1.6° of the normal."""
    from brdffit import InputWarning
    from brdffit.views.figures import checked_samples

    samples = data_synth.synthesize("lambert", {"rho_d": [0.3]}, *data_synth.hemisphere_grid(3, 4, 6))
    path = save_in_radians(samples, tmp_path / "radians.csv")
    result = result_of("lambert", {"rho_d": [0.3]}, channels=samples.channels)
    read = checked_samples(path, [FitResult(**{**result.__dict__, "reading": {"angles": "radians"}})])
    np.testing.assert_allclose(read.wi, load_samples(path, angles="radians").wi, rtol=0, atol=0)
    with pytest.warns(InputWarning, match="radians read as degrees"):
        assert not np.allclose(read.wi, load_samples(path).wi)
