"""The models that fit a CoR table equally well, and the run that would tell them apart.

Look-alikes are the fitted models within :data:`LOOKALIKE_BIC` of the best
one's BIC. For each look-alike of the best, every candidate run is predicted
by both fits: each compensator at the table's first conditions, and each with
the spring twice and half as stiff against the same spacecraft model (f_con
times or over sqrt 2), and the SDC with twice the lead. The run whose two
predictions differ by the most noise std separates them
(:func:`~hybridtable.effects.selection.most_separating`, as ``diagnose``'s
does): with :data:`SEPARATING_STD` or more in one run, or else in the
number of such runs it says.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from hybridtable.effects import selection
from hybridtable.effects.selection import most_separating
from hybridtable.explain.conditions import Conditions
from hybridtable.explain.fit import ModelFit
from hybridtable.explain.model import Case, CorModel, EffectAt

__all__ = ["LOOKALIKE_BIC", "SEPARATING_STD", "lookalikes", "separating_runs"]

#: Models whose BIC is within this of the best one's fit the table equally well.
LOOKALIKE_BIC = 2.0

#: A run separates two models when their predictions differ by more than this
#: many noise std (a squared distance of 9: independent runs add theirs).
SEPARATING_STD = 3.0


def lookalikes(fits: Sequence[ModelFit]) -> list[ModelFit]:
    """The fits within :data:`LOOKALIKE_BIC` of the best (the best first;
    :func:`~hybridtable.effects.selection.lookalikes`: a fit that holds all of the
    best's effects and more is not another explanation, only the best one with
    something added, and is left out)."""
    if not fits:
        return []
    best = fits[0]
    return [best, *selection.lookalikes(best, fits, LOOKALIKE_BIC, _bic, _effects)]


def _bic(fit: ModelFit) -> float:
    return fit.bic


def _effects(fit: ModelFit) -> tuple[str, ...]:
    return fit.effects


def _candidates(first: Conditions) -> list[tuple[str, Case]]:
    mass = first.spacecraft_mass_kg
    out = []
    for comp in ("none", "SDC", "MDC", "SDMDC"):
        out.append((f"{comp} at the table's first conditions", (comp, first)))
        for factor, word in ((2.0, "twice as stiff"), (0.5, "half as stiff")):
            k = first.contact_stiffness_n_per_m * factor
            f = math.sqrt(k / mass) / (2 * math.pi)
            out.append(
                (
                    f"{comp} with a spring {word} ({k:.4g} N/m, same model mass: f_con {f:.3g} Hz)",
                    (comp, replace(first, contact_stiffness_n_per_m=k, contact_frequency_hz=f)),
                )
            )
    lead = 2 * first.lead_s if first.lead_s > 0 else first.sensor_delay_s or 0.001
    out.append(
        (f"SDC with a lead of {1e3 * lead:.3g} ms", ("SDC", replace(first, lead_time_s=lead)))
    )
    return out


def _predict(fit: ModelFit, case: Case, effects: Sequence[EffectAt]) -> float:
    by_name = {e.name: e for e in effects}
    model = CorModel([by_name[n] for n in fit.effects])
    return float(model.predict([case], model.coordinates(fit.values))[0])


def separating_runs(
    fits: Sequence[ModelFit], first: Conditions, sigma_ln: float, effects: Sequence[EffectAt]
) -> list[dict]:
    """For each look-alike of the best fit: the candidate run that separates them most.

    Parameters
    ----------
    fits : sequence of ModelFit
        Ranked, best first.
    first : Conditions
        The conditions candidate runs start from.
    sigma_ln : float
        The noise of one new run, in ln CoR.
    effects : sequence of EffectAt
        The effects the fits are made of.
    """
    alike = lookalikes(fits)
    if len(alike) < 2:
        return []
    best = alike[0]
    out = []
    for other in alike[1:4]:
        pair = {}

        def distance(candidate, other=other, pair=pair) -> float:
            words, case = candidate
            pair[words] = (_predict(best, case, effects), _predict(other, case, effects))
            return abs(pair[words][0] - pair[words][1]) / sigma_ln

        sep = most_separating(_candidates(first), distance, SEPARATING_STD**2)
        words = sep.design[0]
        a, b = pair[words]
        out.append(
            {
                "models": [best.name, other.name],
                "run": words,
                "cor": [float(np.exp(a)), float(np.exp(b))],
                "separation_sigma": float(sep.distance),
                "separates": sep.separates,
                "runs_needed": sep.runs_needed,
                "words": (
                    f"a run of {words} separates {best.name} (CoR {np.exp(a):.4f}) from "
                    f"{other.name} (CoR {np.exp(b):.4f}) by {sep.distance:.1f} noise std"
                    if sep.separates
                    else f"no candidate run separates {best.name} from {other.name} by "
                    f"{SEPARATING_STD:g} noise std (best: {words}, {sep.distance:.1f} std"
                    + (
                        f"; {sep.runs_needed} such runs would)"
                        if sep.runs_needed is not None and sep.runs_needed > 1
                        else ")"
                    )
                ),
            }
        )
    return out
