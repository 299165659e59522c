"""Synthetic captures the svbrdf tests share (``brdffit/data_synth/capture.py``), made once per session."""

import pytest

from brdffit.data_synth.capture import synth_capture


@pytest.fixture(scope="session")
def ward_capture(tmp_path_factory):
    """A 16 × 16-texel Ward capture, 24 photographs with 1% multiplicative noise, and its true maps."""
    folder = tmp_path_factory.mktemp("ward-capture")
    truth = synth_capture(folder, "ward", shape=(16, 16), n_images=24, noise=0.01, seed=1)
    return folder, truth


@pytest.fixture(scope="session")
def noiseless_capture(tmp_path_factory):
    """A 6 × 8-texel Ward capture without noise, as OpenEXR images, and its true maps."""
    folder = tmp_path_factory.mktemp("noiseless-capture")
    truth = synth_capture(folder, "ward", shape=(6, 8), n_images=12, noise=0.0, seed=0, image_format="exr")
    return folder, truth
