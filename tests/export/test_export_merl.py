"""A fitted model tabulated as a MERL table: the bins hold the model's values, and only RGB models fit the format."""

import numpy as np
import pytest

from brdffit import BrdfInputError, evaluate
from brdffit.data.merl import HORIZON, N_BINS, bin_directions, read_merl
from brdffit.export.merl import write_merl

WARD = {"rho_d": [0.1, 0.2, 0.3], "rho_s": [0.05, 0.04, 0.03], "alpha": 0.2}


def test_the_table_holds_the_model_at_every_bin_and_reads_back(tmp_path):
    path = tmp_path / "ward.binary"
    write_merl("ward", WARD, path)
    samples = read_merl(path)
    wi, wo = bin_directions()
    above = (wi[:, 2] > HORIZON) & (wo[:, 2] > HORIZON)
    assert samples.n_samples == int(above.sum())
    # The reader normalises the bin directions (length 1 ± 1 ulp) and the file stores value/scale: a few ulp.
    np.testing.assert_allclose(samples.values, evaluate("ward", WARD, samples.wi, samples.wo), rtol=1e-12)
    assert path.stat().st_size == 12 + 3 * N_BINS * 8


def test_a_model_of_two_channels_is_refused_and_one_is_written_grey(tmp_path):
    path = tmp_path / "two.binary"
    with pytest.raises(BrdfInputError) as error:
        write_merl("lambert", {"rho_d": [0.5, 0.4]}, path)
    message = str(error.value)
    assert message.startswith(str(path)) and "2 channels" in message and "3 (r, g, b), or grey from 1" in message
    assert not path.exists()
    notes = write_merl("lambert", {"rho_d": [0.5]}, tmp_path / "grey.binary")
    assert notes == ["one channel: written as grey, the same values in r, g and b"]
    assert (tmp_path / "grey.binary").exists()
