"""Spectral samples turned into CIE XYZ, linear sRGB or kept bands (brdffit.data.spectral).

The reference is colour-science: ``sd_to_XYZ(sd, cmfs, illuminant) / 100`` of the spectral albedo, with its
classical ``Integration`` (which the conversion reproduces to rounding) and its default ``ASTM E308`` (within 1 %,
the acceptance bound, for the spacings ASTM E308 accepts).
"""

import math
import warnings

import numpy as np
import pytest

colour = pytest.importorskip("colour")

from colour.utilities import ColourRuntimeWarning  # noqa: E402

from brdffit import BrdfInputError, Samples, fit  # noqa: E402
from brdffit.data.spectral import (  # noqa: E402
    SPECTRAL_TARGETS,
    conversion_matrix,
    spectral_to,
    wavelengths,
)
from brdffit.data_synth import uniform_random  # noqa: E402

OBSERVER = "CIE 1931 2 Degree Standard Observer"
CMFS = colour.MSDS_CMFS[OBSERVER]
D65 = colour.SDS_ILLUMINANTS["D65"]
SRGB = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)

EVERY_10_NM = np.arange(400.0, 701.0, 10.0)  # 31 bands
EVERY_40_NM = np.arange(400.0, 681.0, 40.0)  # 8 bands, a spacing ASTM E308 does not accept
UNEVEN_8 = np.array([400.0, 430.0, 470.0, 520.0, 560.0, 600.0, 650.0, 700.0])
BAND_SETS = {"10nm": EVERY_10_NM, "40nm": EVERY_40_NM, "uneven": UNEVEN_8}


def albedos(wl: np.ndarray) -> dict[str, np.ndarray]:
    """Smooth spectral albedos (reflectance, 0..1); every one has positive linear sRGB."""
    return {
        "reddish": 0.05 + 0.8 / (1.0 + np.exp(-(wl - 600.0) / 15.0)),
        "greenish": 0.25 + 0.4 * np.exp(-0.5 * ((wl - 530.0) / 40.0) ** 2),
        "grey": np.full_like(wl, 0.4),
        "bluish": 0.05 + 0.7 * np.exp(-0.5 * ((wl - 450.0) / 25.0) ** 2),
    }


def colour_xyz(wl, albedo, method="Integration", illuminant=D65):
    """colour-science's XYZ of the spectral albedo, scaled to Y = 1 for a perfect reflector."""
    sd = colour.SpectralDistribution(dict(zip(wl, albedo, strict=True)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ColourRuntimeWarning)  # "Aligning … shape": the intended alignment
        return colour.sd_to_XYZ(sd, CMFS, illuminant, method=method) / 100


def lambert_samples(wl, albedo, n=64, seed=3, sigma=None) -> Samples:
    wi, wo = uniform_random(n, seed)
    values = np.tile(albedo / math.pi, (n, 1))
    return Samples.from_arrays(wi, wo, values, channels=[format(w, "g") for w in wl], sigma=sigma, source="spec.csv")


# ------------------------------------------------------------------ acceptance: agreement with colour-science
@pytest.mark.parametrize("bands", BAND_SETS)
def test_xyz_albedos_equal_colour_science(bands):
    wl = BAND_SETS[bands]
    for name, albedo in albedos(wl).items():
        converted = spectral_to(lambert_samples(wl, albedo), "xyz")
        assert converted.channels == ("x", "y", "z")
        got = math.pi * converted.values
        np.testing.assert_allclose(got, np.tile(got[0], (len(got), 1)), rtol=1e-14)
        reference = colour_xyz(wl, albedo)
        np.testing.assert_allclose(got[0], reference, rtol=1e-9, err_msg=name)
        if bands == "10nm":  # colour-science's default method, ASTM E308: within the 1 % of the acceptance
            np.testing.assert_allclose(got[0], colour_xyz(wl, albedo, "ASTM E308"), rtol=1e-3, err_msg=name)


@pytest.mark.parametrize("bands", BAND_SETS)
def test_rgb_albedos_equal_colour_science(bands):
    wl = BAND_SETS[bands]
    for name, albedo in albedos(wl).items():
        converted = spectral_to(lambert_samples(wl, albedo), "rgb")
        assert converted.channels == ("r", "g", "b")
        got = math.pi * converted.values[0]
        xyz = colour_xyz(wl, albedo)
        np.testing.assert_allclose(got, SRGB @ xyz, rtol=1e-9, err_msg=name)
        np.testing.assert_allclose(got, colour.XYZ_to_RGB(xyz, "sRGB"), rtol=1e-9, err_msg=name)
        if bands == "10nm":
            astm = colour.XYZ_to_RGB(colour_xyz(wl, albedo, "ASTM E308"), "sRGB")
            np.testing.assert_allclose(got, astm, rtol=1e-2, err_msg=name)


def test_fitted_lambert_albedo_is_colour_sciences_xyz():
    wl = EVERY_10_NM
    albedo = albedos(wl)["reddish"]
    converted = spectral_to(lambert_samples(wl, albedo, n=200), "xyz")
    result = fit(converted, "lambert")
    assert result.channels == ("x", "y", "z")
    np.testing.assert_allclose(result.params["rho_d"], colour_xyz(wl, albedo), rtol=1e-2)
    np.testing.assert_allclose(result.params["rho_d"], colour_xyz(wl, albedo, "ASTM E308"), rtol=1e-2)


def test_bands_beyond_the_colour_matching_functions_agree_with_colour_science():
    wl = np.arange(300.0, 1001.0, 50.0)  # 360–830 nm is covered; 300, 350, 850… nm only shape the interpolation
    for name, albedo in albedos(wl).items():
        weights, _ = conversion_matrix(wl, "xyz")
        np.testing.assert_allclose(albedo @ weights, colour_xyz(wl, albedo), rtol=1e-9, err_msg=name)
    weights, _ = conversion_matrix(wl, "xyz")
    np.testing.assert_array_equal(weights[-1], 0.0)  # 1000 nm is too far from 830 nm to shape the spectrum there
    assert np.all(np.abs(weights[wl >= 850.0]) < 1e-5 * weights.max())


@pytest.mark.parametrize("wl", [np.array([500.0, 600.0]), np.array([450.0, 550.0, 650.0]), np.array([420.0, 700.0])])
def test_few_bands_interpolate_linearly(wl):
    """colour-science's interpolators need 4 or 6 bands; with fewer, linear interpolation (numpy's reference)."""
    grid = CMFS.wavelengths
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ColourRuntimeWarning)
        power = D65.copy().align(CMFS.shape).values
    weighted = power[:, None] * CMFS.values
    albedo = 0.2 + 0.5 * (wl - wl[0]) / (wl[-1] - wl[0])
    reference = np.interp(grid, wl, albedo) @ weighted / weighted[:, 1].sum()
    weights, _ = conversion_matrix(wl, "xyz")
    np.testing.assert_allclose(albedo @ weights, reference, rtol=1e-12)


# ------------------------------------------------------------------ the perfect reflector
@pytest.mark.parametrize("wl", [EVERY_10_NM, EVERY_40_NM, UNEVEN_8, np.arange(400.5, 701.0, 10.0)])
def test_perfect_reflector_is_the_white_point(wl):
    white = spectral_to(lambert_samples(wl, np.ones_like(wl), n=4), "xyz").values * math.pi
    np.testing.assert_allclose(white, np.tile([0.9505, 1.0, 1.089], (4, 1)), rtol=1e-3)
    d65 = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS[OBSERVER]["D65"])
    np.testing.assert_allclose(white[0], d65, rtol=1e-2)
    rgb = spectral_to(lambert_samples(wl, np.ones_like(wl), n=4), "rgb").values * math.pi
    np.testing.assert_allclose(rgb, 1.0, rtol=1e-2)


def test_other_illuminant_and_observer():
    wl = EVERY_10_NM
    albedo = albedos(wl)["reddish"]
    weights, _ = conversion_matrix(wl, "xyz", illuminant="A", observer="CIE 1964 10 Degree Standard Observer")
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    sd = colour.SpectralDistribution(dict(zip(wl, albedo, strict=True)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ColourRuntimeWarning)
        reference = colour.sd_to_XYZ(sd, cmfs, colour.SDS_ILLUMINANTS["A"], method="Integration") / 100
    np.testing.assert_allclose(albedo @ weights, reference, rtol=1e-9)
    white = np.ones(wl.size) @ weights
    assert white[1] == pytest.approx(1.0, rel=1e-12)


# ------------------------------------------------------------------ channel names
@pytest.mark.parametrize(
    ("channels", "expected"),
    [
        (("r", "g", "b"), None),
        (("value",), None),
        (("400",), None),
        (("400", "410"), [400.0, 410.0]),
        (("400nm", "410 nm", "420NM"), [400.0, 410.0, 420.0]),
        (("400.5", "410.25", "420"), [400.5, 410.25, 420.0]),
        (("410", "400"), None),
        (("400", "400"), None),
        (("400", "g"), None),
        (("400", "nm"), None),
        (("-400", "410"), None),
        (("1e3", "2e3"), None),
        (("nan", "410"), None),
        (("150", "410"), None),
        (("2400", "2600"), None),
        (("900", "1000", "2500"), [900.0, 1000.0, 2500.0]),
    ],
)
def test_wavelengths(channels, expected):
    found = wavelengths(channels)
    if expected is None:
        assert found is None
    else:
        assert found.dtype == np.float64
        np.testing.assert_array_equal(found, expected)


def test_channel_names_with_nm_convert_like_plain_numbers():
    wl = EVERY_10_NM
    plain = lambert_samples(wl, albedos(wl)["grey"])
    named = Samples.from_arrays(plain.wi, plain.wo, plain.values, channels=[f"{w:g}nm" for w in wl])
    np.testing.assert_array_equal(spectral_to(named, "xyz").values, spectral_to(plain, "xyz").values)


# ------------------------------------------------------------------ sigma, keep, weight
def test_sigma_of_two_bands():
    """Hand-worked: y = a·w0 + b·w1 with independent σa, σb has σy = sqrt(σa² w0² + σb² w1²)."""
    wl = np.array([500.0, 600.0])
    weights, names = conversion_matrix(wl, "xyz")
    assert weights.shape == (2, 3) and names == ("x", "y", "z")
    sigma = np.array([[0.03, 0.04]])
    samples = lambert_samples(wl, np.array([0.3, 0.6]), n=1, sigma=sigma)
    converted = spectral_to(samples, "xyz")
    expected = np.sqrt(0.03**2 * weights[0] ** 2 + 0.04**2 * weights[1] ** 2)
    np.testing.assert_allclose(converted.sigma[0], expected, rtol=1e-15)
    # Equal σ in both bands and weights that sum to Y = 1 for a flat spectrum: σ_Y ≤ σ, by less than √2.
    flat = spectral_to(lambert_samples(wl, np.array([0.3, 0.6]), n=1, sigma=np.array([[0.05, 0.05]])), "xyz")
    assert 0.05 / math.sqrt(2) <= flat.sigma[0, 1] <= 0.05


def test_weight_and_directions_unchanged():
    wl = EVERY_10_NM
    plain = lambert_samples(wl, albedos(wl)["grey"], n=5)
    weighted = Samples.from_arrays(plain.wi, plain.wo, plain.values, plain.channels, weight=np.arange(1.0, 6.0))
    converted = spectral_to(weighted, "rgb")
    np.testing.assert_array_equal(converted.weight, np.arange(1.0, 6.0))
    np.testing.assert_array_equal(converted.wi, plain.wi)
    np.testing.assert_array_equal(converted.wo, plain.wo)
    assert converted.sigma is None and converted.source == weighted.source


def test_keep_is_the_identity():
    wl = UNEVEN_8
    samples = lambert_samples(wl, albedos(wl)["reddish"], sigma=np.full((64, wl.size), 0.01))
    assert spectral_to(samples, "keep") is samples
    weights, names = conversion_matrix(wl, "keep")
    np.testing.assert_array_equal(weights, np.eye(wl.size))
    assert names == samples.channels
    rgb = Samples.from_arrays(samples.wi, samples.wo, np.full((64, 3), 0.1), channels=("r", "g", "b"))
    assert spectral_to(rgb, "keep") is rgb


def test_matrix_is_a_fresh_copy():
    first, _ = conversion_matrix(EVERY_10_NM, "xyz")
    first[:] = 0.0
    again, _ = conversion_matrix(EVERY_10_NM, "xyz")
    assert again.flags.writeable and np.all(again.sum(axis=0) > 0.9)


# ------------------------------------------------------------------ errors: one line each
def one_line(error: pytest.ExceptionInfo) -> str:
    message = str(error.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("target", ["xyz", "rgb"])
def test_not_wavelengths(target):
    rgb = Samples.from_arrays(*uniform_random(3, 0), np.full((3, 3), 0.1), channels=("r", "g", "b"), source="a.csv")
    with pytest.raises(BrdfInputError) as error:
        spectral_to(rgb, target)
    assert one_line(error) == (
        f"a.csv: spectral_to={target} needs value columns named by wavelength in nm; got r, g, b"
    )


def test_unknown_illuminant_observer_target():
    samples = lambert_samples(EVERY_10_NM, albedos(EVERY_10_NM)["grey"])
    with pytest.raises(BrdfInputError) as error:
        spectral_to(samples, "xyz", illuminant="D99")
    message = one_line(error)
    assert message.startswith("illuminant='D99' is not known; choose one of: A, ")
    assert "D65" in message and "…" in message
    with pytest.raises(BrdfInputError) as error:
        conversion_matrix(EVERY_10_NM, "rgb", observer="CIE 1931 3 Degree")
    assert one_line(error).startswith("observer='CIE 1931 3 Degree' is not known; choose one of: CIE 1931 2 Degree")
    with pytest.raises(BrdfInputError) as error:
        spectral_to(samples, "lab")
    assert one_line(error) == "spectral_to='lab' is not known; choose one of: xyz, rgb, keep"
    assert SPECTRAL_TARGETS == ("xyz", "rgb", "keep")


def test_bands_that_miss_the_visible():
    wl = np.array([900.0, 1000.0, 1100.0])
    samples = lambert_samples(wl, np.full(3, 0.5))
    with pytest.raises(BrdfInputError) as error:
        spectral_to(samples, "xyz")
    assert one_line(error).startswith("spec.csv: bands 900–1100 nm miss the CIE 1931 2 Degree Standard Observer")
    assert spectral_to(samples, "keep") is samples


@pytest.mark.parametrize("bad", [[500.0], [600.0, 500.0], [500.0, np.nan], [[]]])
def test_bad_wavelength_arrays(bad):
    with pytest.raises(BrdfInputError) as error:
        conversion_matrix(bad, "xyz")
    one_line(error)


def test_negative_rgb_suggests_xyz():
    """A narrow band at 500 nm lies outside the sRGB gamut: linear red < 0."""
    wl = EVERY_10_NM
    albedo = np.where(wl == 500.0, 0.9, 0.0)
    samples = lambert_samples(wl, np.full(wl.size, 0.3), n=4)
    values = samples.values.copy()
    values[2] = albedo / math.pi
    samples = Samples.from_arrays(samples.wi, samples.wo, values, samples.channels, source="spec.csv")
    with pytest.raises(BrdfInputError) as error:
        spectral_to(samples, "rgb")
    message = one_line(error)
    assert message.startswith("spec.csv: sample 3: linear sRGB r = -")
    assert "spectral_to=xyz" in message and "keep" in message
    xyz = spectral_to(samples, "xyz")
    assert np.all(xyz.values >= 0)
