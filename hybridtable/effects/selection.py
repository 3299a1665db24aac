"""One rule for choosing among fitted models, for every front end.

A front end fits models with :mod:`~hybridtable.effects.fitting` and scores
them here:

- **the information criterion** (BIC) of residuals in noise units, for both
  noise models: *stated* (each residual's sigma is known, as a CoR table's
  rows: ``-2 ln L = chi2``) or *estimated* per block (prewhitened blocks of a
  recorded run whose innovation variance is estimated with the model:
  ``-2 ln L = N_b ln s2_b``, ``s2_b`` never below the block's numerical floor,
  so no model is credited with residuals finer than the numbers can be);
  ``delta_bic`` is the gain of one model over another, ``- dp ln N`` for the
  parameters it adds;
- **look-alikes**: models whose criterion is within a margin of a reference
  (the data cannot tell them apart); a model holding all of the reference's
  effects and more is the reference with something added, not another
  explanation;
- **the separating run**: of candidate runs, the one on which two models'
  predictions differ most in noise units; independent runs add their squared
  distances, so it says how many such runs would separate them at a
  threshold (:func:`separation_words`: the words both ``diagnose`` front ends
  say it in).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

__all__ = [
    "MAX_RUNS_SUGGESTED",
    "SCALED_RUNS",
    "Block",
    "Separation",
    "bic",
    "delta_bic",
    "lookalikes",
    "most_separating",
    "scaled_runs",
    "separation_words",
]

T = TypeVar("T")
D = TypeVar("D")


@dataclass(frozen=True)
class Block:
    """A block of residuals in noise units: their sum of squares, their number,
    and (estimated noise) the smallest variance a model is credited with."""

    rss: float
    n: int
    floor: float = 0.0


def bic(chi2: float, n_parameters: int, n: int) -> float:
    """``chi2 + p ln n`` of residuals whose noise is stated."""
    return chi2 + n_parameters * math.log(n)


def delta_bic(
    before: Sequence[Block], after: Sequence[Block], added_parameters: int, stated: bool
) -> float:
    """The BIC of the model ``before`` minus that of ``after`` (positive: ``after``
    is better) over the same blocks (see the module doc); ``stated``: the noise of
    every residual is known, else each block's variance is estimated."""
    total, n_total = 0.0, 0
    for b0, b1 in zip(before, after, strict=True):
        n_total += b0.n
        if stated:
            total += b0.rss - b1.rss
            continue
        s0 = max(b0.rss / b0.n, b0.floor)
        s1 = max(b1.rss / b1.n, b1.floor)
        if s0 > 0.0 and s1 > 0.0:
            total += b0.n * math.log(s0 / s1)
    return total - added_parameters * math.log(max(n_total, 2))


def lookalikes(
    reference: T,
    others: Iterable[T],
    margin: float,
    score: Callable[[T], float],
    effects: Callable[[T], Iterable[str]],
    inclusive: bool = True,
) -> list[T]:
    """The ``others`` whose ``score`` is within ``margin`` of ``reference``'s (at
    ``margin`` itself too when ``inclusive``) and that are not ``reference`` with
    effects added."""
    ref, ref_effects = score(reference), set(effects(reference))
    return [
        o
        for o in others
        if o is not reference
        and (abs(score(o) - ref) <= margin if inclusive else abs(score(o) - ref) < margin)
        and not (ref_effects < set(effects(o)))
    ]


@dataclass(frozen=True)
class Separation:
    """The run that separates two models best, and what it is worth."""

    design: object
    distance: float
    threshold: float

    @property
    def separates(self) -> bool:
        """One such run tells them apart: its squared distance exceeds the threshold."""
        return self.distance * self.distance > self.threshold

    @property
    def runs_needed(self) -> int | None:
        """How many such runs would (None: the models agree on it)."""
        d2 = self.distance * self.distance
        return math.ceil(self.threshold / d2) if d2 > 0.0 else None

    def to_dict(self, recorded_distance: float) -> dict:
        """As ``diagnose`` reports it, for a design of (words, changes):
        ``run``, ``changes``, ``distance``, ``recorded_distance`` (the two
        models apart on the recorded runs), ``separates``, ``runs_needed``."""
        words, changes = self.design
        return {
            "run": words,
            "changes": changes,
            "distance": self.distance,
            "recorded_distance": recorded_distance,
            "separates": self.separates,
            "runs_needed": self.runs_needed,
        }


def _first(values: Sequence[float]) -> float:
    return values[0]


#: The candidate runs both ``diagnose`` front ends try (the 1-D run's JSON and
#: a six-axis scenario name these quantities alike): (words, the quantity,
#: its factor, of the recorded runs' slowest, fastest or first value).
SCALED_RUNS: tuple[tuple[str, str, float, Callable[[Sequence[float]], float]], ...] = (
    ("half the approach velocity", "initial_velocity_m_per_s", 0.5, min),
    ("twice the approach velocity", "initial_velocity_m_per_s", 2.0, max),
    ("three times the approach velocity", "initial_velocity_m_per_s", 3.0, max),
    ("a quarter of the spacecraft mass", "spacecraft_mass_kg", 0.25, _first),
    ("four times the spacecraft mass", "spacecraft_mass_kg", 4.0, _first),
)


def scaled_runs(
    quantity: Callable[[Any, str], float],
) -> tuple[tuple[str, Callable[[Sequence[Any]], dict]], ...]:
    """:data:`SCALED_RUNS` as a front end's designs: (words, the recorded runs
    -> the changes), ``quantity(run, name)`` reading a run's value."""
    return tuple(
        (
            words,
            lambda runs, n=name, f=factor, of=pick: {n: f * of([quantity(r, n) for r in runs])},
        )
        for words, name, factor, pick in SCALED_RUNS
    )


#: Most runs of one kind a separation's words suggest.
MAX_RUNS_SUGGESTED = 5


def separation_words(s: dict, pair: Sequence[str]) -> str:
    """What run (``s``: :meth:`Separation.to_dict`, with the look-alike's
    ``hint``; ``run`` None and ``why``: none was sought) would tell
    ``pair[0]`` from the others, in words."""
    head = f"{pair[0]} and {', '.join(pair[1:])} are indistinguishable on these runs"
    if s.get("run") is None:
        return f"{head}; no run that would separate them was sought: {s.get('why')}."
    head += f" (predictions {s['recorded_distance']:.3g} noise units apart)"
    if s.get("separates"):
        return f"{head}; a run with {s['run']} would put them {s['distance']:.3g} apart."
    needed = s.get("runs_needed")
    if needed is not None and needed <= MAX_RUNS_SUGGESTED:
        return (
            f"{head}; {needed} runs with {s['run']} would separate them "
            f"({s['distance']:.3g} noise units apart each)."
        )
    return (
        f"{head}; none of the runs tried separates them (at most {s['distance']:.3g} "
        f"apart, with {s['run']}): {s.get('hint') or 'another kind of measurement'}."
    )


def most_separating(
    designs: Iterable[D], distance: Callable[[D], float | None], threshold: float
) -> Separation | None:
    """Of ``designs``, the one whose ``distance`` (noise units; None: it could not
    be simulated) is largest; None if none could be."""
    best: Separation | None = None
    for design in designs:
        d = distance(design)
        if d is not None and (best is None or d > best.distance):
            best = Separation(design, d, threshold)
    return best
