"""brdffit: differentiable BRDF fitting for measured reflectance data.

The public API (SPEC section 6)::

    samples = brdffit.load_samples("samples.csv")
    result = brdffit.fit(samples, model="ward", loss="log")
    result.params, result.to_json(), result.predict(wi, wo)
    values = brdffit.evaluate("cook-torrance", params, wi, wo, fresnel="schlick")

Importing brdffit switches JAX to 64-bit floats (``jax_enable_x64``): every
computation is float64 unless asked otherwise.
"""

import jax

jax.config.update("jax_enable_x64", True)

from ._version import __version__ as __version__  # noqa: E402
from .batch import fit_batch as fit_batch  # noqa: E402
from .errors import BrdfInputError as BrdfInputError  # noqa: E402
from .evaluate import evaluate as evaluate  # noqa: E402
from .fit import fit as fit  # noqa: E402
from .losses import LOSSES as LOSSES  # noqa: E402
from .models import MODELS as MODELS  # noqa: E402
from .models import Model as Model  # noqa: E402
from .models import get_model as get_model  # noqa: E402
from .results import FitResult as FitResult  # noqa: E402
from .results import load_result as load_result  # noqa: E402
from .samples import Samples as Samples  # noqa: E402
from .samples import load_samples as load_samples  # noqa: E402
from .samples import save_samples as save_samples  # noqa: E402
