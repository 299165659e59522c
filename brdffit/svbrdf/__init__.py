"""Spatially varying materials: a capture's photographs (``capture.json``, ``capture.py``) fitted texel by texel
into maps of a model's parameters (``texel_fits.py``, ``maps.py``), and the images those maps predict
(``relight.py``).

::

    import brdffit.svbrdf as svbrdf

    maps = svbrdf.fit("capture/", model="ward", output="maps/")
    image = svbrdf.render(maps, light_mm=[0, 0, 300], camera_mm=[0, 0, 400])
"""

from .capture import Capture, Shot, read_capture
from .maps import Maps, read_maps, write_maps
from .relight import relight as render
from .texel_fits import fit_capture as fit

__all__ = ["Capture", "Maps", "Shot", "fit", "read_capture", "read_maps", "render", "write_maps"]
