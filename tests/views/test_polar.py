"""Polar plots of the plane of incidence: half discs with the normal up, a log radius, the in-plane samples
exactly, curves equal to ``predict``, the light's ray, the legend, drawn pixels, saving, and argument errors."""

import numpy as np
import pytest
from conftest import directions_from_degrees
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Annotation

from brdffit import BrdfInputError, FitResult, data_synth
from brdffit.views.polar import MIN_POLAR_RANGE, POLAR_RANGE, polar

#: A Ward lobe over a diffuse floor: the radius spans about a decade and a half.
WARD = {"rho_d": [0.3, 0.2, 0.1], "rho_s": [0.1, 0.08, 0.05], "alpha": 0.2}
LAMBERT = {"rho_d": [0.35, 0.25, 0.12]}


def result_of(model: str, params: dict, channels=("r", "g", "b"), **options) -> FitResult:
    """A result built from known parameters, without fitting."""
    return FitResult(model, options, tuple(channels), params, "log", 0.0, 0.0, 0, 0, True)


def lines(axis, prefix: str) -> list:
    return [line for line in axis.get_lines() if (line.get_gid() or "").startswith(prefix + ":")]


@pytest.fixture(scope="module")
def samples():
    """Ward values in the plane of incidence only: 3 incidences (15°, 45°, 75°) × 24 signed θo."""
    return data_synth.synthesize("ward", WARD, *data_synth.in_plane(3, 24))


@pytest.fixture(scope="module")
def results():
    return [result_of("ward", WARD), result_of("lambert", LAMBERT)]


def test_half_discs_with_the_normal_up_and_a_log_radius(samples, results):
    figure = polar(results, samples)
    axes = [axis for axis in figure.axes if axis.name == "polar"]
    assert len(axes) == len(figure.axes) == 3
    for axis in axes:
        assert (axis.get_thetamin(), axis.get_thetamax()) == pytest.approx((-90.0, 90.0))
        assert axis.get_theta_offset() == pytest.approx(np.pi / 2)  # θo = 0 (the normal) up
        assert axis.get_theta_direction() == -1  # θo > 0, the mirror side, to the right
        assert axis.get_yscale() == "log"
        floor, top = axis.get_ylim()
        assert top / POLAR_RANGE <= floor * (1 + 1e-12) and floor <= top / MIN_POLAR_RANGE * (1 + 1e-12)


def test_the_points_are_exactly_the_in_plane_samples_and_the_curves_are_predict(samples, results):
    figure = polar(results, samples)
    signed = (np.arange(24) + 0.5) * 180 / 24 - 90  # data_synth's, < 0 on the mirror side
    for axis, theta_i in zip(figure.axes, (15.0, 45.0, 75.0), strict=True):
        data = lines(axis, "data")
        assert [line.get_gid() for line in data] == ["data:r", "data:g", "data:b"]
        assert len(lines(axis, "fit")) == 2 * 3
        members = np.isclose(samples.theta_i, theta_i)
        floor, top = axis.get_ylim()
        shown = samples.values[members, 0] > floor
        np.testing.assert_allclose(np.sort(data[0].get_xdata()), np.sort(np.radians(-signed[shown])), atol=1e-12)
        np.testing.assert_allclose(np.sort(data[0].get_ydata()), np.sort(samples.values[members, 0][shown]))
        assert top >= samples.values[members].max()
        for index, result in enumerate(results):
            curve = next(line for line in lines(axis, "fit") if line.get_gid() == f"fit:{index}:r")
            angles, radius = np.degrees(curve.get_xdata()), np.asarray(curve.get_ydata())
            for wanted in (-50.0, 0.0, theta_i, 80.0):
                k = int(np.argmin(np.abs(angles - wanted)))
                wo = directions_from_degrees(abs(angles[k]), 180.0 if angles[k] > 0 else 0.0)
                expected = result.predict(directions_from_degrees(theta_i, 0.0), wo)[0, 0]
                assert radius[k] == pytest.approx(max(expected, floor), rel=1e-12)


def test_the_light_is_a_ray_at_minus_theta_i(samples, results):
    figure = polar(results, samples)
    for axis, theta_i in zip(figure.axes, (15.0, 45.0, 75.0), strict=True):
        (ray,) = [text for text in axis.texts if isinstance(text, Annotation)]
        floor, top = axis.get_ylim()
        assert ray.xy == pytest.approx((np.radians(-theta_i), floor))
        assert ray.xyann == pytest.approx((np.radians(-theta_i), top))
    labels = [text.get_text() for text in figure.legends[0].get_texts()]
    assert labels[:3] == ["ward", "lambert", "data"] and "light (at −θi)" in labels


def test_random_data_say_so_and_still_draw_the_curves(results):
    random = data_synth.synthesize("ward", WARD, *data_synth.uniform_random(200, seed=3))
    figure = polar(results[0], random, incidences=[20, 50])
    for axis in figure.axes:
        assert not lines(axis, "data") and len(lines(axis, "fit")) == 3
        assert "no samples within 0.5° of this plane" in axis.get_title()


def test_the_figure_draws_finite_visible_pixels_and_saves_a_png(samples, results, tmp_path):
    figure = polar(results, samples, path=tmp_path / "polar.png")
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())
    assert np.all(np.isfinite(image)) and image[..., :3].std() > 0
    assert (tmp_path / "polar.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"results": 3}, r"^results must be a FitResult or a non-empty list of them, got int$"),
        ({"max_panels": 2.5}, r"^max_panels=2.5 is not allowed"),
        ({"incidences": [-1]}, r"^incidences=\[-1\] is not allowed"),
        ({"path": "polar"}, r"^path=polar: the file must end in .png, .pdf, .svg$"),
    ],
)
def test_bad_arguments_give_one_line_naming_the_argument(samples, results, arguments, message):
    call = {"results": results, **arguments}
    with pytest.raises(BrdfInputError, match=message) as error:
        polar(call.pop("results"), samples, **call)
    assert "\n" not in str(error.value)


def test_a_long_spec_wraps_and_the_legend_stays_on_the_figure(samples):
    """Issue 29: a long model spec in the legend ran off the figure's right edge. It wraps after its ``:`` and ``,``
    and the figure grows tall enough for the legend's lines."""
    options = {"distribution": "ggx", "shadowing": "smith-correlated", "fresnel": "dielectric"}
    params = {"kd": [0.1] * 3, "ks": [0.5] * 3, "m": 0.2, "eta": 1.5}
    long = [result_of("cook-torrance", params, **options), result_of("cook-torrance", params | {"m": 0.3}, **options)]
    figure = polar(long, samples)
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    (legend,) = figure.legends
    box = legend.get_window_extent(canvas.get_renderer())
    assert figure.bbox.x0 <= box.x0 and box.x1 <= figure.bbox.x1
    assert figure.bbox.y0 <= box.y0 and box.y1 <= figure.bbox.y1
    assert [text.get_text().split("\n")[0] for text in legend.get_texts()[:2]] == ["cook-torrance:"] * 2
