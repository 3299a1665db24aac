"""Validation helpers shared by the parameter dataclasses.

Every check raises :class:`ParameterError` naming the offending field, so a user
sees ``sensor_delay_s must be >= 0 (got -0.001)`` rather than a traceback from
deep inside Drake.
"""

from __future__ import annotations

import math
import numbers

from hybridtable.errors import ParameterError

__all__ = [
    "ParameterError",
    "check_finite",
    "check_positive",
    "check_nonnegative",
    "check_positive_or_inf",
    "check_choice",
    "check_seed",
]


def check_finite(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise if it is not a finite number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number (got {value!r})") from None
    if not math.isfinite(x):
        raise ParameterError(f"{name} must be finite (got {value!r})")
    return x


def check_positive(name: str, value: float) -> float:
    """Return ``value`` if it is a finite number > 0."""
    x = check_finite(name, value)
    if x <= 0.0:
        raise ParameterError(f"{name} must be > 0 (got {value!r})")
    return x


def check_nonnegative(name: str, value: float) -> float:
    """Return ``value`` if it is a finite number >= 0."""
    x = check_finite(name, value)
    if x < 0.0:
        raise ParameterError(f"{name} must be >= 0 (got {value!r})")
    return x


def check_positive_or_inf(name: str, value: float) -> float:
    """Return ``value`` if it is > 0; ``math.inf`` is allowed (an ideal element)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number (got {value!r})") from None
    if math.isnan(x) or x <= 0.0:
        raise ParameterError(f"{name} must be > 0 or inf (got {value!r})")
    return x


def check_choice(name: str, value: str, choices: tuple[str, ...], any_case: bool = False) -> str:
    """Return ``value`` if it is one of ``choices``; with ``any_case``, the one
    choice it spells in other letter case (``"sdmdc"`` -> ``"SDMDC"``) too."""
    if value in choices:
        return value
    if any_case and isinstance(value, str):
        same = [c for c in choices if c.casefold() == value.casefold()]
        if len(same) == 1:
            return same[0]
    raise ParameterError(f"{name} must be one of {', '.join(choices)} (got {value!r})")


def check_seed(name: str, value: object) -> int:
    """Return a noise seed as an ``int``, or raise unless it is a whole number
    >= 0 (numpy's integers too; not a bool)."""
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
        or int(value) != value
        or value < 0
    ):
        raise ParameterError(f"{name} must be a whole number >= 0 (got {value!r})")
    return int(value)
