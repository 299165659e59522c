"""Checks of option values shared by the API and the command line, with the one-line messages users see."""

import numpy as np

from .errors import BrdfInputError


def whole_number(option: str, value, minimum: int = 1, maximum: int | None = None) -> int:
    """``value`` as an int if it is a whole number in ``[minimum, maximum]``, else a one-line error naming ``option``.

    ``maximum`` None means no upper bound.
    """
    allowed = f"from {minimum} to {maximum}" if maximum is not None else f"≥ {minimum}"
    if (
        isinstance(value, bool)
        or not isinstance(value, int | np.integer)
        or value < minimum
        or (maximum is not None and value > maximum)
    ):
        raise BrdfInputError(f"{option} {value!r} is not allowed; give a whole number {allowed}")
    return int(value)
