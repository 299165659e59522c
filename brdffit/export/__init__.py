"""Fitted models in the forms renderers read (``mitsuba.py``, ``gltf.py``, ``merl.py``). Imports every layer below it.

The package is also the function ``brdffit.export(result, to, path, format=None, samples=None, *, bin_centres=False)``
(``targets.export``): its module object is callable (a module's ``__class__`` may be a subclass of ``ModuleType``,
Python 3.5+), so that ``brdffit.export(...)`` and ``brdffit.export.mitsuba`` both mean what they say.
"""

import sys
import types


class _CallableExport(types.ModuleType):
    def __call__(self, result, to: str, path, format: str | None = None, samples=None, *, bin_centres: bool = False):
        """Write ``result`` for the renderer ``to`` (``targets.export``: ``"mitsuba"``, ``"gltf"``, ``"merl"``) to
        ``path``, a file named with one of the target's suffixes (``targets.check_suffix``); returns the lines a
        user should read (whether it is exact, how far it lies, notes)."""
        from .targets import check_suffix, export

        check_suffix(to, path)
        return export(result, to, path, format, samples, bin_centres=bin_centres)


sys.modules[__name__].__class__ = _CallableExport

#: The modules of the package, one target or step each (the reference lists them).
__all__ = [
    "approximate",
    "at_data",
    "gltf",
    "gltf_material",
    "gltf_preview",
    "merl",
    "mitsuba",
    "mitsuba_eval",
    "mitsuba_render",
    "targets",
]
