"""The approximation of a fit by a renderer's model: the grids it is fitted and measured on, and the optimum the coarse
to fine refit reaches."""

import numpy as np
import pytest
from paths import EXAMPLE

from brdffit import FitResult, fit, load_samples
from brdffit.export.approximate import (
    COARSE_GRID,
    FIT_GRID,
    GRID,
    dense_grid,
    error_grid,
    fitting_grid,
    mirror_symmetric,
    reference,
    refit,
)
from brdffit.physics.geometry import mirror_direction


def result_of(model: str, params: dict, **options) -> FitResult:
    """A result with known parameters, without fitting."""
    return FitResult(model, options, ("r", "g", "b"), params, "log", 0.0, 0.0, 0, 0, True)


WARD = result_of("ward", {"rho_d": [0.2, 0.15, 0.1], "rho_s": [0.05, 0.04, 0.03], "alpha": 0.15})
TURNED = result_of(
    "cook-torrance",
    {"kd": [0.1] * 3, "ks": [0.5] * 3, "alpha_u": 0.1, "alpha_v": 0.4, "phi_t": 30.0, "eta": 1.5},
    fresnel="dielectric",
    distribution="ggx",
    shadowing="smith",
    anisotropic=True,
)


def _rows(wi, wo, decimals=12):
    return {tuple(row) for row in np.round(np.hstack([wi, wo]), decimals)}


def test_the_error_grid_holds_every_lights_mirror_direction_and_the_plane_of_incidence():
    """The highlight of a glossy lobe is at the mirror direction: the grid an export's error is measured on holds it
    for each of its lights, and the plane of incidence (φo 0° and 180°), which the dense grid's midpoints miss."""
    wi, wo = error_grid()
    pairs = _rows(wi, wo)
    lights = np.unique(np.round(dense_grid()[0], 12), axis=0)
    assert len(lights) == GRID[0]
    assert all(tuple(np.round(np.hstack([light, mirror_direction(light)]), 12)) in pairs for light in lights)
    in_plane = np.abs(wo[:, 1]) < 1e-12
    assert np.any(in_plane & (wo[:, 0] > 0)) and np.any(in_plane & (wo[:, 0] < 0))
    assert not np.any(np.abs(dense_grid()[1][:, 1]) < 1e-12)  # why the plane is added


def test_the_half_grid_is_the_whole_grid_mirrored():
    """Each pair of the whole grid is a pair of the half grid or its mirror image (``wo_y → −wo_y``), once: a
    mirror-symmetric BRDF's cost on the half grid is half its cost on the whole, at every parameter."""
    whole, half = fitting_grid(FIT_GRID), fitting_grid(FIT_GRID, symmetric=True)
    assert 2 * len(half[0]) == len(whole[0]) and np.all(half[1][:, 1] > 0)
    mirrored = (half[0], half[1] * np.array([1.0, -1.0, 1.0]))
    assert _rows(*whole) == _rows(*half) | _rows(*mirrored)


def test_the_coarse_grid_is_a_subset_of_the_fine_one():
    """The start search sees the same lights and a subset of the fine grid's directions (module docstring: fewer
    lights moved glTF's optimum to another valley)."""
    for symmetric in (False, True):
        assert _rows(*fitting_grid(COARSE_GRID, symmetric)) <= _rows(*fitting_grid(FIT_GRID, symmetric))


def test_mirror_symmetry_is_detected():
    """An isotropic fit is mirror-symmetric about the plane of incidence; a lobe turned by 30° is not (its fit keeps
    the whole grid)."""
    assert mirror_symmetric(WARD.predict) and not mirror_symmetric(TURNED.predict)
    assert reference(WARD).symmetric and not reference(TURNED).symmetric


@pytest.fixture(scope="module")
def oak():
    return fit(load_samples(EXAMPLE), "ward")


def test_the_coarse_to_fine_refit_reaches_the_whole_grids_optimum(oak):
    """Mitsuba's GGX stand-in fitted to the oak example's Ward fit: coarse to fine on the half grid, its error over the
    error grid is that of the fit on the whole 38,880-pair grid with every start (0.065 1/sr, 118.4% of the BRDF's
    rms, directional albedo within 16.15%: the export before the half grid, docs/export.md); within 0.1%, the
    solver's tolerance on a flat optimum."""
    _, approximation = refit(oak, "cook-torrance", fresnel="conductor", distribution="ggx", shadowing="smith")
    assert approximation.relative_rmse == pytest.approx(1.184, rel=1e-3)
    assert approximation.albedo_error == pytest.approx(0.1615, rel=1e-3)
