"""Residual maps: one polar map per light direction for a goniometer's grid, a binned (θh, θd) map for random
data; the colours are the loss's residuals (channel means), the colour scale symmetric about 0, the label names
the loss; drawn pixels, saving, and argument errors."""

import re

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection, QuadMesh

from brdffit import BrdfInputError, FitResult, data_synth
from brdffit.data.summary import half_difference_angles
from brdffit.views.residuals import LIMIT_FLOOR, LIMIT_PERCENTILE, MAX_MAPS, colour_limit, residuals

#: What the data are (Ngan et al. 2005's Ward fit of pickled oak) and a model a little off it: residuals of both signs.
OAK = {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}
OFF = {"rho_d": [0.13, 0.1, 0.05], "rho_s": [0.04, 0.03, 0.02], "alpha": 0.2}


def result_of(params: dict, loss: str = "log", channels=("r", "g", "b")) -> FitResult:
    """A Ward result built from known parameters, without fitting."""
    return FitResult("ward", {}, tuple(channels), params, loss, 0.0, 0.0, 0, 0, True)


def colour_bar(figure):
    """The figure's one colour bar (attached to a map's scatter or mesh)."""
    (bar,) = {c.colorbar for axis in figure.axes for c in axis.collections if getattr(c, "colorbar", None)}
    return bar


def maps(figure) -> list:
    """The residual maps' axes: all but the colour bar's."""
    return [axis for axis in figure.axes if axis is not colour_bar(figure).ax]


def colour_bar_label(figure) -> str:
    return colour_bar(figure).ax.get_ylabel()


@pytest.fixture(scope="module")
def grid_samples():
    """A small goniometer grid: 4 light zeniths × 9 viewer zeniths × 12 azimuths, 1% noise."""
    return data_synth.synthesize("ward", OAK, *data_synth.hemisphere_grid(4, 9, 12), noise=0.01, seed=2)


def test_a_grid_gets_one_polar_map_per_light_coloured_by_the_mean_residual(grid_samples):
    result = result_of(OFF)
    figure = residuals(result, grid_samples)
    axes = maps(figure)
    assert len(axes) == 4 and all(axis.name == "polar" for axis in axes)
    expected = np.mean(result.residuals(grid_samples), axis=1)
    limit = np.percentile(np.abs(expected), LIMIT_PERCENTILE)
    light_zeniths = (np.arange(4) + 0.5) * 90 / 4
    for axis, theta_i in zip(axes, light_zeniths, strict=True):
        (dots,) = [c for c in axis.collections if isinstance(c, PathCollection)]
        members = np.isclose(grid_samples.theta_i, theta_i)
        assert dots.get_offsets().shape == (members.sum(), 2) == (108, 2)
        np.testing.assert_allclose(np.sort(dots.get_array()), np.sort(expected[members]), rtol=1e-12)
        # Radius θo in degrees, angle φo − φi (the light at azimuth 0): the grid's own values.
        np.testing.assert_allclose(np.unique(np.round(dots.get_offsets()[:, 1], 9)), (np.arange(9) + 0.5) * 10)
        np.testing.assert_allclose(np.unique(np.round(np.degrees(dots.get_offsets()[:, 0]), 6)), np.arange(12) * 30)
        assert dots.get_clim() == pytest.approx((-limit, limit), rel=1e-12)
        assert float(re.match(r"θi = ([0-9.]+)°", axis.get_title()).group(1)) == pytest.approx(theta_i, abs=0.051)
    bar_label = colour_bar_label(figure)
    assert bar_label.startswith("log-loss residual (mean of 3 channels)") and "> 0: model above the data" in bar_label


def test_more_lights_than_maps_are_evenly_chosen():
    samples = data_synth.synthesize("ward", OAK, *data_synth.hemisphere_grid(8, 4, 6))
    figure = residuals(result_of(OFF), samples)
    axes = maps(figure)
    assert len(axes) == MAX_MAPS
    assert any(text.get_text().startswith(f"{MAX_MAPS} of 8 light directions") for text in figure.texts)


def test_random_data_get_the_mean_residual_in_half_difference_bins():
    """3000 random pairs: 9 × 9 bins of 10° (fewer than 10 samples per bin on average for 18 × 18); each bin's
    value is the mean residual of the samples in it, computed here with numpy's histogram; empty bins masked."""
    samples = data_synth.synthesize("ward", OAK, *data_synth.uniform_random(3000, seed=5), noise=0.01, seed=6)
    result = result_of(OFF, loss="l2")
    figure = residuals(result, samples)
    (axis,) = maps(figure)
    (mesh,) = [c for c in axis.collections if isinstance(c, QuadMesh)]
    theta_h, theta_d = half_difference_angles(samples)
    mean = np.mean(result.residuals(samples), axis=1)
    edges = np.linspace(0, 90, 10)
    sums, _, _ = np.histogram2d(theta_d, theta_h, bins=(edges, edges), weights=mean)
    counts, _, _ = np.histogram2d(theta_d, theta_h, bins=(edges, edges))
    shown = np.ma.masked_invalid(mesh.get_array()).reshape(9, 9)
    np.testing.assert_array_equal(shown.mask, counts == 0)
    np.testing.assert_allclose(shown[counts > 0], (sums / np.maximum(counts, 1))[counts > 0], rtol=1e-10, atol=1e-15)
    low, high = mesh.get_clim()
    assert low == -high and high == pytest.approx(np.percentile(np.abs(shown.compressed()), LIMIT_PERCENTILE))
    assert axis.get_xlabel().startswith("θh (°)") and axis.get_ylabel().startswith("θd (°)")
    assert colour_bar_label(figure).startswith("l2-loss residual (mean of 3 channels)\nf − y")


def test_the_label_says_when_residuals_are_divided_by_sigma():
    samples = data_synth.synthesize(
        "ward", OAK, *data_synth.hemisphere_grid(2, 6, 6), noise=0.02, seed=1, with_sigma=True
    )
    figure = residuals(result_of(OFF), samples)
    assert colour_bar_label(figure).startswith("log-loss residual ÷ σ (mean of 3 channels)")


def test_the_figure_draws_finite_visible_pixels_and_saves_a_png(grid_samples, tmp_path):
    figure = residuals(result_of(OFF), grid_samples, path=tmp_path / "residuals.png")
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())
    assert np.all(np.isfinite(image)) and image[..., :3].std() > 0
    assert (tmp_path / "residuals.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"result": [result_of(OFF)]}, r"^result must be one FitResult, got list$"),
        (
            {"result": result_of({"rho_d": [0.1], "rho_s": [0.1], "alpha": 0.2}, channels=("value",))},
            r"^result: ward has channels value but the samples have r, g, b$",
        ),
        ({"samples": "nowhere/samples.csv"}, r"^nowhere/samples.csv: no such file$"),  # a path is read
        ({"samples": 3}, r"^samples must be Samples \(from brdffit.load_samples\), got int$"),
        ({"path": "maps.gif"}, r"^path=maps.gif: the file must end in .png, .pdf, .svg$"),
    ],
)
def test_bad_arguments_give_one_line_naming_the_argument(grid_samples, arguments, message):
    call = {"result": result_of(OFF), "samples": grid_samples, **arguments}
    with pytest.raises(BrdfInputError, match=message) as error:
        residuals(call.pop("result"), call.pop("samples"), **call)
    assert "\n" not in str(error.value)


def test_an_exact_fit_shows_white_not_its_rounding(grid_samples):
    """Residuals of an exact fit are rounding (~1e-17 in log-loss units): the colour limit stays at LIMIT_FLOOR, so
    the map is white, rather than stretching the rounding to full red and blue."""
    exact = data_synth.synthesize("ward", OAK, *data_synth.hemisphere_grid(4, 9, 12))
    figure = residuals(result_of(OAK), exact)
    assert colour_bar(figure).mappable.get_clim() == (-LIMIT_FLOOR, LIMIT_FLOOR)


def test_several_fits_can_share_one_colour_scale(grid_samples):
    near, far = result_of(OFF), result_of({"rho_d": [0.2, 0.15, 0.1], "rho_s": [0.1, 0.1, 0.1], "alpha": 0.3})
    shared = max(colour_limit(near, grid_samples), colour_limit(far, grid_samples))
    assert colour_limit(far, grid_samples) > colour_limit(near, grid_samples)
    for result in (near, far):
        assert colour_bar(residuals(result, grid_samples, limit=shared)).mappable.get_clim() == (-shared, shared)
    with pytest.raises(BrdfInputError, match=r"^limit=0 is not allowed; give a positive number"):
        residuals(near, grid_samples, limit=0)


def test_a_quadratic_theta_h_grid_leaves_no_empty_columns():
    """MERL's θh bins are (i/90)²·90°: at 1° bins their centres above ~25° leave every other column empty. The map
    takes the finest bins with no empty cell between two full ones."""
    from brdffit.physics.geometry import from_half_difference

    theta_h = np.radians((np.arange(90) / 90) ** 2 * 90)
    theta_d = np.radians(np.arange(0.5, 89, 1.0))
    phi_d = np.radians(np.arange(0.0, 180.0, 6.0))
    grid_h, grid_d, grid_p = (a.ravel() for a in np.meshgrid(theta_h, theta_d, phi_d))
    wi, wo = from_half_difference(grid_h, 0 * grid_h, grid_d, grid_p)
    above = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    samples = data_synth.synthesize("ward", OAK, wi[above], wo[above], noise=0.01, seed=3)
    mesh = next(
        c for axis in residuals(result_of(OFF), samples).axes for c in axis.collections if isinstance(c, QuadMesh)
    )
    full = ~np.ma.getmaskarray(mesh.get_array()).reshape(int(np.sqrt(mesh.get_array().size)), -1)
    assert not np.any(~full[:, 1:-1] & full[:, :-2] & full[:, 2:])
    assert samples.n_samples >= 10 * 90 * 90  # enough for 1° bins: only their gaps make the map coarser
    assert full.shape[0] < 90
