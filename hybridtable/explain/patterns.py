"""Patterns in a CoR table, read to first order and checked against the effect library.

To first order the loop's ln CoR is ``pi^2 f_con (delay + table lag - T_lead
[SDC] - lag the MDC removes [MDC]) - pi zeta``: every loop effect moves the
four compensators' ln CoR along the same few directions. From that:

- **interaction** ``I = ln none - ln SDC - ln MDC + ln SDMDC`` (four
  compensators at the same conditions) is zero to first order; what each
  single effect of the library gives over its range is computed, not assumed;
- **readings**: the SDC's gain ``ln none - ln SDC`` is ``pi^2 f_con T_lead``,
  the MDC's ``ln none - ln MDC`` is ``pi^2 f_con`` times the lag it removes, so
  their ratio is that lag over the lead whatever f_con is; SDMDC below 1 needs
  damping or a lead longer than the delay;
- **trends**: rows at the same contact frequency and compensator whose CoR
  moves with the stiffness or the velocity, while the loop's CoR depends on
  f_con alone (a linear contact).

A pattern is flagged "not explained by the loop model" when the best model
misses it by more than :data:`FLAG_SIGMA` noise std.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hybridtable.explain.model import Case, CorModel, EffectAt

__all__ = ["FLAG_SIGMA", "WINDOW_LN", "interactions", "readings", "trends"]

#: How many noise std a pattern must miss the best model by to be flagged.
FLAG_SIGMA = 3.0
#: How far (ln CoR) outside the measured CoRs an effect's size still counts as near the table.
WINDOW_LN = 0.1
_ORDER = ("none", "SDC", "MDC", "SDMDC")


def _quartets(cases: Sequence[Case]) -> list[dict[str, list[int]]]:
    """Row indices of each compensator, per set of conditions that has all four."""
    sets: dict[object, dict[str, list[int]]] = {}
    for i, (comp, cond) in enumerate(cases):
        sets.setdefault(cond, {}).setdefault(comp, []).append(i)
    return [v for v in sets.values() if all(c in v for c in _ORDER)]


def _combine(values: np.ndarray, sigma: np.ndarray, quartet: dict[str, list[int]]):
    mean = {c: float(np.mean(values[quartet[c]])) for c in _ORDER}
    var = {c: float(np.sum(sigma[quartet[c]] ** 2)) / len(quartet[c]) ** 2 for c in _ORDER}
    return mean, var


def _interaction(m: dict[str, float]) -> float:
    return m["none"] - m["SDC"] - m["MDC"] + m["SDMDC"]


def _reach(
    effects: Sequence[EffectAt],
    cases: Sequence[Case],
    window: tuple[float, float],
    points: int = 13,
) -> dict[str, tuple]:
    """Per effect: (smallest, largest) interaction over the part of its range
    where all four ln CoR stay inside ``window``."""
    out = {}
    for e in effects:
        model = CorModel((e,))
        lo, hi = model.bounds()
        values = []
        for u in np.linspace(lo, hi, points):
            pred = model.predict(cases, u)
            if np.all((pred >= window[0]) & (pred <= window[1])):
                values.append(pred[0] - pred[1] - pred[2] + pred[3])
        if values:
            out[e.name] = (float(min(values)), float(max(values)))
    return out


def interactions(
    cases: Sequence[Case],
    y: np.ndarray,
    sigma: np.ndarray,
    predicted: np.ndarray,
    effects: Sequence[EffectAt],
    single: dict[str, np.ndarray] | None = None,
) -> list[dict]:
    """The interaction of every complete set of four compensators.

    Parameters
    ----------
    single : dict, optional
        Effect -> ln CoR of every row as that effect alone, fitted, predicts it.

    Returns
    -------
    list of dict
        ``interaction``, ``std``, ``best_model`` (the best fit's), ``stated_loop``
        (no effect), ``fitted_single`` (effect -> I at its fit), ``library``
        (effect -> [min, max] over its range while the four CoRs stay within
        ``WINDOW_LN`` of the measured ones), ``nearest`` (the closest of all
        these), ``distance_sigma``, ``flagged``.
    """
    out = []
    for quartet in _quartets(cases):
        m, v = _combine(y, sigma, quartet)
        p, _ = _combine(predicted, sigma, quartet)
        measured = _interaction(m)
        std = math.sqrt(sum(v.values()))
        four = [cases[quartet[c][0]] for c in _ORDER]
        window = (min(m.values()) - WINDOW_LN, max(m.values()) + WINDOW_LN)
        reach = _reach(effects, four, window)
        nominal = CorModel(()).predict(four, np.zeros(0))
        stated = float(nominal[0] - nominal[1] - nominal[2] + nominal[3])
        fitted = {
            name: _interaction(_combine(pred, sigma, quartet)[0])
            for name, pred in (single or {}).items()
        }
        best = _interaction(p)
        points = [stated, best, *fitted.values()]
        lows = [a for a, _ in reach.values()] + points
        highs = [b for _, b in reach.values()] + points
        nearest = float(min(max(measured, min(lows)), max(highs)))
        out.append(
            {
                "conditions": four[0][1].to_dict(),
                "interaction": measured,
                "std": std,
                "best_model": best,
                "stated_loop": stated,
                "fitted_single": fitted,
                "fitted_single_largest": float(max((abs(x) for x in fitted.values()), default=0.0)),
                "library": {k: list(r) for k, r in reach.items()},
                "library_largest": float(max(abs(x) for x in lows + highs)),
                "nearest": nearest,
                "distance_sigma": abs(measured - nearest) / std,
                "flagged": abs(measured - best) > FLAG_SIGMA * std
                and abs(measured - nearest) > FLAG_SIGMA * std,
            }
        )
    return out


def readings(cases: Sequence[Case], y: np.ndarray, sigma: np.ndarray) -> list[dict]:
    """First-order readings of each complete set of four compensators, in words."""
    out = []
    for quartet in _quartets(cases):
        m, v = _combine(y, sigma, quartet)
        cond = cases[quartet["none"][0]][1]
        words = []
        sdc_gain = m["none"] - m["SDC"]
        mdc_gain = m["none"] - m["MDC"]
        s_sdc = math.sqrt(v["none"] + v["SDC"])
        s_mdc = math.sqrt(v["none"] + v["MDC"])
        pi2 = math.pi**2
        f_lead = sdc_gain / pi2
        stated = cond.contact_frequency_hz * cond.lead_s
        item = {"f_con_times_lead": f_lead, "stated_f_con_times_lead": stated}
        if stated > 0 and sdc_gain > 3 * s_sdc:
            ratio = f_lead / stated
            if abs(ratio - 1.0) <= 3 * s_sdc / sdc_gain:
                judgement = "as stated"
            else:
                judgement = (
                    f"the contact is {ratio:.2g} times faster than stated, or the lead that much "
                    "longer"
                )
            words.append(
                f"The SDC's gain ln(none/SDC) = {sdc_gain:.4f} gives f_con * T_lead = {f_lead:.4g} "
                f"(pi^2 f_con T_lead to first order); the stated {cond.contact_frequency_hz:g} Hz "
                f"and {1e3 * cond.lead_s:g} ms give {stated:.4g}: {judgement}."
            )
        if sdc_gain > 3 * s_sdc:
            lag = mdc_gain / sdc_gain * cond.lead_s
            item["mdc_removed_lag_s"] = lag
            if mdc_gain < sdc_gain - 2 * math.hypot(s_sdc, s_mdc):
                table = cond.table_lag_s
                faster = table / lag if lag > 0 else math.inf
                words.append(
                    f"MDC is worse than SDC (CoR {math.exp(m['MDC']):.4f} against "
                    f"{math.exp(m['SDC']):.4f}): the lag the MDC removes is "
                    f"{mdc_gain / sdc_gain:.2f} of the lead, {1e3 * lag:.2g} ms, while the stated "
                    f"table lags {1e3 * table:.3g} ms: the table responds about {faster:.2g} times "
                    "faster than stated (or the MDC believes a stiffness that much too low)."
                )
        s_sd = math.sqrt(v["SDMDC"])
        if m["SDMDC"] < -2 * s_sd:
            zeta = -m["SDMDC"] / math.pi
            excess = -m["SDMDC"] / (pi2 * cond.contact_frequency_hz)
            words.append(
                f"SDMDC is below 1 (CoR {math.exp(m['SDMDC']):.4f}): net damping (a damping ratio "
                f"of {zeta:.2g}) or a lead longer than the delay (by {1e3 * excess:.2g} ms at "
                f"{cond.contact_frequency_hz:g} Hz), or an MDC removing more lag than the table "
                "has; the table alone cannot separate these."
            )
        item["words"] = words
        out.append(item)
    return out


def trends(
    cases: Sequence[Case],
    y: np.ndarray,
    sigma: np.ndarray,
    predicted: np.ndarray,
    effects: Sequence[EffectAt],
) -> list[dict]:
    """Rows at the same compensator and contact frequency whose CoR moves with a condition.

    Repeated rows of the same conditions count as one (their mean); a pair
    names the first row of each.

    For the stiffness and the velocity: the pairs of rows that differ in it
    (same compensator and f_con), the measured change of ln CoR from the lower
    to the higher value, and the best model's. Flagged when every pair moves
    the same way, there are at least three, and the best model misses their
    sum by more than :data:`FLAG_SIGMA` std; ``library_can`` lists the effects
    that move the pairs that way at a size that keeps the CoRs within
    :data:`WINDOW_LN` of the table's.
    """
    # Repeated rows of the same conditions are one point: their mean, its noise.
    groups: dict[Case, list[int]] = {}
    for i, case in enumerate(cases):
        groups.setdefault(case, []).append(i)
    distinct, rows = list(groups), [g[0] for g in groups.values()]
    ym = np.array([float(np.mean(y[g])) for g in groups.values()])
    sm = np.array([math.sqrt(float(np.sum(sigma[g] ** 2))) / len(g) for g in groups.values()])
    out = []
    for field, word in (
        ("contact_stiffness_n_per_m", "stiffer spring"),
        ("initial_velocity_m_per_s", "faster approach"),
    ):
        pairs = []
        for i in range(len(distinct)):
            for j in range(i + 1, len(distinct)):
                (ci, ki), (cj, kj) = distinct[i], distinct[j]
                if ci != cj or ki.contact_frequency_hz != kj.contact_frequency_hz:
                    continue
                xi, xj = getattr(ki, field), getattr(kj, field)
                if xi == xj:
                    continue
                lo, hi = (i, j) if xi < xj else (j, i)
                pairs.append((lo, hi))
        if len(pairs) < 3:
            continue
        d = np.array([ym[h] - ym[lo] for lo, h in pairs])
        dp = np.array([predicted[rows[h]] - predicted[rows[lo]] for lo, h in pairs])
        s = np.array([math.hypot(sm[h], sm[lo]) for lo, h in pairs])
        same = bool(np.all(d < 0) or np.all(d > 0))
        miss = float(np.sum(d - dp) / math.sqrt(np.sum(s**2)))
        sign = 1.0 if np.mean(d) > 0 else -1.0
        can = []
        lows = [distinct[lo] for lo, _ in pairs]
        highs = [distinct[h] for _, h in pairs]
        for e in effects:
            model = CorModel((e,))
            a, b = model.bounds()
            for u in np.linspace(a, b, 13):
                ph, pl = model.predict(highs, u), model.predict(lows, u)
                both = np.concatenate([ph, pl])
                if np.any((both < y.min() - WINDOW_LN) | (both > y.max() + WINDOW_LN)):
                    continue  # a size far from the table's CoRs
                moved = ph - pl
                if np.all(sign * moved > 0) and sign * np.sum(moved) > FLAG_SIGMA * math.sqrt(
                    np.sum(s**2)
                ):
                    can.append(e.name)
                    break
        direction = "higher" if sign > 0 else "lower"
        out.append(
            {
                "condition": field,
                "pairs": [[rows[lo], rows[h]] for lo, h in pairs],
                "measured_change": [float(x) for x in d],
                "best_model_change": [float(x) for x in dp],
                "all_same_way": same,
                "miss_sigma": miss,
                "library_can": can,
                "flagged": same and abs(miss) > FLAG_SIGMA,
                "words": f"the {word} gives the {direction} CoR in "
                f"{int(np.sum(sign * d > 0))} of {len(pairs)} pairs at the same contact frequency "
                f"(mean change of ln CoR {float(np.mean(d)):+.4f}); the best model gives "
                f"{float(np.mean(dp)):+.4f}, {abs(miss):.1f} std away; "
                + (
                    "no effect in the library moves them that way"
                    if not can
                    else "the library's " + ", ".join(can) + " can move them that way"
                ),
            }
        )
    return out
