"""The one search for models of several effects, for every front end.

A front end fits every candidate effect alone (``diagnose``'s first round,
``explain``'s singles). Models of two or three effects are too many to fit
all of them (13 effects make 78 pairs and 286 triples, and a fit costs
seconds to minutes), and forward selection alone misses two effects whose
influence cancels (one dissipates, one adds energy: neither enters alone).
:func:`propose` names the few worth fitting, of one size:

- the combinations a front end's cheap *screen* ranks best, the ``keep``
  best (``explain``: the loop linearized at the stated point, bounded linear
  least squares; ``diagnose``: the best point of a grid over each pair on the
  runs the nominal model misses most);
- every combination of the ``best`` single effects (unscreened);

and :func:`swaps` the current selection with one effect replaced by one of
the best candidates (a look-alike chosen first can block the right effect).
:func:`forward` is the forward selection itself, every front end's one loop:
the candidates beside the selection (none changing a part a selected effect
changes), one round of fits, the one the front end's rule lets in.

Combinations a front end cannot use (two effects that change the same part, a
pair it holds already) are left out before the screen, and no set of effects
is proposed twice. Each proposal carries its start: the screen's best point
where it has one, else what the front end gives (the single effects' own fits).
The front end fits the proposals (:func:`~hybridtable.effects.workers.pool_map`)
and judges them with its own rule (:mod:`~hybridtable.effects.selection`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from itertools import combinations

from hybridtable.effects.registry import get_effect

__all__ = ["Proposal", "forward", "beside", "compatible", "propose", "swaps"]

#: Effect names of one model.
Names = tuple[str, ...]

#: Effect -> parameter -> value (SI units).
Start = dict[str, dict[str, float]]


@dataclass(frozen=True)
class Proposal:
    """A model of several effects worth fitting, and where its fit starts."""

    names: Names
    start: Start = field(default_factory=dict)
    #: The screen's figure (the lower the better; NaN: not screened).
    screened: float = math.nan


def propose(
    names: Sequence[str],
    size: int,
    screen: Callable[[list[Names]], Sequence[tuple[float, Start | None]]],
    keep: int,
    start: Callable[[Names], Start] = lambda _c: {},
    best: Sequence[str] = (),
    allowed: Callable[[Names], bool] = lambda _c: True,
    seen: set[frozenset[str]] | None = None,
) -> list[Proposal]:
    """The combinations of ``size`` of ``names`` worth fitting (see the module doc).

    Parameters
    ----------
    names : sequence of str
        The candidate effects; a combination lists its effects in this order.
    screen : callable
        The combinations ``allowed`` -> for each, its figure (lower is better;
        not finite: it could not be screened, and is not proposed from the
        screen) and the start it found (None: ``start`` gives it).
    keep : int
        How many of the best screened combinations are proposed.
    start : callable
        The start of a combination the screen gives none for.
    best : sequence of str
        Effects each of whose combinations of ``size`` is proposed unscreened.
    allowed : callable
        Whether a combination may be proposed at all.
    seen : set, optional
        The sets of effects proposed already (by an earlier size or search);
        the ones proposed here are added.
    """
    seen = set() if seen is None else seen
    order = {n: i for i, n in enumerate(names)}
    candidates = [c for c in combinations(names, size) if allowed(c)]
    scores = screen(candidates) if candidates else []
    screened = [
        (cost, c, found)
        for c, (cost, found) in zip(candidates, scores, strict=True)
        if math.isfinite(cost)
    ]
    chosen = [(c, found, cost) for cost, c, found in sorted(screened, key=lambda r: r[0])][:keep]
    for combo in combinations(best, size):
        chosen.append((tuple(sorted(combo, key=order.__getitem__)), None, math.nan))
    out = []
    for c, found, cost in chosen:
        if frozenset(c) in seen or not allowed(c):
            continue
        seen.add(frozenset(c))
        out.append(Proposal(c, start(c) if found is None else found, cost))
    return out


def swaps(
    selected: Sequence[str],
    pool: Sequence[str],
    allowed: Callable[[Names], bool] = lambda _c: True,
    seen: set[frozenset[str]] | None = None,
) -> Iterator[Names]:
    """The selection with one of its effects replaced by one of ``pool``'s that it
    does not hold (the replacement last), each set of effects once (none of
    ``seen``, to which they are added) and ``allowed``."""
    seen = set() if seen is None else seen
    for s in selected:
        for c in pool:
            names = (*(n for n in selected if n != s), c)
            if c not in selected and frozenset(names) not in seen and allowed(names):
                seen.add(frozenset(names))
                yield names


def compatible(names: Sequence[str]) -> bool:
    """No two of the effects ``names`` change the same part
    (:meth:`~hybridtable.effects.effect.Effect.conflicts_with`): a model can
    hold them together."""
    effects = [get_effect(n) for n in names]
    return not any(a.conflicts_with(b) for a, b in combinations(effects, 2))


def beside(names: Sequence[str], selected: Sequence[str]) -> list[str]:
    """The candidates of ``names`` a model of ``selected`` can gain: not
    selected, and changing no part a selected effect changes
    (:meth:`~hybridtable.effects.effect.Effect.conflicts_with`)."""
    chosen = [get_effect(s) for s in selected]
    return [
        n
        for n in names
        if n not in selected and not any(get_effect(n).conflicts_with(s) for s in chosen)
    ]


def forward(
    names: Sequence[str],
    selected: list[str],
    max_effects: int,
    round_: Callable[[list[str]], str | None],
) -> list[str]:
    """Forward selection from ``selected`` (extended in place, and returned):
    while it holds fewer than ``max_effects``, ``round_(pool)`` fits the
    candidates :func:`beside` it and names the one its front end's rule lets
    in (None: none, and the selection ends); it ends too when no candidate is
    left."""
    while len(selected) < max_effects:
        pool = beside(names, selected)
        if not pool:
            break
        chosen = round_(pool)
        if chosen is None:
            break
        selected.append(chosen)
    return selected
