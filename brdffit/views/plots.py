"""The figures of a fit, under one name: ``brdffit.plots.slices(results, samples)``, … Each returns a matplotlib
:class:`~matplotlib.figure.Figure` (built without pyplot) and, given ``path=``, also writes it atomically.

=============  ==============================================================================================
``slices``     data and fits against the signed viewer zenith, plane of incidence and perpendicular plane
``polar``      the same slices as polar plots (BRDF Explorer's view)
``residuals``  where one fit misses: its residuals per light direction, or over (θh, θd) for dense data
``sphere``     lit spheres of the fits, beside the sphere of the measured values when the data are dense
``corner``     the posterior of a fit with an uncertainty estimate (every pair of parameters)
=============  ==============================================================================================

:data:`KINDS` names the first four as ``brdffit plot --kind`` takes them.
"""

from collections.abc import Callable
from typing import Any

from ..errors import needs

needs("matplotlib", "plots", "brdffit's figures")  # before the figure modules, which import it: one line if absent

from .corner import corner_plot as corner  # noqa: E402
from .polar import polar  # noqa: E402
from .residuals import residuals  # noqa: E402
from .slices import slices  # noqa: E402
from .sphere import sphere  # noqa: E402

#: The figures ``brdffit plot --kind`` draws from result files and samples, in the order ``--kind all`` writes them.
KINDS: dict[str, Callable[..., Any]] = {"slices": slices, "polar": polar, "residuals": residuals, "sphere": sphere}

__all__ = ["KINDS", "corner", "polar", "residuals", "slices", "sphere"]
