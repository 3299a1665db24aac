"""What a CoR table can determine, and what it cannot: the SVD of its sensitivities.

Every effect parameter moves one loop quantity (its ``quantity``: f_con, the
delay, the SDC's lead, the table's lag, the MDC's stiffness, the damping). The
table's sensitivities to those quantities (d ln CoR / d ln q for a quantity
with a stated size, d ln CoR / d q per unit otherwise), weighted by each row's
noise, are split by the SVD into directions the table determines (a change of
one tenth of a quantity, or of one unit, moves the table by more than one
noise std) and directions it cannot resolve.

The determined directions are stated as named combinations: a quantity alone,
or a product or ratio of two (``f_con * T_lead``) whose sensitivity lies in the
determined space (at most 10 % of it outside). The unresolved directions are
stated as the changes that leave every CoR of the table unchanged.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hybridtable.effects.effect import ParameterAt
from hybridtable.explain.model import Case, CorModel, EffectAt, loop_of

__all__ = ["Quantity", "Identifiability", "identifiability"]

#: A direction is determined when its std is below this (10 % of a quantity, or 0.1 unit).
DETERMINED_STD = 0.1
#: A named combination is determined when at most this part of it lies outside the determined space.
OUTSIDE_FRACTION = 0.1


@dataclass(frozen=True)
class Quantity:
    """A loop quantity, as the effect parameter that moves it.

    Parameters
    ----------
    name : str
        The quantity in words (``"delay"``).
    effect : EffectAt
        The effect whose parameter moves it.
    parameter : ParameterAt
        That parameter.
    reference : float
        Its size on the table (the stated value, s or Hz, or the ratio 1), or 0
        when it has none (then it is additive: the unit is the parameter's ``scale``).
    """

    name: str
    effect: EffectAt
    parameter: ParameterAt
    reference: float

    @property
    def relative(self) -> bool:
        """Changes are relative (d ln q) rather than additive."""
        return self.parameter.log or self.reference > 0.0

    def per_coordinate(self) -> float:
        """d (ln q or q / unit) / d u: the quantity's change for one unit of the fit's coordinate."""
        p = self.parameter
        if p.log:
            return -p.scale if self.name == "table lag" else p.scale
        if self.reference > 0.0:
            return p.scale / self.reference
        return 1.0


def _reference(name: str, cases: Sequence[Case], effects, at) -> float:
    loops = [loop_of(c, effects, at)[0] for c in cases]
    if name == "delay":
        return float(np.mean([p.sensor_delay_s for p in loops]))
    if name == "T_lead":
        return float(np.mean([p.beliefs()["lead_time_s"] for p in loops]))
    return 0.0


def quantities(
    effects: Sequence[EffectAt], cases: Sequence[Case], at: dict[str, float] | None = None
) -> list[Quantity]:
    """One :class:`Quantity` per distinct ``quantity`` of the effects' parameters (first
    wins), sized at the parameter values ``at`` (default: null)."""
    full = {p.name: p.null for e in effects for p in e.parameters} | dict(at or {})
    out: dict[str, Quantity] = {}
    for e in effects:
        for p in e.parameters:
            if p.quantity and p.quantity not in out:
                out[p.quantity] = Quantity(
                    p.quantity, e, p, _reference(p.quantity, cases, effects, full)
                )
    return list(out.values())


@dataclass(frozen=True)
class Identifiability:
    """What the table determines and what it leaves open.

    Parameters
    ----------
    quantities : list of str
        The loop quantities analysed.
    singular_values : list of float
        Of the noise-weighted sensitivities (per 100 % of a relative quantity).
    identifiable : list of dict
        Named combinations the table determines: ``combination`` (words),
        ``exponents`` (quantity -> power), ``std`` (relative, or per unit).
    unresolved : list of dict
        Directions it cannot resolve: ``words``, ``direction`` (quantity -> weight).
    undetermined : list of str
        Quantities the table cannot determine alone.
    """

    quantities: list[str]
    singular_values: list[float]
    identifiable: list[dict]
    unresolved: list[dict]
    undetermined: list[str]

    def to_dict(self) -> dict:
        """JSON-ready."""
        return {
            "quantities": self.quantities,
            "singular_values": self.singular_values,
            "identifiable": self.identifiable,
            "unresolved": self.unresolved,
            "undetermined": self.undetermined,
        }


def _combo_words(exponents: dict[str, int]) -> str:
    up = [q for q, e in exponents.items() if e > 0]
    down = [q for q, e in exponents.items() if e < 0]
    words = " * ".join(up) if up else "1"
    return words + "".join(f" / {q}" for q in down)


def _amount(q: Quantity, w: float) -> str:
    if q.relative:
        return f"{q.name} by {100 * w:+.3g} %"
    return f"{q.name} by {w * q.parameter.scale:+.3g} {q.parameter.unit}"


#: The times that scale against f_con: the CoR is unchanged when f_con grows and they shrink.
SCALED_TIMES = ("delay", "T_lead", "table lag")


def identifiability(
    effects: Sequence[EffectAt],
    cases: Sequence[Case],
    sigma: np.ndarray,
    at: dict[str, float] | None = None,
) -> Identifiability:
    """Analyse the table ``cases`` (noise ``sigma`` in ln CoR) around the parameter values ``at``.

    Parameters
    ----------
    effects : sequence of EffectAt
        The library.
    cases : sequence of (compensator, Conditions)
        The table's rows.
    sigma : ndarray
        Each row's noise, in ln CoR.
    at : dict, optional
        Parameter -> value of the point to linearize at (default: every effect null).
    """
    qs = quantities(effects, cases, at)
    if not qs:  # no effect names the loop quantity it moves
        return Identifiability([], [], [], [], [])
    model = CorModel(effects)
    u = model.coordinates(at or {})
    # one column per quantity: its parameter's column, per unit of the quantity
    index = [next(j for j, p in enumerate(model.parameters) if p is q.parameter) for q in qs]
    # steps of half a scale: the continuous engine's ln CoR jitters by ~5e-5 over finer ones
    full = model.jacobian(cases, u, step=0.5, columns=index)
    cols = [full[:, k] / q.per_coordinate() for k, q in enumerate(qs)]
    jac = np.column_stack(cols) / sigma[:, None]
    names = [q.name for q in qs]
    _, s, vt = np.linalg.svd(jac, full_matrices=True)
    s_full = np.zeros(len(names))
    s_full[: len(s)] = s
    determined = vt[s_full * DETERMINED_STD > 1.0]
    # the covariance within the determined space: the open directions carry no information
    s_det = s_full[s_full * DETERMINED_STD > 1.0]
    cov = determined.T @ np.diag(1.0 / s_det**2) @ determined

    def check(g: np.ndarray) -> tuple[bool, float]:
        """Whether the combination with exponents ``g`` is determined, and its std
        (relative, or per unit)."""
        unit = g / np.linalg.norm(g)
        inside = determined.T @ (determined @ unit) if len(determined) else np.zeros_like(g)
        ok = np.linalg.norm(unit - inside) <= OUTSIDE_FRACTION
        return ok, float(math.sqrt(max(g @ cov @ g, 0.0)))

    identifiable, singles = [], set()
    for i, name in enumerate(names):
        g = np.zeros(len(names))
        g[i] = 1.0
        ok, std = check(g)
        if ok:
            singles.add(name)
            identifiable.append(
                {
                    "combination": name,
                    "exponents": {name: 1},
                    "std": std,
                    "relative": qs[i].relative,
                }
            )
    rel = [i for i, q in enumerate(qs) if q.relative]
    accepted = [np.eye(len(names))[i] for i, n in enumerate(names) if n in singles]
    for size in (2, 3):
        for group in itertools.combinations(rel, size):
            if any(names[i] in singles for i in group):
                continue
            for signs in itertools.product((1, -1), repeat=size - 1):
                g = np.zeros(len(names))
                g[group[0]] = 1.0
                g[list(group[1:])] = signs
                ok, std = check(g)
                if ok and accepted:
                    basis = np.array(accepted).T
                    coef, *_ = np.linalg.lstsq(basis, g, rcond=None)
                    ok = np.linalg.norm(basis @ coef - g) > OUTSIDE_FRACTION * np.linalg.norm(g)
                if ok:
                    accepted.append(g.copy())
                    exps = {names[group[0]]: 1} | {
                        names[i]: sg for i, sg in zip(group[1:], signs, strict=True)
                    }
                    identifiable.append(
                        {
                            "combination": _combo_words(exps),
                            "exponents": exps,
                            "std": std,
                            "relative": True,
                        }
                    )
    unresolved = []
    by_name = {q.name: q for q in qs}
    outside = determined.T @ determined if len(determined) else np.zeros((len(names),) * 2)
    scaled = [n for n in SCALED_TIMES if n in by_name]
    if "f_con" in by_name and scaled:
        g = np.array([1.0 if n == "f_con" else -1.0 if n in scaled else 0.0 for n in names])
        g /= np.linalg.norm(g)
        if np.linalg.norm(outside @ g) <= OUTSIDE_FRACTION:
            unresolved.append(
                {
                    "direction": {n: (1.0 if n == "f_con" else -1.0) for n in ["f_con", *scaled]},
                    "words": "raising f_con by 1 % while shortening "
                    + ", ".join(scaled)
                    + " by 1 % each leaves every CoR unchanged: the table fixes products "
                    "f_con * time, never f_con or a time alone",
                }
            )
    for a, b in itertools.combinations(range(len(names)), 2):
        ca, cb = jac[:, a], jac[:, b]
        na, nb = np.linalg.norm(ca), np.linalg.norm(cb)
        if na * DETERMINED_STD <= 1.0 or nb * DETERMINED_STD <= 1.0:
            continue
        cos = float(ca @ cb / (na * nb))
        if abs(cos) > 0.99:
            w = float(ca @ cb / nb**2)  # one unit of a does what w units of b do
            unresolved.append(
                {
                    "direction": {names[a]: 1.0, names[b]: -w},
                    "words": f"{names[a]} and {names[b]} move this table alike: changing "
                    f"{_amount(by_name[names[a]], 0.01)} does what changing "
                    f"{_amount(by_name[names[b]], 0.01 * w)} does",
                }
            )
    for i, name in enumerate(names):
        if np.linalg.norm(jac[:, i]) * DETERMINED_STD <= 1.0:
            unresolved.append(
                {
                    "direction": {name: 1.0},
                    "words": f"{name} does not move this table by more than its noise "
                    f"({_amount(by_name[name], DETERMINED_STD)} or less)",
                }
            )
    rank = len(determined)
    if rank < len(names):
        unresolved.append(
            {
                "direction": {},
                "words": f"the table determines {rank} combination(s) of the {len(names)} "
                f"quantities ({', '.join(names)}); {len(names) - rank} direction(s) are open",
            }
        )
    return Identifiability(
        quantities=names,
        singular_values=[float(x) for x in s_full],
        identifiable=identifiable,
        unresolved=unresolved,
        undetermined=[n for n in names if n not in singles],
    )
