"""Cross-validation folds: whole light directions held out where there are enough of them, random otherwise."""

import numpy as np
import pytest

from brdffit import BrdfInputError, data_synth
from brdffit.fitting.comparison.folds import MIN_GROUPS, make_folds

LAMBERT = {"rho_d": [0.3]}


def samples_of(wi, wo):
    return data_synth.synthesize("lambert", LAMBERT, wi, wo)


def test_gonioreflectometer_data_hold_out_whole_light_directions():
    samples = samples_of(*data_synth.hemisphere_grid(8, 9, 12))  # 8 light directions × 108 views
    folds = make_folds(samples, 5, seed=3)
    assert folds.kind == "light-direction" and folds.count == 5 and folds.groups == 8
    _, light = samples.light_directions()
    for group in range(8):  # every light direction lies in one fold only
        assert len(np.unique(folds.fold[light == group])) == 1
    sizes = np.bincount(folds.fold, minlength=5)
    assert sizes.sum() == samples.n_samples and np.all(sizes > 0)
    assert sizes.max() <= 2 * 108  # 8 equal groups over 5 folds: one or two groups each
    np.testing.assert_array_equal(folds.fold, make_folds(samples, 5, seed=3).fold)  # seeded
    assert any(not np.array_equal(folds.fold, make_folds(samples, 5, seed=s).fold) for s in range(4, 10))


def test_few_light_directions_or_random_data_give_random_folds():
    few = samples_of(*data_synth.hemisphere_grid(MIN_GROUPS - 1, 9, 12))
    random = samples_of(*data_synth.uniform_random(503, seed=1))  # every sample its own light direction
    for samples in (few, random):
        folds = make_folds(samples, 4, seed=0)
        assert folds.kind == "random"
        sizes = np.bincount(folds.fold, minlength=4)
        assert sizes.max() - sizes.min() <= 1 and sizes.sum() == samples.n_samples
        assert all(np.sum(folds.held_out(k)) == sizes[k] for k in range(4))


def test_folds_that_cannot_be_filled_are_refused():
    samples = samples_of(*data_synth.hemisphere_grid(6, 9, 12))
    with pytest.raises(BrdfInputError, match=r"6 light directions cannot fill 7 folds .*; give folds ≤ 6$"):
        make_folds(samples, 7)
    with pytest.raises(BrdfInputError, match=r"^folds=1 is not allowed; give a whole number ≥ 2$"):
        make_folds(samples, 1)
    tiny = samples_of(*data_synth.uniform_random(3, seed=1))
    with pytest.raises(BrdfInputError, match="3 samples cannot fill 5 folds"):
        make_folds(tiny, 5)
