"""Reciprocal pairs tell what a file's values are: the real tape, ALTA's cosine header, and made-up quantities."""

import math
import time
import warnings

import numpy as np
import pytest
from paths import SHARED_DATA, TAPE

from brdffit import data_synth, load_samples, save_samples
from brdffit.cli import main
from brdffit.data.quantities import stored_factor
from brdffit.data.reciprocity import MIN_PAIRS, RECIPROCAL, ReciprocityAhead, reciprocity
from brdffit.data.samples import Samples
from brdffit.errors import FitWarning, InputWarning
from brdffit.physics.geometry import spherical_to_direction

#: A sharp retro lobe beside a forward one: values that differ by orders of magnitude between a pair's two
#: directions if the quantity is read wrong.
TAPE_LIKE = {
    "rho_d": [0.3],
    "lobes": [
        {"rho_s": [0.25], "cxy": 0.577, "cz": 0.578, "n": 300.0},
        {"rho_s": [0.2], "cxy": -0.58, "cz": 0.571, "n": 37.0},
    ],
}


def isotropic_pairs():
    """A gonioreflectometer grid whose light zeniths are among its view zeniths: many reciprocal pairs."""
    theta = np.radians([10.0, 25.0, 40.0, 55.0, 70.0])
    phi = np.radians(np.arange(0.0, 181.0, 15.0))
    light, view, azimuth = np.meshgrid(theta, theta, phi, indexing="ij")
    wi = spherical_to_direction(light.ravel(), 0 * light.ravel())
    wo = spherical_to_direction(view.ravel(), azimuth.ravel())
    return wi, wo


@pytest.fixture(scope="module")
def brdf_values():
    return data_synth.synthesize("lafortune", TAPE_LIKE, *isotropic_pairs(), noise=0.0, lobes=2)


def test_brdf_values_are_reciprocal_and_cosine_readings_are_not(brdf_values):
    found = reciprocity(brdf_values)
    assert found.pairs >= MIN_PAIRS and found.reciprocal and found.best == "brdf"
    # Every model here is exactly reciprocal: the median ratio is 1 to rounding.
    assert found.ratios["brdf"] == pytest.approx(1.0, rel=1e-12)
    assert found.ratios["cosine-weighted-in"] < RECIPROCAL[0] < RECIPROCAL[1] < found.ratios["cosine-weighted-out"]


def test_the_check_started_ahead_finds_what_the_check_finds_and_raises_what_it_raises(brdf_values):
    """A fit starts the check in a thread while it compiles (``ReciprocityAhead``): its answer is the check's, and an
    error inside the thread reaches the caller of ``result()``."""
    cosine = Samples.from_arrays(
        brdf_values.wi, brdf_values.wo, brdf_values.values * brdf_values.wi[:, 2:3], source="cosine"
    )
    for samples in (brdf_values, cosine):
        assert ReciprocityAhead(samples).result(timeout=60) == reciprocity(samples)
    failed = ReciprocityAhead(None)  # type: ignore[arg-type]
    depths = []
    for _ in range(2):  # raised again as it was: its traceback does not grow with each result()
        with pytest.raises(AttributeError) as raised:
            failed.result(timeout=60)
        depths.append(len(raised.traceback))
    assert depths[0] == depths[1]


@pytest.mark.parametrize("quantity", ["cosine-weighted-in", "cosine-weighted-out", "reflectance-factor"])
def test_a_file_of_any_quantity_reads_reciprocal_under_its_own(brdf_values, quantity, tmp_path):
    stored = brdf_values.values * stored_factor(quantity, brdf_values.wi, brdf_values.wo)
    path = tmp_path / "values.csv"
    save_samples(Samples.from_arrays(brdf_values.wi, brdf_values.wo, stored), path)
    as_brdf = reciprocity(load_samples(path))
    right = reciprocity(load_samples(path, quantity=quantity))
    assert right.reciprocal and right.as_read == pytest.approx(1.0, rel=1e-9)
    reading = "brdf" if quantity == "reflectance-factor" else quantity
    assert as_brdf.best == reading and (as_brdf.reciprocal == (quantity == "reflectance-factor"))


def write_alta(path, wi, wo, values, param_out="INV_STERADIAN_COSINE_FACTOR"):
    """An ALTA file of spherical angles (radians) and one channel, its header naming ``param_out``."""
    theta_l, phi_l = np.arccos(wi[:, 2]), np.arctan2(wi[:, 1], wi[:, 0])
    theta_v, phi_v = np.arccos(wo[:, 2]), np.arctan2(wo[:, 1], wo[:, 0])
    rows = np.column_stack([theta_l, phi_l, theta_v, phi_v, values])
    header = f"#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT {param_out}\n"
    path.write_text(header + "".join(" ".join(f"{x:.17g}" for x in row) + "\n" for row in rows))
    return path


def test_an_alta_file_with_the_cosine_header_loads_reciprocal(brdf_values, tmp_path):
    """ALTA's INV_STERADIAN_COSINE_FACTOR is the BRDF times the view's cosine: read as such, the pairs agree."""
    stored = brdf_values.values * brdf_values.wo[:, 2:3]
    loaded = load_samples(write_alta(tmp_path / "cosine.dat", brdf_values.wi, brdf_values.wo, stored))
    assert loaded.provenance.quantity == "cosine-weighted-out"
    found = reciprocity(loaded)
    assert 0.9 <= found.as_read <= 1.1 and not found.header_contradicted
    np.testing.assert_allclose(loaded.values, brdf_values.values, rtol=1e-12)


#: A gonioreflectometer's positioning jitter, degrees (1σ, each angle): far above the 0.01° that pairs once had to
#: match to, well below the grid's 15° steps.
JITTER_DEGREES = 0.05


def jittered_pairs(seed=0):
    """:func:`isotropic_pairs` with every angle of both directions moved by a seeded N(0, JITTER_DEGREES²)."""
    rng = np.random.default_rng(seed)
    moved = []
    for w in isotropic_pairs():
        theta, phi = np.arccos(w[:, 2]), np.arctan2(w[:, 1], w[:, 0])
        theta, phi = (a + np.radians(rng.normal(0.0, JITTER_DEGREES, len(a))) for a in (theta, phi))
        moved.append(spherical_to_direction(np.abs(theta), phi))
    return moved


@pytest.mark.parametrize("quantity", ["brdf", "cosine-weighted-in", "cosine-weighted-out"])
def test_jittered_directions_pair_within_the_files_spacing(quantity):
    """Directions that miss each other by ~0.1° still pair: the tolerance follows the grid's spacing (15°, so
    the 0.5° cap), and the check names the quantity the values hold."""
    wi, wo = jittered_pairs()
    values = data_synth.synthesize("lafortune", TAPE_LIKE, wi, wo, noise=0.0, lobes=2).values
    found = reciprocity(Samples.from_arrays(wi, wo, values * stored_factor(quantity, wi, wo)))
    assert found is not None and found.pairs >= MIN_PAIRS
    assert found.tolerance_degrees == pytest.approx(0.5)  # the cap: half of 15° is more
    assert found.best == quantity
    # ~0.1° of jitter moves a lobe of exponent 300 by a few per cent at most, far inside the verdict's band.
    assert found.ratios[quantity] == pytest.approx(1.0, abs=0.05)


@pytest.fixture()
def mislabelled(tmp_path):
    """An ALTA file whose header says INV_STERADIAN_COSINE_FACTOR (f·cos θv) over BRDF values, jittered directions."""
    wi, wo = jittered_pairs(seed=1)
    values = data_synth.synthesize("lafortune", TAPE_LIKE, wi, wo, noise=0.0, lobes=2).values
    return write_alta(tmp_path / "mislabelled.dat", wi, wo, values)


def test_a_header_the_data_contradict_is_named_by_info(mislabelled, capsys):
    found = reciprocity(load_samples(mislabelled))
    assert found.header == "cosine-weighted-out" and found.header_contradicted and found.best == "brdf"
    assert main(["info", str(mislabelled)]) == 0
    out = capsys.readouterr().out
    assert "warning: the file's header says its values are cosine-weighted-out, but its" in out
    assert "read them with --quantity brdf" in out
    # Read as the data say, info still says the header is wrong (it is), and the values are reciprocal.
    assert main(["info", str(mislabelled), "--quantity", "brdf"]) == 0
    out = capsys.readouterr().out
    assert "the values as read are reciprocal" in out and "header says its values are cosine-weighted-out" in out


def test_a_header_the_data_contradict_is_named_by_the_fit(mislabelled):
    from brdffit import fit

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(load_samples(mislabelled), "lambert")
    said = [str(w.message) for w in caught if issubclass(w.category, FitWarning)]
    line = "the file's header says its values are cosine-weighted-out, but its"
    assert any(line in message and "--quantity brdf" in message for message in said)
    assert any(line in message for message in result.warnings)
    with pytest.warns(InputWarning, match="not as the header says"):
        as_brdf = load_samples(mislabelled, quantity="brdf")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)  # Lambert on a lobed material: other caveats
        right = fit(as_brdf, "lambert")
    assert not any("reciprocal" in message or "header" in message for message in right.warnings)


def test_the_real_tape_is_cosine_weighted_by_the_view():
    """The gray tape has no #PARAM_OUT line; its reciprocal pairs say its values are f·cos θv (issue 11: 0.61 as
    stored, 0.35 divided by cos θl, 1.06 divided by cos θv)."""
    stored = reciprocity(load_samples(TAPE))
    assert not stored.reciprocal and stored.best == "cosine-weighted-out"
    assert stored.ratios["brdf"] == pytest.approx(0.61, abs=0.02)
    assert stored.ratios["cosine-weighted-in"] == pytest.approx(0.35, abs=0.02)
    read_right = reciprocity(load_samples(TAPE, quantity="cosine-weighted-out"))
    assert 0.9 <= read_right.as_read <= 1.1 and read_right.reciprocal


def test_info_on_the_tape_names_the_quantity_and_what_was_dropped(capsys):
    assert main(["info", str(TAPE)]) == 0
    out = capsys.readouterr().out
    assert "read them with --quantity cosine-weighted-out" in out
    assert "dropped: 86 with the light or the viewer at or below the horizon" in out
    assert "values read as brdf (by default): taken as they are" in out
    assert main(["info", str(TAPE), "--quantity", "cosine-weighted-out"]) == 0
    out = capsys.readouterr().out
    assert "divided by cos θo (the view's cosine)" in out and "the values as read are reciprocal" in out


def test_too_few_pairs_say_nothing():
    wi, wo = data_synth.uniform_random(500, seed=1)
    assert reciprocity(data_synth.synthesize("lambert", {"rho_d": [0.5]}, wi, wo)) is None


def test_the_cosine_readings_are_the_cosines():
    """A pair (a → b) and (b → a) of a Lambertian surface stored times the light's cosine: ratio cos a / cos b."""
    a, b = math.radians(20.0), math.radians(60.0)
    wi = np.array([[math.sin(a), 0, math.cos(a)], [math.sin(b), 0, math.cos(b)]] * MIN_PAIRS)
    wo = np.array([[-math.sin(b), 0, math.cos(b)], [-math.sin(a), 0, math.cos(a)]] * MIN_PAIRS)
    stored = np.full((2 * MIN_PAIRS, 1), 0.1) * wi[:, 2:3]
    found = reciprocity(Samples.from_arrays(wi, wo, stored))
    assert found.pairs == MIN_PAIRS and found.ratios["brdf"] == pytest.approx(math.cos(a) / math.cos(b), rel=1e-12)
    assert found.ratios["cosine-weighted-in"] == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("path", [TAPE, SHARED_DATA / "alta" / "retro-gray-tape.dat"], ids=["examples", "shared-data"])
def test_the_real_tape_read_as_its_header_says_is_checked_within_its_spacing(path):
    """The tape's neighbouring measurements lie a median 0.92° apart (θv steps of ~3°, azimuths of ~15°, nearer
    towards the retro peak): its pairs match within half that, and say what the values are."""
    if not path.exists():
        pytest.skip(f"{path} is absent (reference data beside the project, not in it)")
    found = reciprocity(load_samples(path))
    assert found is not None and found.pairs >= 108  # the 0.01° grid found 108
    assert 0.4 <= found.tolerance_degrees <= 0.5
    assert found.best == "cosine-weighted-out" and not found.reciprocal


@pytest.mark.parametrize("general", [True, False])
def test_a_few_samples_pair_as_a_k_d_tree_pairs_them(monkeypatch, general):
    """Up to EVERY_PAIR_UP_TO samples the nearest points come from the whole distance matrix: the same pairs and the
    same tolerance as a k-d tree's, on a grid with many pairs (325 samples, cut to 200) and jittered by 0.1°."""
    from brdffit.data import reciprocity as module

    wi, wo = isotropic_pairs()
    rng = np.random.default_rng(4)
    jitter = [w + rng.normal(0.0, np.radians(0.1), w.shape) for w in (wi, wo)]
    wi, wo = (w[:200] / np.linalg.norm(w[:200], axis=1, keepdims=True) for w in jitter)
    samples = Samples.from_arrays(wi, wo, np.ones((200, 1)))
    few = module._paired(samples, general)
    monkeypatch.setattr(module, "EVERY_PAIR_UP_TO", 0)
    tree = module._paired(samples, general)
    assert len(few[0]) >= (3 if general else MIN_PAIRS)  # swapped directions: the lights lie at azimuth 0 alone
    np.testing.assert_array_equal(few[0], tree[0])
    np.testing.assert_array_equal(few[1], tree[1])
    assert few[2] == pytest.approx(tree[2], rel=1e-12)


def jittered_swaps(count: int, seed: int):
    """``count`` random direction pairs with ``θi < θo`` and each again with its directions swapped, jittered by ~0.05°:
    ~``count`` reciprocal pairs, spread over every ``cos θi − cos θo``."""
    rng = np.random.default_rng(seed)
    wi, wo = data_synth.uniform_random(count, seed=seed)
    wi, wo = np.where(wi[:, 2:] > wo[:, 2:], wi, wo), np.where(wi[:, 2:] > wo[:, 2:], wo, wi)
    wi, wo = np.concatenate([wi, wo]), np.concatenate([wo, wi])
    jitter = [w + rng.normal(0.0, np.radians(0.05), w.shape) for w in (wi, wo)]
    wi, wo = (w / np.linalg.norm(w, axis=1, keepdims=True) for w in jitter)
    above = (wi[:, 2] > 0.01) & (wo[:, 2] > 0.01)  # jitter took a few grazing ones below the horizon
    return Samples.from_arrays(wi[above], wo[above], np.ones((np.count_nonzero(above), 1)))


@pytest.mark.parametrize("general", [True, False])
def test_pairing_band_by_band_finds_what_one_tree_finds(monkeypatch, general):
    """A large file is paired band by band of cos θi − cos θo (BAND_SAMPLES a k-d tree): the same pairs and tolerance
    as one tree of every sample, on ~6,000 samples in 24 bands, their pairs straddling the bands' edges (no direction
    measured twice: equally near partners could be taken either way)."""
    from brdffit.data import reciprocity as module

    samples = jittered_swaps(3000, seed=5)
    whole = module._paired(samples, general)
    monkeypatch.setattr(module, "BAND_SAMPLES", 250)
    assert len(module._bands(module._cosine_difference(samples))) == 24
    banded = module._paired(samples, general)
    assert len(whole[0]) >= 2000
    np.testing.assert_array_equal(banded[0], whole[0])
    np.testing.assert_array_equal(banded[1], whole[1])
    assert banded[2] == pytest.approx(whole[2], rel=1e-12)  # the same distances, from trees over other points


@pytest.mark.parametrize("general", [True, False])
def test_a_large_file_is_paired_in_a_region_where_its_trees_find_what_trees_of_every_sample_find(monkeypatch, general):
    """Above REGION_ABOVE samples, the firsts asked lie in cells of (cos θi + cos θo, wi · wo), which a sample and its
    partner share to √2 × the tolerance, and the trees hold the samples in those cells or beside them alone: for the
    same firsts and the same spacing samples, trees of every sample find the same partners and the same tolerance,
    pairs straddling a cell's edge included; the spacing samples, 2 × SPACING_REACH inside the region, have the
    same neighbours. Made: ~6,000 jittered swapped pairs and 1,500 samples within ~1° of others (neighbours within
    the reach), the region of 600 firsts a fraction of the cells."""
    from brdffit.data import reciprocity as module

    pairs = jittered_swaps(3000, seed=5)
    rng = np.random.default_rng(7)
    near = [w[:1500] + rng.normal(0.0, 0.008, (1500, 3)) for w in (pairs.wi, pairs.wo)]
    near = [w / np.linalg.norm(w, axis=1, keepdims=True) for w in near]
    wi, wo = np.vstack([pairs.wi, near[0]]), np.vstack([pairs.wo, near[1]])
    samples = Samples.from_arrays(wi, wo, np.ones((len(wi), 1)))
    monkeypatch.setattr(module, "REGION_ABOVE", 0)
    monkeypatch.setattr(module, "MAX_QUERIES", 600)
    monkeypatch.setattr(module, "SPACING_SAMPLE", 64)
    region = module._region(samples, module._firsts(samples))
    assert region is not None and len(region.kept) < 0.6 * samples.n_samples
    in_region = module._paired(samples, general)
    everywhere = module._Region(region.queried, np.arange(samples.n_samples), region.inner)
    monkeypatch.setattr(module, "_region", lambda samples, firsts: everywhere)
    whole = module._paired(samples, general)
    assert len(whole[0]) >= 300 and np.any(~region.queried[whole[1]])  # some partners lie beside the region
    np.testing.assert_array_equal(in_region[0], whole[0])
    np.testing.assert_array_equal(in_region[1], whole[1])
    assert in_region[2] == pytest.approx(whole[2], rel=1e-12)
    inner = module._points_at(samples, region.inner, general)
    trees = [module._tree(module._points_at(samples, kept, general), False) for kept in (region.kept, everywhere.kept)]
    found = [module._nearest(inner, tree, module.SPACING_NEIGHBOURS) for tree in trees]
    assert np.isfinite(found[1][:, 1]).mean() > 0.3  # many have a neighbour within the reach besides themselves
    np.testing.assert_array_equal(found[0], found[1])


def test_a_large_file_without_a_region_big_enough_asks_every_cell(monkeypatch):
    """Where the cells hold fewer firsts than MAX_QUERIES, or too few samples lie inside them to measure the spacing
    (SPACING_SAMPLE), there is no region (None), and the pairing asks samples from every cell, as a small file's."""
    from brdffit.data import reciprocity as module

    samples = jittered_swaps(1000, seed=8)
    plain = module._paired(samples, True)
    monkeypatch.setattr(module, "REGION_ABOVE", 0)
    for name, value in (("MAX_QUERIES", samples.n_samples), ("SPACING_SAMPLE", samples.n_samples)):
        with monkeypatch.context() as patched:
            patched.setattr(module, name, value)
            assert module._region(samples, module._firsts(samples)) is None
            paired = module._paired(samples, True)
            np.testing.assert_array_equal(paired[0], plain[0])
            np.testing.assert_array_equal(paired[1], plain[1])
            assert paired[2] == plain[2]


def test_bands_hold_every_sample_once_where_differences_repeat(monkeypatch):
    """A grid's cos θi − cos θo repeats, so quantiles can coincide: no band is empty, every sample is in one."""
    from brdffit.data import reciprocity as module

    monkeypatch.setattr(module, "BAND_SAMPLES", 10)
    difference = np.repeat([-0.5, 0.0, 0.0, 0.0, 0.25], 20)
    bands = module._bands(difference)
    assert all(len(band) for band in bands)
    np.testing.assert_array_equal(np.sort(np.concatenate(bands)), np.arange(len(difference)))


def test_the_spacing_needs_no_neighbour_beyond_its_reach():
    """The spacing's neighbours are looked up within SPACING_REACH alone: any distance beyond it, written as inf, gives
    the same tolerance, also where the median straddles the reach (4,096 rows of 9 distances around it, some the
    sample itself again, some rows all itself)."""
    from brdffit.data import reciprocity as module

    rng = np.random.default_rng(6)
    for scale in (0.25, 0.5, 1.0, 1.5, 3.0):
        nearest = np.sort(rng.uniform(0.0, 2 * scale * module.SPACING_REACH, (4096, 9)), axis=1)
        nearest[:300, :2] = 0.0  # measured twice
        nearest[300:310] = 0.0  # nothing but itself
        unseen = np.where(nearest > module.SPACING_REACH, np.inf, nearest)
        assert module.tolerance(unseen) == module.tolerance(nearest)
    # The median's two middle values straddle the reach, the lower far below it: their mean, just over half the reach,
    # is still beyond the spacing whose SPACING_FRACTION is the cap (MAX_TOLERANCE / SPACING_FRACTION), by 11 %.
    rows = np.full((4096, 9), 1.01 * module.SPACING_REACH)
    rows[:2048, 0] = 0.1 * module.SPACING_REACH
    rows = np.sort(rows, axis=1)
    assert module.tolerance(rows) == module.MAX_TOLERANCE
    assert module.tolerance(np.where(rows > module.SPACING_REACH, np.inf, rows)) == module.MAX_TOLERANCE


def test_the_check_ahead_says_its_warnings_at_the_callers_line(monkeypatch):
    """A warning the check meets in its thread (a stored pairing it cannot use) is issued when the caller asks for the
    result, in the caller's thread, naming the caller's line: issued in the thread it would name threading.py's."""
    from brdffit.data import reciprocity as module
    from brdffit.errors import warn

    def checked(samples):
        warn(InputWarning("the stored pairs are not used"))
        return None

    monkeypatch.setattr(module, "reciprocity", checked)
    ahead = ReciprocityAhead(None)  # type: ignore[arg-type]
    with pytest.warns(InputWarning, match="stored pairs") as said:
        assert ahead.result(timeout=60) is None
    assert [warning.filename for warning in said] == [__file__]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ahead.result(timeout=60)  # said once


def test_the_check_ahead_hands_its_memory_back_before_its_result(monkeypatch):
    """The thread's freed pages go back to the system before the caller, waiting for the result, goes on to its
    solve (a MERL-size fit's peak: 575 MB, 615–620 MB without)."""
    from brdffit.data import reciprocity as module

    done = []
    monkeypatch.setattr(module, "reciprocity", lambda samples: done.append("checked"))
    monkeypatch.setattr(module, "return_freed_memory", lambda: (time.sleep(0.2), done.append("trimmed")))
    ReciprocityAhead(None).result(timeout=60)  # type: ignore[arg-type]
    assert done == ["checked", "trimmed"]


def test_fewer_firsts_than_pairs_say_nothing_at_once(monkeypatch):
    """A pair's first sample has θi < θo: under MIN_PAIRS of those (a capture's texel seen from above: its camera
    nearer the normal than almost every light) there cannot be MIN_PAIRS pairs, so nothing is paired."""
    from brdffit.data import reciprocity as module

    monkeypatch.setattr(module, "_pairs", lambda *args, **kwargs: pytest.fail("paired"))
    count = 100
    azimuth = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
    theta_i = np.where(np.arange(count) < MIN_PAIRS - 1, np.radians(5.0), np.radians(40.0))
    wi = spherical_to_direction(theta_i, azimuth)
    wo = spherical_to_direction(np.full(count, np.radians(10.0)), np.zeros(count))
    assert reciprocity(Samples.from_arrays(wi, wo, np.ones(count))) is None
