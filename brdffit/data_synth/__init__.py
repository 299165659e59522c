"""Synthetic gonioreflectometer data for brdffit: geometries, noise and sample sets.

::

    wi, wo = data_synth.hemisphere_grid(8, 36, 36)
    samples = data_synth.synthesize("ward", params, wi, wo, noise=0.01, seed=1)
    brdffit.save_samples(samples, "ward.csv")
"""

from brdffit.data_synth.geometries import GEOMETRIES as GEOMETRIES
from brdffit.data_synth.geometries import hemisphere_grid as hemisphere_grid
from brdffit.data_synth.geometries import in_plane as in_plane
from brdffit.data_synth.geometries import near_specular as near_specular
from brdffit.data_synth.geometries import uniform_random as uniform_random
from brdffit.data_synth.noise import NOISE_KINDS as NOISE_KINDS
from brdffit.data_synth.noise import add_noise as add_noise
from brdffit.data_synth.synthesize import synthesize as synthesize
