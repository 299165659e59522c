"""ALTA text data files (brdffit/data/alta.py): parameterisations, round trip, the real tape, errors, fuzzing."""

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import random_directions
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from paths import TAPE

from brdffit import load_samples
from brdffit.data.alta import PARAMETERISATIONS, read_alta, write_alta
from brdffit.data.samples import Samples
from brdffit.errors import BrdfInputError, InputWarning

S30, C30 = math.sin(math.radians(30)), math.cos(math.radians(30))
S45, C45 = math.sin(math.radians(45)), math.cos(math.radians(45))
S40, C40 = math.sin(math.radians(40)), math.cos(math.radians(40))
D20, D30, D45, D60 = (math.radians(a) for a in (20, 30, 45, 60))


def alta_file(tmp_path, body: str, name: str = "data.dat") -> Path:
    path = tmp_path / name
    path.write_text(body, encoding="utf-8")
    return path


def header(param: str, n_out: int = 1, extra: str = "") -> str:
    return f"#DIM {PARAMETERISATIONS[param]} {n_out}\n#PARAM_IN {param}\n{extra}"


def row(*numbers) -> str:
    return " ".join(repr(float(x)) for x in numbers) + "\n"


# ---------------------------------------------------------------------- parameterisations by hand
HAND_WORKED = [
    # SPHERICAL_TL_PL_TV_PV: θl, φl, θv, φv.
    ("SPHERICAL_TL_PL_TV_PV", (D30, 0, D45, math.pi), (S30, 0, C30), (-S45, 0, C45)),
    ("SPHERICAL_TL_PL_TV_PV", (D30, math.pi / 2, D30, math.pi / 2), (0, S30, C30), (0, S30, C30)),
    # ISOTROPIC_TL_TV_PROJ_DPHI: θl, θv cos Δφ, θv sin Δφ; light at φ = 0, viewer at φ = Δφ.
    ("ISOTROPIC_TL_TV_PROJ_DPHI", (D30, D30, 0), (S30, 0, C30), (S30, 0, C30)),  # retro: wo = wi
    ("ISOTROPIC_TL_TV_PROJ_DPHI", (D30, -D30, 0), (S30, 0, C30), (-S30, 0, C30)),  # mirror: Δφ = π
    ("ISOTROPIC_TL_TV_PROJ_DPHI", (D30, 0, D45), (S30, 0, C30), (0, S45, C45)),  # Δφ = π/2
    ("ISOTROPIC_TL_TV_PROJ_DPHI", (0, 0, 0), (0, 0, 1), (0, 0, 1)),  # θv = 0: any Δφ
    # RUSIN_TH_PH_TD_PD: θh, φh, θd, φd.
    ("RUSIN_TH_PH_TD_PD", (0, 0, D30, 0), (S30, 0, C30), (-S30, 0, C30)),
    ("RUSIN_TH_PH_TD_PD", (0, math.pi / 2, D30, 0), (0, S30, C30), (0, -S30, C30)),
    ("RUSIN_TH_PH_TD_PD", (D20, 0, D20, 0), (S40, 0, C40), (0, 0, 1)),  # h at 20° between 40° and the normal
    ("RUSIN_TH_PH_TD_PD", (D30, 0, 0, 1.234), (S30, 0, C30), (S30, 0, C30)),  # θd = 0: wi = wo = h
    # RUSIN_TH_TD_PD: θh, θd, φd with φh = 0.
    ("RUSIN_TH_TD_PD", (0, D30, 0), (S30, 0, C30), (-S30, 0, C30)),
    ("RUSIN_TH_TD_PD", (D20, D20, math.pi), (0, 0, 1), (S40, 0, C40)),
    # CARTESIAN: the viewer first (ALTA's params.h), then the light.
    ("CARTESIAN", (-S45, 0, C45, S30, 0, C30), (S30, 0, C30), (-S45, 0, C45)),
]


@pytest.mark.parametrize(("param", "coordinates", "wi", "wo"), HAND_WORKED)
def test_hand_worked_rows(tmp_path, param, coordinates, wi, wo):
    path = alta_file(tmp_path, header(param) + row(*coordinates, 0.25))
    samples = read_alta(path)
    np.testing.assert_allclose(samples.wi, [wi], atol=1e-12)
    np.testing.assert_allclose(samples.wo, [wo], atol=1e-12)
    assert samples.values.tolist() == [[0.25]] and samples.channels == ("value",) and samples.source == str(path)


def half_difference(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Rusinkiewicz's θh, φh, θd, φd of direction pairs (the inverse of the reader's rotation)."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    theta_h, phi_h = np.arccos(np.clip(h[:, 2], -1, 1)), np.arctan2(h[:, 1], h[:, 0])
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    x, y, z = c * wi[:, 0] - s * wi[:, 1], s * wi[:, 0] + c * wi[:, 1], wi[:, 2]
    ct, st = np.cos(-theta_h), np.sin(-theta_h)
    d = np.stack([ct * x + st * z, y, -st * x + ct * z], axis=1)
    return np.stack([theta_h, phi_h, np.arccos(np.clip(d[:, 2], -1, 1)), np.arctan2(d[:, 1], d[:, 0])], axis=1)


def spherical(w):
    return np.arccos(w[:, 2]), np.arctan2(w[:, 1], w[:, 0])


def test_every_parameterisation_gives_back_random_directions(tmp_path, rng):
    """Coordinates made from 200 known direction pairs come back as those directions."""
    n = 200
    wi, wo = random_directions(rng, n, 0.05), random_directions(rng, n, 0.05)
    values = rng.random((n, 3))
    theta_i, phi_i = spherical(wi)
    theta_o, phi_o = spherical(wo)
    # Isotropic parameterisations: turn each pair about the normal so that the light is at φ = 0.
    dphi = phi_o - phi_i
    wo_turned = np.stack([np.sin(theta_o) * np.cos(dphi), np.sin(theta_o) * np.sin(dphi), np.cos(theta_o)], axis=1)
    wi_turned = np.stack([np.sin(theta_i), np.zeros(n), np.cos(theta_i)], axis=1)
    rusin = half_difference(wi, wo)
    rusin_turned = half_difference(wi_turned, wo_turned)
    cases = {
        "SPHERICAL_TL_PL_TV_PV": (np.c_[theta_i, phi_i, theta_o, phi_o], wi, wo),
        "ISOTROPIC_TL_TV_PROJ_DPHI": (
            np.c_[theta_i, theta_o * np.cos(dphi), theta_o * np.sin(dphi)],
            wi_turned,
            wo_turned,
        ),
        "RUSIN_TH_PH_TD_PD": (rusin, wi, wo),
        "RUSIN_TH_TD_PD": (rusin_turned[:, [0, 2, 3]], *_turned_for_rusin(rusin_turned, wi_turned, wo_turned)),
        "CARTESIAN": (np.c_[wo, wi], wi, wo),
    }
    assert set(cases) == set(PARAMETERISATIONS)
    for param, (coordinates, want_wi, want_wo) in cases.items():
        body = header(param, 3) + "".join(row(*c, *v) for c, v in zip(coordinates, values, strict=True))
        samples = read_alta(alta_file(tmp_path, body, f"{param}.dat"))
        assert samples.n_samples == n, param
        np.testing.assert_allclose(samples.wi, want_wi, atol=1e-12, err_msg=param)
        np.testing.assert_allclose(samples.wo, want_wo, atol=1e-12, err_msg=param)
        np.testing.assert_allclose(samples.values, values, rtol=0, atol=0, err_msg=param)
        assert samples.channels == ("r", "g", "b")


def _turned_for_rusin(rusin, wi, wo):
    """RUSIN_TH_TD_PD drops φh: the pair turned about the normal by −φh."""
    c, s = np.cos(-rusin[:, 1]), np.sin(-rusin[:, 1])

    def turn(w):
        return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=1)

    return turn(wi), turn(wo)


def test_header_keys_outputs_and_confidence_columns(tmp_path):
    body = (
        '#SAMPLE "x"\n#ORIGIN somewhere\n#URL https://example.org\n# a free comment\n\n'
        "#dim 4 3\n#param_in spherical_tl_pl_tv_pv\n#PARAM_OUT XYZ_COLOR\n#VS 2\n"
        + "0.5 0 0.5 3.14159 0.1 0.2 0.3 0.05 0.15\n\n"
        + "0.5 0 0.5 3.14159 0.1 0.2 0.3 0.05 0.15\n"
    )
    samples = read_alta(alta_file(tmp_path, body))
    assert samples.channels == ("x", "y", "z") and samples.n_samples == 2
    np.testing.assert_allclose(samples.values, [[0.1, 0.2, 0.3]] * 2)
    # #VS 2 with two bounds per output also reads; the bounds are ignored.
    body = header("SPHERICAL_TL_PL_TV_PV", 2, "#VS 2\n") + row(0.5, 0, 0.5, 3, 0.1, 0.2, 0.0, 0.2, 0.1, 0.3)
    assert read_alta(alta_file(tmp_path, body)).values.tolist() == [[0.1, 0.2]]
    body = header("SPHERICAL_TL_PL_TV_PV", 2, "#VS 1\n") + row(0.5, 0, 0.5, 3, 0.1, 0.2, 0.01)
    assert read_alta(alta_file(tmp_path, body)).channels == ("c0", "c1")


def test_cosine_factor_output_is_weighted_by_the_view_and_divided_once(tmp_path):
    """ALTA's params.h: INV_STERADIAN_COSINE_FACTOR is the BRDF "weighted by the cosine factor of the output
    direction", the view's. The reader keeps the value and says so; loading divides by cos θv, once."""
    body = header("SPHERICAL_TL_PL_TV_PV", 1, "#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n") + row(D60, 0, 0.2, 1, 0.1)
    path = alta_file(tmp_path, body)
    read = read_alta(path)
    assert read.values.tolist() == [[0.1]] and read.provenance.header_quantity == "cosine-weighted-out"
    loaded = load_samples(path)
    np.testing.assert_allclose(loaded.values, [[0.1 / math.cos(0.2)]], rtol=1e-14)
    assert loaded.provenance.quantity == "cosine-weighted-out" and not loaded.provenance.quantity_given
    np.testing.assert_allclose(load_samples(path, quantity="cosine-weighted-out").values, loaded.values, rtol=0)
    with pytest.warns(InputWarning, match=r"read as quantity=brdf, not as the header says \(cosine-weighted-out\)"):
        assert load_samples(path, quantity="brdf").values.tolist() == [[0.1]]
    path = alta_file(tmp_path, body + row(D60, 0, 1.5707963267, 1, 1e308))
    with pytest.raises(BrdfInputError, match=r"data.dat: sample 2: the value read as cosine-weighted-out overflows"):
        load_samples(path)


def test_rows_at_or_below_the_horizon_are_dropped(tmp_path):
    body = header("SPHERICAL_TL_PL_TV_PV") + row(D30, 0, math.pi / 2, 0, 1) + row(D30, 0, 2.0, 0, 1)
    body += row(D30, 0, D45, 0, 0.5) + row(math.pi / 2, 0, D45, 0, 1)
    samples = read_alta(alta_file(tmp_path, body))
    assert samples.n_samples == 1 and samples.values.tolist() == [[0.5]]


# ---------------------------------------------------------------------- writing
@pytest.mark.parametrize(
    ("channels", "output"),
    [
        (("value",), "INV_STERADIAN"),
        (("r", "g", "b"), "RGB_COLOR"),
        (("x", "y", "z"), "XYZ_COLOR"),
        (("400", "410", "420", "430", "440"), "INV_STERADIAN"),
    ],
)
def test_write_read_round_trip(tmp_path, rng, channels, output):
    n = 300
    original = Samples.from_arrays(
        random_directions(rng, n), random_directions(rng, n), rng.random((n, len(channels))) * 5, channels=channels
    )
    path = tmp_path / "out.dat"
    write_alta(original, path)
    text = path.read_text()
    assert text.startswith(f"#DIM 4 {len(channels)}\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT {output}\n#VS 0\n")
    back = read_alta(path)
    assert back.channels == channels and back.n_samples == n
    np.testing.assert_allclose(back.wi, original.wi, atol=1e-12)
    np.testing.assert_allclose(back.wo, original.wo, atol=1e-12)
    np.testing.assert_allclose(back.values, original.values, rtol=1e-15)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.dat"]  # atomic: no temporary left


def test_write_leaves_out_channel_names_the_header_cannot_carry(tmp_path, rng):
    original = Samples.from_arrays(
        random_directions(rng, 4), random_directions(rng, 4), rng.random((4, 2)), channels=("red band", "nir")
    )
    write_alta(original, tmp_path / "o.dat")
    assert "#CHANNELS" not in (tmp_path / "o.dat").read_text()
    assert read_alta(tmp_path / "o.dat").channels == ("c0", "c1")


# ---------------------------------------------------------------------- the real measurement
def test_real_retro_reflective_tape():
    """CEA's gray tape (ALTA's documents/data): 7,405 rows, of which the 86 with θv = 90° lie on the horizon.

    Its largest value (72.5 1/sr, θl = 15°) is where the viewer is at the light: the convention
    ``wi = d(θl, 0)``, ``wo = d(θv, Δφ)`` puts the retro-reflection peak at ``wo = wi``.
    """
    samples = read_alta(TAPE)
    rows = sum(1 for line in TAPE.read_text().splitlines() if line.strip() and not line.startswith("#"))
    assert rows == 7405
    assert samples.n_samples == 7405 - 86 and samples.channels == ("value",)
    angle = np.degrees(np.arccos(np.clip(np.sum(samples.wi * samples.wo, axis=1), -1, 1)))
    top = int(np.argmax(samples.values[:, 0]))
    assert samples.values[top, 0] > 70 and angle[top] < 5
    mirror = samples.wi * np.array([-1, -1, 1])
    to_mirror = np.degrees(np.arccos(np.clip(np.sum(mirror * samples.wo, axis=1), -1, 1)))
    # At θl = 15° and 30° the retro peak dwarfs the mirror direction's values.
    for theta_l in (15, 30):
        light = np.isclose(samples.theta_i, theta_l)
        assert samples.values[light & (angle < 2)].max() > 30 * samples.values[light & (to_mirror < 2)].max()


# ---------------------------------------------------------------------- errors
GOOD = header("SPHERICAL_TL_PL_TV_PV") + row(0.5, 0, 0.5, 3, 0.1)

ERRORS = [
    ("", "empty file"),
    ("  \n\n", "empty file"),
    ("#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n", "no data rows after the header"),
    ("#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.5 0 0.5 3 0.1\n", "no #DIM line; ALTA files start with '#DIM n_in n_out'"),
    ("#DIM 4\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.5 0 0.5 3 0.1\n", "line 1: #DIM '4' is not two whole numbers"),
    ("#DIM 4 x\n#PARAM_IN CARTESIAN\n1 2\n", "line 1: #DIM '4 x' is not two whole numbers"),
    (
        "#DIM 4 0\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.5 0 0.5 3\n",
        "line 1: #DIM 4 0; both dimensions must be at least 1",
    ),
    ("#DIM 4 1\n0.5 0 0.5 3 0.1\n", "no #PARAM_IN line; give one of: SPHERICAL_TL_PL_TV_PV, ISOTROPIC_TL_TV_PROJ_DPHI"),
    (
        "#DIM 2 1\n#PARAM_IN RUSIN_TH_TD\n0.5 0.1 0.2\n",
        "line 2: unknown #PARAM_IN 'RUSIN_TH_TD'; supported: SPHERICAL_TL_PL_TV_PV, ISOTROPIC_TL_TV_PROJ_DPHI,"
        " RUSIN_TH_PH_TD_PD, RUSIN_TH_TD_PD, CARTESIAN",
    ),
    ("#DIM 4 1\n#PARAM_IN\n0.5 0 0.5 3 0.1\n", "line 2: #PARAM_IN needs one name"),
    (
        "#DIM 3 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n0.5 0 0.5 0.1\n",
        "line 1: #DIM gives 3 inputs, but #PARAM_IN SPHERICAL_TL_PL_TV_PV has 4 (theta_l, phi_l, theta_v, phi_v)",
    ),
    ("#DIM 4 1\n#DIM 4 1\n#PARAM_IN CARTESIAN\n", "line 2: #DIM appears twice (first on line 1)"),
    (GOOD.replace("0.1\n", "0.1 0.2\n"), "line 3: 6 numbers, but #DIM 4 1 (with #VS 0) means 5"),
    (GOOD + "0.5 0 0.5 0.1\n", "line 4: 4 numbers, but the rows before have 5 (#DIM 4 1)"),
    (GOOD + "0.5 0 0.5 3 nan\n", "line 4, column 5 (channel value): nan is not allowed (values must be finite)"),
    (GOOD + "0.5 0 inf 3 0.1\n", "line 4, column 3 (theta_v): inf is not allowed (values must be finite)"),
    (GOOD + "0.5 0 0.5 x3 0.1\n", "line 4, column 4 (phi_v): 'x3' is not a number"),
    (GOOD + "0.5 0 0.5 3 1_0\n", "line 4, column 5 (channel value): '1_0' is not a number"),
    (GOOD + "0.5 0 0.5 3 -0.1\n", "line 4, channel value: -0.1 is negative (negative reflectance is not allowed)"),
    (GOOD.replace("#PARAM_IN", "#VS 3\n#PARAM_IN"), "line 2: #VS '3' is not allowed; give 0 (no confidence interval)"),
    (GOOD.replace("#PARAM_IN", "#PARAM_OUT WATTS\n#PARAM_IN"), "line 2: unknown #PARAM_OUT 'WATTS'; supported:"),
    (GOOD.replace("#PARAM_IN", "#CHANNELS a b\n#PARAM_IN"), "line 2: #CHANNELS names 2 channels, but #DIM 1"),
    (
        header("SPHERICAL_TL_PL_TV_PV") + row(0.5, 0, 1.6, 3, 0.1),
        "every row has the light or the viewer at or below the horizon (z ≤ 1e-12); check #PARAM_IN",
    ),
    (
        header("CARTESIAN") + row(0, 0, 1, 0, 0, 0.5, 0.1),
        "line 3: the light (l_x, l_y, l_z) vector has length 0.5, not 1 (CARTESIAN directions must be unit vectors",
    ),
    (
        header("ISOTROPIC_TL_TV_PROJ_DPHI") + row(0.5, 1.5e308, 1.5e308, 0.1),
        "line 3, column 2 (theta_v*cos(dphi)): 1.5e+308 is beyond ±2π; ALTA angles are radians",
    ),
]


@pytest.mark.parametrize(("body", "message"), ERRORS)
def test_errors_name_the_file_and_line(tmp_path, body, message):
    path = alta_file(tmp_path, body)
    with pytest.raises(BrdfInputError) as caught:
        read_alta(path)
    text = str(caught.value)
    assert text.startswith(f"{path}: ") and message in text and "\n" not in text, text


def test_unreadable_and_binary_files(tmp_path):
    cases = {
        tmp_path / "missing.dat": "no such file",
        tmp_path: "is a folder, not an ALTA data file",
    }
    latin = tmp_path / "latin.dat"
    latin.write_bytes(b"#DIM 4 1\n#SAMPLE caf\xe9\n")
    cases[latin] = "not a text file (not UTF-8)"
    nul = tmp_path / "nul.dat"
    nul.write_bytes(b"#DIM 4 1\n\0\0\0")
    cases[nul] = "binary content (NUL bytes)"
    binary = tmp_path / "binary.dat"
    binary.write_bytes(b"#DIM 4 1\n#PARAM_IN CARTESIAN\n#FORMAT binary\n#BEGIN_STREAM\n")
    cases[binary] = "a binary ALTA data file (#FORMAT binary); only ALTA's text format is read"
    for path, message in cases.items():
        with pytest.raises(BrdfInputError, match=None) as caught:
            read_alta(path)
        assert str(caught.value).startswith(f"{path}: ") and message in str(caught.value), caught.value


# ---------------------------------------------------------------------- fuzzing
SEED = header("ISOTROPIC_TL_TV_PROJ_DPHI", 1, "#PARAM_OUT INV_STERADIAN\n#VS 0\n") + "".join(
    row(a, b, c, v) for a, b, c, v in [(0.26, -1.5, 0.1, 0.004), (0.52, 0.5, 0.0, 40.0), (1.0, -1.0, 0.01, 1.4)]
)
TOKENS = st.sampled_from(
    [
        "#DIM",
        "#PARAM_IN",
        "#PARAM_OUT",
        "#VS",
        "#CHANNELS",
        "CARTESIAN",
        "RUSIN_TH_TD_PD",
        "RGB_COLOR",
        "3",
        "1",
        "0",
        "-1",
        "2",
        "nan",
        "inf",
        "-inf",
        "1e400",
        "1e308",
        "-0.5",
        "x",
        "",
        " ",
        "\n",
        "\t",
        "#",
        "1_0",
        "é",
        "\0",
    ]
)


def _mutate(text: str, data: st.DataObject) -> str:
    for _ in range(data.draw(st.integers(1, 4))):
        choice = data.draw(st.integers(0, 4))
        if choice == 0:  # truncate
            text = text[: data.draw(st.integers(0, len(text)))]
        elif choice == 1:  # replace a token
            words = text.split(" ")
            index = data.draw(st.integers(0, max(len(words) - 1, 0)))
            words[index] = data.draw(TOKENS)
            text = " ".join(words)
        elif choice == 2:  # insert a token or random text
            at = data.draw(st.integers(0, len(text)))
            insert = data.draw(st.one_of(TOKENS, st.text(max_size=12)))
            text = text[:at] + insert + text[at:]
        elif choice == 3:  # drop or duplicate a line
            lines = text.split("\n")
            index = data.draw(st.integers(0, max(len(lines) - 1, 0)))
            if data.draw(st.booleans()):
                del lines[index]
            else:
                lines.insert(index, lines[index] if lines else "")
            text = "\n".join(lines)
        else:  # change a header value
            text = text.replace(
                data.draw(st.sampled_from(["#DIM 3 1", "ISOTROPIC_TL_TV_PROJ_DPHI", "#VS 0", "INV_STERADIAN"])),
                data.draw(
                    st.sampled_from(
                        [
                            "#DIM 4 1",
                            "#DIM 3 3",
                            "#DIM 3",
                            "SPHERICAL_TL_PL_TV_PV",
                            "#VS 1",
                            "#VS 2",
                            "XYZ_COLOR",
                            "#CHANNELS a",
                            "#DIM 6 1",
                            "CARTESIAN",
                        ]
                    )
                ),
            )
    return text


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_fuzzed_files_raise_only_brdf_input_error(data):
    text = _mutate(SEED, data)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.dat"
        if data.draw(st.booleans()):
            path.write_text(text, encoding="utf-8", errors="surrogatepass")
        else:
            path.write_bytes(text.encode("utf-8", errors="surrogatepass")[:-1] + data.draw(st.binary(max_size=8)))
        try:
            samples = read_alta(path)
        except BrdfInputError as error:
            assert str(error).startswith(f"{path}: ") and "\n" not in str(error)
        else:
            assert isinstance(samples, Samples) and samples.n_samples >= 1
            assert np.all(np.isfinite(samples.values)) and np.all(samples.values >= 0)
            assert np.all(samples.wi[:, 2] > 0) and np.all(samples.wo[:, 2] > 0)


@pytest.mark.parametrize(
    ("vs", "extra", "sigma"),
    [
        (1, "0.02", [[0.02]]),  # a half-width, read as ±1σ
        (2, "0.07 0.11", [[0.02]]),  # bounds lo, hi: sigma (hi - lo)/2
    ],
)
def test_confidence_intervals_become_sigma(tmp_path, vs, extra, sigma):
    body = header("SPHERICAL_TL_PL_TV_PV", 1, f"#VS {vs}\n") + f"{D30} 0 {D45} 1 0.09 {extra}\n"
    samples = read_alta(alta_file(tmp_path, body))
    np.testing.assert_allclose(samples.sigma, sigma, rtol=1e-12)
    assert samples.provenance.sigma_from.startswith(f"#VS {vs} confidence intervals")


def test_a_zero_width_interval_is_refused(tmp_path):
    body = header("SPHERICAL_TL_PL_TV_PV", 1, "#VS 1\n") + f"{D30} 0 {D45} 1 0.09 0\n"
    with pytest.raises(BrdfInputError, match=r"line 4, confidence interval of channel value: 0 wide"):
        read_alta(alta_file(tmp_path, body))


def test_angles_beyond_two_pi_are_degrees_in_disguise(tmp_path):
    body = header("SPHERICAL_TL_PL_TV_PV") + row(30.0, 0, 45.0, 0, 0.1)
    with pytest.raises(BrdfInputError, match=r"column 1 \(theta_l\): 30 is beyond ±2π; ALTA angles are radians"):
        read_alta(alta_file(tmp_path, body))
