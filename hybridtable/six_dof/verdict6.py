"""The verdict of ``diagnose`` on 6-DoF runs (:mod:`~hybridtable.six_dof.diagnose6`):
each component's replay error in noise levels, when a model explains the
runs, the rounds and the swap step, and the one-line verdict with its
evidence (:class:`Diagnosis6`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from hybridtable.diagnosis.settings import (
    BIC_THRESHOLD,
    EXPLAINED_MAX_ERROR,
    INDISTINGUISHABLE_BIC,
    MIN_EXCESS_REMOVED,
)
from hybridtable.effects.registry import get_effect
from hybridtable.effects.spec import RigScale
from hybridtable.six_dof.audit6 import Audit6
from hybridtable.six_dof.compare6 import COMPONENTS
from hybridtable.six_dof.fit6 import Fit6
from hybridtable.six_dof.run6 import Run6

__all__ = [
    "COMPONENT_MAX_ERROR",
    "Diagnosis6",
    "Step6",
    "component_errors",
    "pooled_error",
    "public_entry",
]

#: The largest RMS replay error (noise levels) of one component of a model
#: that explains the runs.
COMPONENT_MAX_ERROR = 2.0


def pooled_error(errors: dict[str, float]) -> float:
    """The components' RMS errors pooled (each has as many ticks)."""
    return math.sqrt(sum(e * e for e in errors.values()) / len(errors))


def component_errors(runs: Sequence[Run6], residuals: np.ndarray) -> dict[str, float]:
    """Each component's RMS replay error over the runs, in noise levels."""
    sums = dict.fromkeys((c[0] for c in COMPONENTS), 0.0)
    counts = dict.fromkeys(sums, 0)
    start = 0
    for run in runs:
        for name, *_ in COMPONENTS:
            part = residuals[start : start + run.n]
            sums[name] += float(part @ part)
            counts[name] += run.n
            start += run.n
    return {k: math.sqrt(sums[k] / counts[k]) for k in sums}


@dataclass
class Step6:
    """One round of forward selection (``kind="round"``: every candidate's
    score, the chosen one), or the swap step (``"swap"``: every swap's
    score against the selection, the one that replaced it)."""

    ranking: list[dict]
    chosen: str | None
    why: str
    kind: str = "round"


@dataclass
class Diagnosis6:
    """The result of :func:`diagnose_runs6` (see the module)."""

    run_ids: list[str]
    candidates: list[str]
    nominal_errors: dict[str, float]
    selected: list[str] = field(default_factory=list)
    fit: Fit6 | None = None
    final_errors: dict[str, float] = field(default_factory=dict)
    #: Each selected effect's look-alikes: the candidates of the round it
    #: entered in (or of the swaps of it) within
    #: :data:`~hybridtable.diagnosis.settings.INDISTINGUISHABLE_BIC` of it.
    lookalikes_of: dict[str, list[str]] = field(default_factory=dict)
    steps: list[Step6] = field(default_factory=list)
    fits: int = 0
    #: Candidates that cannot act on this rig, with why (e.g. the table's
    #: response on the Stewart platform, whose response is its reference model).
    refused: dict[str, str] = field(default_factory=dict)
    #: The audit of the rig computer's spacecraft (its findings are effects found).
    audit: Audit6 | None = None
    #: The scale the effects' bounds were taken at (the first run's scenario).
    scale: RigScale | None = None
    #: (selected effect, look-alike) -> the two models fitted: the one with
    #: the selected effect, the same with the look-alike in its place.
    pairs: dict[tuple[str, str], tuple[Fit6, Fit6]] = field(default_factory=dict, repr=False)
    #: Each selected effect's look-alikes' separating runs
    #: (:func:`~hybridtable.six_dof.design6.separation`, with ``effects``
    #: and ``hint``; ``run`` None and ``why`` where none was sought).
    separations: dict[str, list[dict]] = field(default_factory=dict)

    @property
    def lookalikes(self) -> list[str]:
        """The selected effects' look-alikes, each once."""
        names = (n for s in self.selected for n in self.lookalikes_of.get(s, ()))
        return list(dict.fromkeys(n for n in names if n not in self.selected))

    @property
    def found(self) -> list[str]:
        """Every effect found: the audit's, then the replay's selection."""
        return (self.audit.effects if self.audit is not None else []) + list(self.selected)

    @property
    def explained(self) -> bool:
        errors = self.final_errors
        return (
            pooled_error(errors) <= EXPLAINED_MAX_ERROR
            and max(errors.values()) <= COMPONENT_MAX_ERROR
        )

    @property
    def verdict(self) -> str:
        """``nothing missing``, ``found`` or ``not explained``."""
        if not self.found and self.explained:
            return "nothing missing"
        return "found" if self.explained else "not explained"

    def sentence(self) -> str:
        """The one-line verdict, with its evidence."""
        replay = self._replay_sentence()
        if self.audit is None or not self.audit.findings:
            return replay
        computer = self.audit.sentence()
        if self.verdict == "found" and not self.selected:
            return (
                f"found {computer}; the rig's physical part is the scenario's (replay error "
                f"{pooled_error(self.final_errors):.3g} noise levels pooled, largest component "
                f"{max(self.final_errors.values()):.3g})"
            )
        return f"{replay}; and {computer}"

    def _replay_sentence(self) -> str:
        worst0 = max(self.nominal_errors, key=self.nominal_errors.__getitem__)
        e0 = self.nominal_errors[worst0]
        worst = max(self.final_errors, key=self.final_errors.__getitem__)
        e1 = self.final_errors[worst]
        if self.explained and not self.selected:
            why = (
                "no effect fitted: none is needed"
                if not self.steps
                else "and no candidate is significant"
            )
            return (
                f"nothing is missing: the nominal model explains the runs (replay error "
                f"{pooled_error(self.nominal_errors):.3g} noise levels pooled, at most "
                f"{EXPLAINED_MAX_ERROR:g}; largest component {worst0} {e0:.3g}); {why}"
            )
        named = " + ".join(self.selected) if self.selected else "no candidate"
        values = self._values()
        if self.explained:
            alike = f"; look-alikes: {', '.join(self.lookalikes)}" if self.lookalikes else ""
            bounds = self.at_bounds()
            edge = f"; {', '.join(bounds)}: it may stand in for another effect" if bounds else ""
            return (
                f"found {named} ({values}): the worst component {worst0} falls from {e0:.3g} to "
                f"{self.final_errors[worst0]:.3g} noise levels, {pooled_error(self.final_errors):.3g} "
                f"pooled{alike}{edge}"
            )
        return (
            f"not explained: {named} is the best the library does ({values or 'no effect'}), "
            f"but {worst} is still {e1:.3g} noise levels off ({pooled_error(self.final_errors):.3g} "
            f"pooled; from {e0:.3g} for {worst0}): an effect outside the candidates, or a rig "
            "unlike its scenario"
        )

    def at_bounds(self) -> list[str]:
        """The selected effects' fitted parameters that ended at a bound, in
        words (:meth:`~hybridtable.effects.effect.Effect.at_bounds`)."""
        if self.fit is None or self.scale is None:
            return []
        return [
            f"{name}'s {said}"
            for name in self.selected
            for said in get_effect(name).at_bounds(self.fit.values[name], self.scale)
        ]

    def _values(self) -> str:
        if self.fit is None:
            return ""
        parts = []
        for name, values in self.fit.values.items():
            for k, v in values.items():
                s = self.fit.std[name].get(k)
                parts.append(f"{k} = {v:.4g}" + (f" +- {s:.2g}" if s is not None else ""))
        return ", ".join(parts)

    def to_dict(self) -> dict:
        return {
            "verdict": self.verdict,
            "explained": self.explained,
            "sentence": self.sentence(),
            "runs": self.run_ids,
            "candidates": self.candidates,
            "selected": self.selected,
            "found": self.found,
            "audit": None if self.audit is None else self.audit.to_dict(),
            "fit": None if self.fit is None else self.fit.to_dict(),
            "nominal_errors": self.nominal_errors,
            "nominal_pooled_error": pooled_error(self.nominal_errors),
            "final_pooled_error": pooled_error(self.final_errors),
            "final_errors": self.final_errors,
            "error_unit": "RMS replay error / noise level, per component, over the runs",
            "lookalikes": self.lookalikes,
            "lookalikes_of": {s: self.lookalikes_of.get(s, []) for s in self.selected},
            "at_bounds": self.at_bounds(),
            "separating_runs": {s: self.separations.get(s, []) for s in self.selected},
            "rounds": [
                {"kind": s.kind, "ranking": s.ranking, "chosen": s.chosen, "why": s.why}
                for s in self.steps
            ],
            "fits": self.fits,
            "refused": self.refused,
            "thresholds": {
                "bic": BIC_THRESHOLD,
                "explained_max_error": EXPLAINED_MAX_ERROR,
                "component_max_error": COMPONENT_MAX_ERROR,
                "min_excess_removed": MIN_EXCESS_REMOVED,
                "indistinguishable_bic": INDISTINGUISHABLE_BIC,
            },
        }


def public_entry(entry: dict) -> dict:
    """A ranking entry as JSON (the fit's values, not the fit)."""
    out = {k: v for k, v in entry.items() if k != "fit"}
    if "fit" in entry:
        out["values"] = entry["fit"].values
        out["std"] = entry["fit"].std
    return out
