"""The distributions a Monte Carlo campaign draws its inputs from.

``uniform`` on ``[low, high]``; ``log_uniform`` (uniform in ``ln x`` on
``[low, high]``, ``low > 0``: a stiffness or a frequency known to a factor);
``normal`` with ``mean`` and ``std``, optionally truncated to ``[low, high]``
(drawn by the inverse CDF, so a truncated draw costs one uniform number);
``choice`` among a user's ``values``, optionally with ``weights``.

A draw takes a :class:`numpy.random.Generator`; the campaign seeds one per
Monte Carlo sample from the spec's seed and the sample's index, so a draw does
not depend on where or in what order it runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridtable.errors import ParameterError

__all__ = ["DISTRIBUTIONS", "Distribution", "parse_distribution"]

#: Distribution name -> its keys (required, optional).
DISTRIBUTIONS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "uniform": (("low", "high"), ()),
    "log_uniform": (("low", "high"), ()),
    "normal": (("mean", "std"), ("low", "high")),
    "choice": (("values",), ("weights",)),
}


@dataclass(frozen=True)
class Distribution:
    """One input's distribution (see the module docstring).

    Attributes
    ----------
    kind : str
        A key of :data:`DISTRIBUTIONS`.
    low, high : float or None
        Bounds (uniform, log_uniform; optional truncation of normal).
    mean, std : float or None
        Normal's mean and standard deviation (> 0).
    values : tuple
        Choice's values.
    weights : tuple of float
        Choice's weights (normalized), empty for equal weights.
    """

    kind: str
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None
    values: tuple[Any, ...] = ()
    weights: tuple[float, ...] = ()

    def draw(self, rng: np.random.Generator) -> Any:
        """One value drawn with ``rng``."""
        if self.kind == "uniform":
            return float(rng.uniform(self.low, self.high))
        if self.kind == "log_uniform":
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        if self.kind == "normal":
            if self.low is None and self.high is None:
                return float(rng.normal(self.mean, self.std))
            from scipy.special import ndtr, ndtri

            a = 0.0 if self.low is None else float(ndtr((self.low - self.mean) / self.std))
            b = 1.0 if self.high is None else float(ndtr((self.high - self.mean) / self.std))
            x = self.mean + self.std * float(ndtri(rng.uniform(a, b)))
            lo = -math.inf if self.low is None else self.low
            hi = math.inf if self.high is None else self.high
            return min(max(x, lo), hi)
        if self.weights:
            return self.values[int(rng.choice(len(self.values), p=np.asarray(self.weights)))]
        return self.values[int(rng.integers(len(self.values)))]

    def extremes(self) -> tuple[Any, ...]:
        """The values every draw lies between (or among): the bounds, or the
        choices; a normal without bounds has none."""
        if self.kind == "choice":
            return self.values
        return tuple(x for x in (self.low, self.high) if x is not None)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"distribution": self.kind}
        for key in ("low", "high", "mean", "std"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.kind == "choice":
            out["values"] = list(self.values)
            if self.weights:
                out["weights"] = list(self.weights)
        return out


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterError(f"{key} must be a number (got {value!r})")
    if not math.isfinite(value):
        raise ParameterError(f"{key} must be finite (got {value!r})")
    return float(value)


def parse_distribution(raw: Any) -> Distribution:
    """A :class:`Distribution` from a spec's table, e.g.
    ``{distribution = "log_uniform", low = 1e4, high = 1e6}``.

    Raises
    ------
    ParameterError
        Naming the key that is missing, unknown or out of place.
    """
    if not isinstance(raw, Mapping):
        raise ParameterError(
            'must be a table such as {distribution = "uniform", low = 0.001, high = 0.01} '
            f"(got {raw!r})"
        )
    kind = raw.get("distribution")
    if kind not in DISTRIBUTIONS:
        raise ParameterError(
            f"distribution must be one of {', '.join(DISTRIBUTIONS)} (got {kind!r})"
        )
    required, optional = DISTRIBUTIONS[kind]
    unknown = sorted(set(raw) - set(required) - set(optional) - {"distribution"})
    if unknown:
        raise ParameterError(
            f"{kind} takes {', '.join(required + optional)}; unknown key {unknown[0]!r}"
        )
    missing = [k for k in required if k not in raw]
    if missing:
        raise ParameterError(f"{kind} needs {', '.join(required)}; {missing[0]} is missing")
    if kind == "choice":
        values = raw["values"]
        if not isinstance(values, list) or not values:
            raise ParameterError("values must be a non-empty list")
        weights: tuple[float, ...] = ()
        if "weights" in raw:
            w = raw["weights"]
            if not isinstance(w, list) or len(w) != len(values):
                raise ParameterError(f"weights must be a list of {len(values)} numbers")
            w = [_number("weights", x) for x in w]
            if min(w) < 0.0 or sum(w) <= 0.0:
                raise ParameterError("weights must be >= 0 with a positive sum")
            weights = tuple(x / sum(w) for x in w)
        return Distribution(kind, values=tuple(values), weights=weights)
    nums = {k: _number(k, raw[k]) for k in required + optional if k in raw}
    low, high = nums.get("low"), nums.get("high")
    if low is not None and high is not None and not low < high:
        raise ParameterError(f"low must be below high (got low = {low:g}, high = {high:g})")
    if kind == "log_uniform" and low <= 0.0:
        raise ParameterError(f"log_uniform needs low > 0 (got {low:g})")
    if kind == "normal":
        if nums["std"] <= 0.0:
            raise ParameterError(f"std must be > 0 (got {nums['std']:g})")
        return Distribution(kind, low=low, high=high, mean=nums["mean"], std=nums["std"])
    return Distribution(kind, low=low, high=high)
