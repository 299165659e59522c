"""Progress bars of long work (``fit_batch``, ``compare``, ``brdffit basis``): tqdm's, on stderr."""

import importlib
import importlib.util
import sys


def progress_bar(total: int, unit: str, enabled: bool | None, **options):
    """A tqdm bar of ``total`` ``unit``s on stderr, gone once closed (``leave=False``); ``options``: tqdm's others.

    ``enabled`` None shows it only where it can be drawn: on a terminal (tqdm's ``disable=None``), or in a Jupyter
    kernel that has ipywidgets, as tqdm's widget (``tqdm.auto``). Without ipywidgets a notebook gets no bar rather than
    ``tqdm.auto``'s warning ("IProgress not found"), printed in every notebook that fits, before a text bar that a
    kernel's stderr (not a terminal) hides all the same.
    """
    widget = "ipykernel" in sys.modules and importlib.util.find_spec("ipywidgets") is not None
    bar = importlib.import_module("tqdm.auto" if widget else "tqdm").tqdm
    return bar(total=total, unit=unit, disable=None if enabled is None else not enabled, leave=False, **options)
