"""A small library of MERL tables made from brdffit's own models, and bases learned from it.

Eight Ward tables with seeded parameters (writing one takes ~0.3 s): enough vectors (24) for a basis of a few
components, little enough for the suite. ``linear_library`` is two fixed grey tables and their linear mixtures:
in the ``none`` mapping it has rank 2 (every channel of every table is a mixture of the same two), so its basis
is exact and a mixture outside it is reproduced exactly.
"""

import numpy as np
import pytest

from brdffit.data.merl import HORIZON, N_BINS, bin_directions, write_merl_table
from brdffit.datadriven.basis import save_basis
from brdffit.datadriven.build import build_basis
from brdffit.physics.evaluate import evaluate


def ward_table(params: dict) -> np.ndarray:
    """The Ward model's MERL table (N_BINS, 3), 0 below the horizon."""
    wi, wo = bin_directions()
    above = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    values = np.zeros((N_BINS, 3))
    values[above] = evaluate("ward", params, wi[above], wo[above])
    return values


def ward_params(rng) -> dict:
    return {
        "rho_d": list(rng.uniform(0.05, 0.5, 3)),
        "rho_s": list(rng.uniform(0.02, 0.3, 3)),
        "alpha": float(rng.uniform(0.08, 0.4)),
    }


@pytest.fixture(scope="session")
def library(tmp_path_factory):
    """Paths of 8 Ward tables (the first 7 build the basis, the last is held out) and their parameters."""
    folder = tmp_path_factory.mktemp("library")
    rng = np.random.default_rng(7)
    paths, params = [], []
    for index in range(8):
        one = ward_params(rng)
        path = folder / f"ward-{index}.binary"
        write_merl_table(ward_table(one), path)
        paths.append(path)
        params.append(one)
    return paths, params


@pytest.fixture(scope="session")
def basis_file(library, tmp_path_factory):
    """A 6-component log-relative basis of the library's first 7 tables (21 vectors)."""
    path = tmp_path_factory.mktemp("basis") / "basis.npz"
    save_basis(build_basis(library[0][:7], components=6), path)
    return path


@pytest.fixture(scope="session")
def linear_library(tmp_path_factory):
    """Two grey Ward tables ``A``, ``B`` and 5 files of ``a·A + b·B`` (seeded a, b); returns the paths, A and B."""
    folder = tmp_path_factory.mktemp("linear")
    rng = np.random.default_rng(11)
    first, second = (np.repeat(ward_table(ward_params(rng))[:, :1], 3, axis=1) for _ in range(2))  # grey
    paths = []
    for index in range(5):
        a, b = rng.uniform(0.2, 1.0, 2)
        path = folder / f"mix-{index}.binary"
        write_merl_table(a * first + b * second, path)
        paths.append(path)
    return paths, first, second
