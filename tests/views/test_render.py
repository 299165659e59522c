"""The lit-sphere renderer: golden values of the rendering equation, reciprocity, anisotropy, finite values, the
measured lookup against the model it was sampled from, and the display transform."""

import numpy as np
import pytest
from catalogue import RECIPROCAL_CASES, case_params
from paths import EXAMPLE

from brdffit import BrdfInputError, data_synth, evaluate, load_samples
from brdffit.physics.geometry import from_half_difference
from brdffit.views.render import (
    LIGHTS,
    LUMINANCE_WEIGHTS,
    MAX_DISTANCE_DEGREES,
    Light,
    display_rgb,
    exposure_for,
    render_measured,
    render_sphere,
    rusinkiewicz_embedding,
    shading_frame,
    sphere_normals,
    to_srgb,
)
from brdffit.views.sphere import DENSE_FRACTION

LAMBERT = {"rho_d": [0.5, 0.3, 0.2]}
#: A broad, smooth lobe over a diffuse base: what a nearest-neighbour lookup should reproduce closely.
BROAD_WARD = {"rho_d": [0.2], "rho_s": [0.1], "alpha": 0.3}


def pixel_normals(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pixel centres' ``x``, ``y`` (size, size) and ``n_z`` (NaN outside the disc), computed here afresh."""
    centres = -1.0 + (np.arange(size) + 0.5) * (2.0 / size)
    x = np.tile(centres, (size, 1))
    y = -x.T
    with np.errstate(invalid="ignore"):
        n_z = np.sqrt(1.0 - x**2 - y**2)
    return x, y, n_z


# ---------------------------------------------------------------------- geometry
def test_the_disc_and_its_normals():
    inside, normals = sphere_normals(9)
    x, y, n_z = pixel_normals(9)
    assert np.array_equal(inside, np.isfinite(n_z) & (n_z > 0))
    assert np.allclose(normals, np.stack([x[inside], y[inside], n_z[inside]], axis=-1), rtol=0, atol=1e-15)
    assert normals[0, 1] > 0  # row 0 is the top of the image


def test_the_shading_frame_is_orthonormal_right_handed_and_its_tangent_runs_along_the_parallels():
    _, normals = sphere_normals(64)
    frame = shading_frame(normals)
    assert np.allclose(frame @ np.swapaxes(frame, -1, -2), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(frame), 1.0, atol=1e-14)  # t × b = n
    tangent = frame[:, 0]
    assert np.allclose(tangent[:, 1], 0.0)  # east about the vertical axis: no vertical component
    assert np.all(tangent[:, 0] > 0)  # pointing right on the visible hemisphere (n_z > 0)
    # At the poles, on the silhouette, the frame is still defined.
    poles = shading_frame(np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]))
    assert np.all(np.isfinite(poles))
    assert np.allclose(poles[:, 0], [[1.0, 0.0, 0.0]] * 2)


def test_the_rusinkiewicz_embedding_recovers_the_angles_and_is_reciprocal(rng):
    """Directions built from known angles by ALTA's converter (Rusinkiewicz 1998) give those angles back, and
    swapping light and viewer (φd → φd + π) gives the same point."""
    n = 2000
    theta_h, theta_d = rng.uniform(0, np.pi / 2, (2, n))
    phi_h, phi_d = rng.uniform(-np.pi, np.pi, (2, n))
    wi, wo = from_half_difference(theta_h, phi_h, theta_d, phi_d)
    point = rusinkiewicz_embedding(wi, wo)
    radius = 0.5 * np.sin(theta_d)
    expected = np.stack([theta_h, theta_d, radius * np.cos(2 * phi_d), radius * np.sin(2 * phi_d)], axis=-1)
    assert np.allclose(point, expected, atol=1e-7)  # arccos near 0 loses half the digits: ~1e-8 rad
    assert np.allclose(rusinkiewicz_embedding(wo, wi), point, atol=1e-7)


# ---------------------------------------------------------------------- golden values
def test_a_lambert_sphere_lit_from_the_camera_is_rho_over_pi_times_e_times_n_z():
    """Light along the view axis: cos θi = n_z, so L = ρd/π · E · n_z at every pixel centre, per channel."""
    irradiance = (2.0, 0.5, 1.25)
    image = render_sphere("lambert", LAMBERT, size=33, lights=[Light("camera", (0.0, 0.0, 1.0), irradiance)])
    _, _, n_z = pixel_normals(33)
    inside = np.isfinite(n_z)
    expected = np.asarray(LAMBERT["rho_d"]) / np.pi * np.asarray(irradiance) * n_z[inside][:, None]
    assert image.shape == (33, 33, 3)
    assert np.allclose(image[inside], expected, rtol=1e-12, atol=0)
    assert np.all(image[~inside] == 0.0)


def test_one_channel_takes_the_lights_luminance_and_scales_with_its_albedo():
    light = Light("camera", (0.0, 0.0, 1.0), (1.0, 2.0, 3.0))
    one = render_sphere("lambert", {"rho_d": [0.4]}, size=17, lights=[light])
    twice = render_sphere("lambert", {"rho_d": [0.8]}, size=17, lights=[light])
    _, _, n_z = pixel_normals(17)
    inside = np.isfinite(n_z)
    luminance = float(np.dot(LUMINANCE_WEIGHTS, light.irradiance))
    assert np.allclose(one[inside, 0], 0.4 / np.pi * luminance * n_z[inside], rtol=1e-12, atol=0)
    assert np.allclose(twice, 2 * one, rtol=1e-12, atol=0)


def test_a_light_from_behind_lights_nothing_and_lights_add_up():
    behind = Light("behind", (0.0, 0.0, -1.0))
    assert np.all(render_sphere("ward", _ward(), size=32, lights=[behind]) == 0.0)
    key, fill = LIGHTS["environment"][:2]
    both = render_sphere("ward", _ward(), size=32, lights=[key, fill])
    apart = render_sphere("ward", _ward(), size=32, lights=[key]) + render_sphere(
        "ward", _ward(), size=32, lights=[fill]
    )
    assert np.allclose(both, apart, rtol=1e-13, atol=0)


@pytest.mark.parametrize("case", case_params(RECIPROCAL_CASES, as_one=True))
def test_swapping_light_and_view_gives_the_same_brdf_helmholtz(case):
    """On the middle row of an odd-sized image (``y = 0``), pixels a and b at angles βa, βb from the view axis,
    with the light at ``α = βa + βb``, see the pair (θi, θo) = (βb, βa) and (βa, βb), both in the plane of
    incidence on opposite sides of the normal: a swap (and a half turn about the normal, which no model here
    notices). Reciprocity: ``L_a / cos βb = f(βb, βa) = f(βa, βb) = L_b / cos βa``."""
    name, options, params = case
    size = 65
    middle = size // 2
    centres = -1.0 + (np.arange(size) + 0.5) * (2.0 / size)
    for column_a, column_b in ((36, 44), (40, 50), (33, 57), (45, 45)):
        beta_a, beta_b = np.arcsin(centres[column_a]), np.arcsin(centres[column_b])
        alpha = beta_a + beta_b
        light = Light("probe", (np.sin(alpha), 0.0, np.cos(alpha)))
        image = render_sphere(name, params, size=size, lights=[light], **options)
        brdf_a = image[middle, column_a] / np.cos(beta_b)
        brdf_b = image[middle, column_b] / np.cos(beta_a)
        assert np.all(brdf_a > 0)
        assert np.allclose(brdf_a, brdf_b, rtol=1e-12, atol=0)
        # and both are the model's own value at that pair
        wi = np.array([[np.sin(beta_b), 0.0, np.cos(beta_b)]])
        wo = np.array([[-np.sin(beta_a), 0.0, np.cos(beta_a)]])
        assert np.allclose(brdf_a, evaluate(name, params, wi, wo, **options)[0], rtol=1e-12, atol=0)


# ---------------------------------------------------------------------- anisotropy
def _highlight_second_moments(model: str, params: dict) -> tuple[float, float]:
    """Second moments of the highlight about its centre along the image's x and y, lit from the camera."""
    image = render_sphere(model, params, size=129, lights=[Light("camera", (0.0, 0.0, 1.0))])[..., 0]
    x, y, _ = pixel_normals(129)
    weight = image / image.sum()
    mean_x, mean_y = np.sum(weight * x), np.sum(weight * y)
    return float(np.sum(weight * (x - mean_x) ** 2)), float(np.sum(weight * (y - mean_y) ** 2))


def test_an_anisotropic_highlight_is_longer_along_its_rougher_axis_and_an_isotropic_one_is_round():
    """Lit from the camera the half vector is the view direction; at the disc's centre the tangent is the image's
    x axis. ``alpha_x < alpha_y``: the highlight spreads more along y; swapping the two turns it by 90°."""
    along_x, along_y = _highlight_second_moments(
        "ward-aniso", {"rho_d": [0.0], "rho_s": [1.0], "alpha_x": 0.05, "alpha_y": 0.2}
    )
    assert along_y > 4 * along_x  # a Gaussian in slope: the spread grows like α², (0.2/0.05)² = 16
    swapped = _highlight_second_moments("ward-aniso", {"rho_d": [0.0], "rho_s": [1.0], "alpha_x": 0.2, "alpha_y": 0.05})
    assert swapped[0] > 4 * swapped[1]
    round_x, round_y = _highlight_second_moments("ward", {"rho_d": [0.0], "rho_s": [1.0], "alpha": 0.1})
    assert round_x == pytest.approx(round_y, rel=1e-12)  # the square grid is symmetric under x ↔ y


# ---------------------------------------------------------------------- finite everywhere
@pytest.mark.parametrize(
    ("model", "params", "options"),
    [
        ("phong", {"rho_d": [0.1], "rho_s": [0.9], "n": 1e4}, {}),
        ("cook-torrance", {"kd": [0.1], "ks": [0.9], "m": 1e-3, "f0": 0.04}, {"fresnel": "schlick"}),
        ("ward", {"rho_d": [0.1], "rho_s": [0.9], "alpha": 1e-3}, {}),
        ("ward-aniso", {"rho_d": [0.1], "rho_s": [0.9], "alpha_x": 1e-3, "alpha_y": 0.5}, {}),
    ],
    ids=["phong-1e4", "cook-torrance-m-1e-3", "ward-1e-3", "ward-aniso-1e-3"],
)
@pytest.mark.parametrize("lights", [*LIGHTS, "grazing"])
def test_sharp_lobes_and_grazing_pixels_stay_finite(model, params, options, lights):
    if lights == "grazing":  # at 89° from the view axis: every pixel near the limb is grazing in and out
        lights = [Light("grazing", (np.sin(np.radians(89.0)), 0.0, np.cos(np.radians(89.0))))]
    image = render_sphere(model, params, size=128, lights=lights, **options)
    inside, _ = sphere_normals(128)
    assert np.all(np.isfinite(image))
    assert np.all(image >= 0)
    assert np.all(image[~inside] == 0.0)
    assert np.any(image[inside] > 0)


# ---------------------------------------------------------------------- measured values
def _rusinkiewicz_angles(wi, wo):
    """θh, θd, φd computed here by another route: ``d``'s coordinates in the frame ``(∂h/∂θh, ∂h/∂φh / sin θh, h)``."""
    half = wi + wo
    half = half / np.linalg.norm(half, axis=1, keepdims=True)
    theta_h = np.arccos(np.clip(half[:, 2], -1, 1))
    phi_h = np.arctan2(half[:, 1], half[:, 0])
    meridian = np.stack([np.cos(theta_h) * np.cos(phi_h), np.cos(theta_h) * np.sin(phi_h), -np.sin(theta_h)], 1)
    parallel = np.stack([-np.sin(phi_h), np.cos(phi_h), np.zeros_like(phi_h)], 1)
    theta_d = np.arccos(np.clip(np.sum(wi * half, 1), -1, 1))
    phi_d = np.arctan2(np.sum(wi * parallel, 1), np.sum(wi * meridian, 1))
    return theta_h, theta_d, phi_d


def _nearest_neighbour_tolerance(params: dict, size: int, lights: str) -> np.ndarray:
    """A pixel's bound on ``|measured − model|`` (P,) when every value comes from a sample within
    D = MAX_DISTANCE_DEGREES: per light, ``E · cos θi · ‖Δf‖`` with ``‖Δf‖ = sqrt(Σ_k Δ_k²)`` and ``Δ_k`` the
    largest change of f over a step of D either way along θh, θd and φd (an arc sin θd · Δφd = D): the first-order
    bound ‖∇f‖·D, with each derivative taken over the whole step so that the curvature is in it."""
    step = np.radians(MAX_DISTANCE_DEGREES)
    _, normals = sphere_normals(size)
    frame = shading_frame(normals)
    wo = frame @ np.array([0.0, 0.0, 1.0])
    tolerance = np.zeros(len(normals))
    for light in LIGHTS[lights]:
        wi = frame @ np.asarray(light.direction)
        lit = wi[:, 2] > 0
        angles = _rusinkiewicz_angles(wi[lit], wo[lit])
        centre = evaluate("ward", params, *from_half_difference(angles[0], 0 * angles[0], *angles[1:]))
        squares = 0.0
        for axis, width in enumerate((step, step, step / np.maximum(np.sin(angles[1]), 1e-9))):
            largest = 0.0
            for sign in (1.0, -1.0):
                moved = [a.copy() for a in angles]
                moved[axis] = moved[axis] + sign * width
                moved[0], moved[1] = np.clip(moved[0], 0, np.pi / 2), np.clip(moved[1], 0, np.pi / 2)
                pair_in, pair_out = from_half_difference(moved[0], 0 * moved[0], moved[1], moved[2])
                above = (pair_in[:, 2] > 0) & (pair_out[:, 2] > 0)
                value = np.zeros_like(centre)
                value[above] = evaluate("ward", params, pair_in[above], pair_out[above])
                largest = np.maximum(largest, np.abs(value - centre)[:, 0])
            squares = squares + largest**2
        tolerance[lit] += light.irradiance[0] * wi[lit, 2] * np.sqrt(squares)
    return tolerance


@pytest.fixture(scope="module")
def dense_ward():
    """200,000 pairs uniform over both hemispheres: a sample within 2° of ~99% of the sphere's lookups."""
    return data_synth.synthesize("ward", BROAD_WARD, *data_synth.uniform_random(200_000, seed=7))


@pytest.mark.parametrize("lights", list(LIGHTS))
def test_a_dense_measured_sphere_matches_the_model_within_the_nearest_neighbour_error(dense_ward, lights):
    size = 64
    measured = render_measured(dense_ward, size=size, lights=lights)
    model = render_sphere("ward", BROAD_WARD, size=size, lights=lights)
    inside, _ = sphere_normals(size)
    assert measured.data_fraction >= DENSE_FRACTION
    assert np.array_equal(measured.lit[inside], (model[inside, 0] > 0))
    tolerance = _nearest_neighbour_tolerance(BROAD_WARD, size, lights)
    error = np.abs(measured.radiance - model)[inside, 0]
    has_data = measured.has_data[inside]
    assert np.all(error[has_data] <= tolerance[has_data] + 1e-15)
    assert np.all(measured.radiance[~measured.has_data] == 0.0)


def test_a_lambert_measured_sphere_is_the_model_exactly_where_there_is_data(rng):
    """A constant BRDF: whichever sample is nearest, its value is the model's."""
    samples = data_synth.synthesize("lambert", LAMBERT, *data_synth.uniform_random(20_000, seed=3))
    measured = render_measured(samples, size=48, lights="environment", max_distance=5.0)
    model = render_sphere("lambert", LAMBERT, size=48, lights="environment")
    assert measured.data_fraction > 0.9
    assert np.allclose(measured.radiance[measured.has_data], model[measured.has_data], rtol=1e-12, atol=0)


def test_sparse_gonioreflectometer_data_cover_little_of_the_sphere():
    """The shipped 10k example: 8 light zeniths 11.25° apart leave most of the (θh, θd, φd) space beyond 2°."""
    samples = load_samples(EXAMPLE)
    for lights in LIGHTS:
        measured = render_measured(samples, size=64, lights=lights)
        assert 0 < measured.data_fraction < DENSE_FRACTION
        assert np.all(measured.has_data <= measured.lit)


def test_bad_arguments_are_named():
    with pytest.raises(BrdfInputError, match=r"^lights='sun' is not allowed; choose one of: point, environment$"):
        render_sphere("lambert", LAMBERT, lights="sun")
    with pytest.raises(BrdfInputError, match=r"^lights must be one of"):
        render_sphere("lambert", LAMBERT, lights=[])
    with pytest.raises(BrdfInputError, match=r"^size=1 is not allowed"):
        render_sphere("lambert", LAMBERT, size=1)
    with pytest.raises(BrdfInputError, match=r"^direction=\(0, 0, 0\) must be"):
        Light("none", (0, 0, 0))
    with pytest.raises(BrdfInputError, match=r"^max_distance=0 is not allowed"):
        render_measured(load_samples(EXAMPLE), max_distance=0)


# ---------------------------------------------------------------------- display
def test_the_srgb_transfer_function_is_colour_sciences():
    import colour

    linear = np.array([0.0, 0.001, 0.0031308, 0.01, 0.18, 0.5, 1.0])
    assert np.allclose(to_srgb(linear), colour.cctf_encoding(linear, function="sRGB"), rtol=1e-12, atol=1e-15)
    assert np.allclose(to_srgb(np.array([-1.0, 2.0, np.nan])), [0.0, 1.0, 0.0], rtol=0, atol=1e-15)  # NaN: black
    assert to_srgb(np.array([0.25]), exposure=4.0)[0] == pytest.approx(1.0, rel=1e-15)


def test_channels_are_shown_as_rgb_grey_or_xyz_converted():
    import colour

    radiance = np.array([[0.2, 0.4, 0.6]])
    assert display_rgb(radiance, ("r", "g", "b")) == (pytest.approx(radiance), "")
    grey, note = display_rgb(np.array([[0.1, 0.2, 0.3, 0.4, 0.5]]), [f"c{k}" for k in range(5)])
    assert np.allclose(grey, 0.3) and note == "grey: mean of 5 channels"
    white = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    rgb, note = display_rgb(white[None, :], ("x", "y", "z"))
    assert np.allclose(rgb, 1.0, atol=1e-3) and note  # D65 white is sRGB white (to the matrix's 4 digits)


def test_xyz_channels_see_the_same_white_light():
    """White lights in XYZ channels have D65's XYZ: an XYZ Lambert sphere of a flat albedo shows as sRGB grey."""
    light = [Light("camera", (0.0, 0.0, 1.0))]
    rgb = render_sphere("lambert", {"rho_d": [0.5, 0.5, 0.5]}, size=9, lights=light)
    xyz = render_sphere("lambert", {"rho_d": [0.5, 0.5, 0.5]}, size=9, lights=light, channels=("x", "y", "z"))
    assert np.allclose(display_rgb(xyz, ("x", "y", "z"))[0], rgb, rtol=1e-13, atol=0)


def test_the_exposure_puts_the_chosen_percentile_at_white():
    luminance = np.linspace(0.0, 2.0, 1001)
    image = luminance[:, None] * np.ones(3)
    exposure = exposure_for(image)
    assert exposure == pytest.approx(1.0 / np.percentile(luminance[1:], 99.0), rel=1e-12)
    assert exposure_for(np.zeros((4, 3))) == 1.0
    # pooled images share one exposure
    assert exposure_for([image, 2 * image]) < exposure


def _ward() -> dict:
    return {"rho_d": [0.143, 0.094, 0.054], "rho_s": [0.0359, 0.0313, 0.0215], "alpha": 0.146}
