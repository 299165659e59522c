"""Stored reciprocal pairs (``brdffit/data/stored_pairs.py``): a large file's pairs are kept in the cache's folder,
read back by a later process instead of pairing again, and never trusted when they are not this cache's own or not
of these samples. (Here "large" is lowered to 100 samples: the pairs of a real MERL table take 0.7 s to find.)"""

import io

import numpy as np
import pytest

from brdffit import data_synth
from brdffit._programs import cache, signing
from brdffit.data import reciprocity, stored_pairs
from brdffit.errors import InputWarning
from brdffit.physics.geometry import spherical_to_direction

PARAMS = {"rho_d": [0.3], "rho_s": [0.1], "alpha": 0.3}


def grid_samples():
    """In-plane light and view zeniths on one grid, both azimuths: every sample's swapped partner is measured."""
    zeniths = np.radians(np.arange(5.0, 80.0, 5.0))
    theta_i, theta_o, phi_o = (grid.ravel() for grid in np.meshgrid(zeniths, zeniths, np.radians([0.0, 180.0])))
    wi = spherical_to_direction(theta_i, np.zeros_like(theta_i))
    wo = spherical_to_direction(theta_o, phi_o)
    return data_synth.synthesize("ward", PARAMS, np.asarray(wi), np.asarray(wo))


@pytest.fixture
def stored(tmp_path, monkeypatch):
    """A cache of its own, pairings of 100 samples or more stored, none kept in memory; the folder of programs."""
    monkeypatch.setattr(cache, "_enabled", tmp_path)
    monkeypatch.setattr(reciprocity, "STORED_FROM", 100)
    monkeypatch.setattr(reciprocity, "_kept", type(reciprocity._kept)())
    return tmp_path / "programs"


def later_process(monkeypatch):
    monkeypatch.setattr(reciprocity, "_kept", type(reciprocity._kept)())


def pairs_files(folder):
    return sorted(folder.glob(f"*{stored_pairs.SUFFIX}"))


def test_pairs_are_stored_once_and_read_back_without_pairing(stored, monkeypatch):
    samples = grid_samples()
    found = reciprocity.reciprocity(samples)
    assert found is not None and found.pairs >= reciprocity.MIN_PAIRS
    paths = pairs_files(stored)  # one a kind of pairing tried: swapped directions, and (too few) isotropic
    assert len(paths) == 2 and found.kind.startswith("isotropic")
    later_process(monkeypatch)
    monkeypatch.setattr(reciprocity, "_paired", lambda *args: pytest.fail("paired again"))
    assert reciprocity.reciprocity(samples) == found
    assert pairs_files(stored) == paths


def test_small_files_and_a_cache_that_is_off_store_nothing(stored, monkeypatch):
    samples = grid_samples()
    monkeypatch.setattr(reciprocity, "STORED_FROM", len(samples.wi) + 1)
    reciprocity.reciprocity(samples)
    assert pairs_files(stored) == []
    monkeypatch.setattr(reciprocity, "STORED_FROM", 100)
    monkeypatch.setattr(cache, "_enabled", None)
    later_process(monkeypatch)
    reciprocity.reciprocity(samples)
    assert not stored.exists()


def _signed_body(stored_folder, path, first, second, within=0.001):
    body = io.BytesIO()
    np.savez(body, first=np.asarray(first, np.int64), second=np.asarray(second, np.int64), within=within)
    content = body.getvalue()
    key = (stored_folder / signing.KEY_FILE).read_bytes()
    return signing.signed(key, path.stem, content) + b"\n" + content


@pytest.mark.parametrize("fault", ["flipped bytes", "other samples' indices", "unsigned"])
def test_pairs_that_are_not_this_caches_own_or_not_of_these_samples_are_found_again(stored, monkeypatch, fault):
    """A planted or changed file would make the check say what the file does not: each is one warning, the file
    removed, the pairs found again and the answer unchanged."""
    samples = grid_samples()
    found = reciprocity.reciprocity(samples)
    written = {}
    for path in pairs_files(stored):
        content = bytearray(path.read_bytes())
        if fault == "flipped bytes":
            content[-20] ^= 0xFF
        elif fault == "other samples' indices":  # signed with the key (one that leaked), indices beyond the samples
            content = bytearray(_signed_body(stored, path, [0, 1], [len(samples.wi), len(samples.wi) + 5]))
        else:
            content = content.split(b"\n", 1)[1]
        path.write_bytes(bytes(content))
        written[path] = bytes(content)
    later_process(monkeypatch)
    reason = "outside the" if fault == "other samples' indices" else "not signed by this cache"
    with pytest.warns(InputWarning, match=rf"the stored pairs .* are not used \(.*{reason}"):
        assert reciprocity.reciprocity(samples) == found
    for path, content in written.items():  # stored again, from the pairs found again
        assert path.read_bytes() != content
