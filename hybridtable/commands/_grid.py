"""The axes of the ``margins`` grid: their syntax (``a,b,c`` or ``start:stop:count``),
their plausible ranges and their defaults."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["DEFAULT_DELAYS", "DEFAULT_TABLES", "MAX_GRID_VALUES", "parse_list", "default_delays"]

#: Sensor delays [s] and table response frequencies [Hz] of the default grid.
DEFAULT_DELAYS = "0:0.02:41"
DEFAULT_TABLES = "5:200:40"

#: Most values of one axis of the margins grid.
MAX_GRID_VALUES = 1000


def parse_list(text: str, name: str, limit: str | None = None) -> np.ndarray:
    """``"a,b,c"`` or ``"start:stop:count"`` (``count`` evenly spaced values,
    both ends included, at most :data:`MAX_GRID_VALUES`) as a float array,
    each value inside the plausible range of the quantity ``limit``
    (:data:`hybridtable.limits.LIMITS`) if given.

    Raises
    ------
    CommandError
        On malformed input (one line, names the option).
    """
    from hybridtable.errors import CommandError

    text = text.strip()
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop = float(parts[0]), float(parts[1])
            count = int(parts[2])
            if count < 1 or not (math.isfinite(start) and math.isfinite(stop)):
                raise ValueError
            values = np.linspace(start, stop, count)
        else:
            items = [v for v in text.split(",") if v.strip() != ""]
            values = np.array([float(v) for v in items])
            if any(
                math.isinf(x) and "inf" not in v.lower() for x, v in zip(values, items, strict=True)
            ):
                raise ValueError  # a literal too large for a float, not "inf"
    except ValueError:
        raise CommandError(
            f"{name}: expected comma-separated numbers or start:stop:count, got {text!r}"
        ) from None
    if values.size == 0 or np.isnan(values).any():
        raise CommandError(f"{name}: expected at least one number, got {text!r}")
    if values.size > MAX_GRID_VALUES:
        raise CommandError(f"{name}: {values.size} values, at most {MAX_GRID_VALUES}")
    if limit is not None:
        from hybridtable.limits import LIMITS

        bounds = LIMITS[limit]
        for v in values:
            if not bounds.contains(float(v)):
                unit = "" if bounds.unit == "1" else f" {bounds.unit}"
                raise CommandError(
                    f"{name}: {v:g}{unit} is outside its plausible range {bounds.words()}"
                )
    return values


def default_delays(sample_rate_hz: float | None) -> np.ndarray:
    """0-20 ms: 41 values, or whole sample periods up to 20 ms when sampled
    (at most 81 values)."""
    if sample_rate_hz is None:
        return np.linspace(0.0, 0.02, 41)
    h = 1.0 / sample_rate_hz
    n = int(math.floor(0.02 / h + 1e-9))
    samples = np.unique(np.round(np.linspace(0, n, min(n + 1, 81))).astype(int))
    return samples * h
