"""Checks of argument values shared by every layer, with the one-line errors users see.

Each check names the argument as the library's callers write it (``n_starts``); the command line spells
the same message with its flag (``--starts``), see :mod:`brdffit.errors`.
"""

import numbers
from collections.abc import Iterable

from .errors import not_a_choice, not_allowed


def whole_number(name: str, value, minimum: int = 1, maximum: int | None = None) -> int:
    """``value`` as an int if it is a whole number in ``[minimum, maximum]`` (a float such as ``2000.0`` counts),
    else a one-line error naming the argument ``name``; ``maximum`` None means no upper bound."""
    allowed = f"from {minimum} to {maximum}" if maximum is not None else f"≥ {minimum}"
    whole = not isinstance(value, bool) and (
        isinstance(value, numbers.Integral) or (isinstance(value, float) and value.is_integer())
    )
    if not whole or value < minimum or (maximum is not None and value > maximum):
        raise not_allowed(name, value, f"give a whole number {allowed}")
    return int(value)


def choice(name: str, value, choices: Iterable[str], verb: str = "is not allowed"):
    """``value`` if it is one of ``choices``, else ``name='x' is not allowed; choose one of: …``."""
    choices = tuple(choices)
    if not isinstance(value, str) or value not in choices:
        raise not_a_choice(name, value, choices, verb)
    return value


#: How a yes-or-no option is written in a spec or on the command line (``anisotropic=true``), any case.
BOOLEAN_WORDS = {"true": True, "false": False}


def boolean(name: str, value) -> bool:
    """``value`` as a bool: True or False, or the words ``true`` and ``false`` (any case) as a spec or a flag
    writes them; anything else is ``name='yes' is not allowed; give true or false``."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.lower() in BOOLEAN_WORDS:
        return BOOLEAN_WORDS[value.lower()]
    raise not_allowed(name, value, "give true or false")


def positive_number(name: str, value) -> float:
    """``value`` as a float if it is a finite number above 0, else a one-line error naming the argument ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < float(value) < float("inf"):
        raise not_allowed(name, value, "give a finite number above 0")
    return float(value)


def angle_up_to_90(name: str, value: float) -> float:
    """An angle in degrees in (0, 90]: a zenith limit, a spread about a direction."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value <= 90:
        raise not_allowed(name, value, "give degrees in (0, 90]")
    return value


def max_theta(value: float | None) -> float | None:
    """A zenith limit in degrees, in (0, 90] (None: no limit)."""
    return None if value is None else angle_up_to_90("max_theta", value)
