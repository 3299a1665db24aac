"""The model of a six-axis rig as a file (``hybridtable-model6/1``): what
``diagnose`` or ``compare --add`` found on 6-DoF runs, carried into
``compare --model`` (other runs of the rig: does the model hold?) and
``simulate6 --model`` (the rig as found, under a new scenario).

A :class:`RigModel6` holds the scenario of the runs it was fitted to (their
JSON's ``scenario``, the nominal rig), the scale its effects' bounds were
taken at, the effects with their values, standard errors and which were
fitted (the 1-D model file's entries: :func:`~hybridtable.effects.model_file.effects_json`,
read back by :func:`~hybridtable.effects.model_reader.effect_from_json`),
the runs (id, CSV, SHA-256), the evidence and where it came from. An effect
of the rig computer the audit solved (``com_offset``, ``lead_time_error``,
``compensator_stiffness_error``) is one of the effects; the audit's other
findings (a mass, an inertia, a gain or a dead band of the compensation: the
6-DoF loop's computer cannot take them) are in the evidence. The file is JSON::

    {"format": "hybridtable-model6/1", "tool_version": "0.1.0",
     "created": "2026-11-29T01:00:00+00:00", "source": "diagnose",
     "description": "...", "scenario": {...}, "scale": {...},
     "effects": [{"name": "sensor_misalignment", "parameters": {...}}],
     "runs": [{"run_id": "run1", "csv": "...", "sha256": "..."}],
     "evidence": {...}}
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from hybridtable._files import read_user_json
from hybridtable.effects.model_file import (
    MODEL6_FORMAT,
    FittedEffect,
    created_now,
    csv_digest,
    describe_effects,
    effects_json,
    file_header,
    tool_version,
)
from hybridtable.effects.model_reader import (
    check_document,
    effects_from_json,
    provenance,
    runs_from_json,
    scale_from_json,
)
from hybridtable.effects.registry import effect_names, get_effect
from hybridtable.effects.spec import RigScale
from hybridtable.errors import ParameterError
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.physics6 import PHYSICAL_FIELDS, DockingPhysics, physics_with, rig_scale
from hybridtable.six_dof.scenario import parse_scenario

__all__ = [
    "MODEL6_FORMAT",
    "RigModel6",
    "fitted_effects",
    "load_model6",
    "model6_from_json",
    "model6_of_runs",
]

#: The scenario's quantities that say which rig a run is of (the model's
#: effects were fitted to that rig).
RIG_FIELDS: tuple[str, ...] = ("sample_period_s", *PHYSICAL_FIELDS)


@dataclass(frozen=True)
class RigModel6:
    """A six-axis rig's model: its scenario plus effects (see the module)."""

    scenario: Mapping[str, Any]
    scale: RigScale
    effects: tuple[FittedEffect, ...] = ()
    runs: tuple[Mapping[str, Any], ...] = ()
    source: str = "user"
    evidence: Mapping[str, Any] = field(default_factory=dict)
    tool_version: str = field(default_factory=tool_version)
    created: str = field(default_factory=created_now)

    @property
    def params(self) -> DockingLoopParams:
        """The loop of the model's scenario."""
        return parse_scenario(self.scenario, "the model's scenario")

    @property
    def effect_names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.effects)

    def physics(self) -> DockingPhysics:
        """The rig's physical part (and computer) with the model's effects."""
        return physics_with([(e.effect, dict(e.values)) for e in self.effects], self.scale)

    def rig_differences(self, params: Sequence[tuple[str, DockingLoopParams]]) -> list[str]:
        """Where the rigs of ``params`` (``(what, params)``, e.g. ``("run
        run1", ...)``) differ from the model's: its effects were fitted to
        another rig."""
        mine, out = self.params, []
        for what, p in params:
            diffs = [
                f"{k} {getattr(p, k):g} (model: {getattr(mine, k):g})"
                for k in RIG_FIELDS
                if not math.isclose(getattr(p, k), getattr(mine, k), rel_tol=1e-9)
            ]
            if diffs:
                out.append(f"{what} is of another rig than the model's: {', '.join(diffs)}")
        return out

    def describe(self) -> str:
        """One line: the effects and their values with standard errors."""
        return describe_effects(self.effects)

    def to_json(self) -> dict:
        return {
            **file_header(MODEL6_FORMAT, self),
            "scenario": copy.deepcopy(dict(self.scenario)),
            "scale": asdict(self.scale),
            "effects": effects_json(self.effects),
            "runs": [dict(r) for r in self.runs],
            "evidence": dict(self.evidence),
        }


def fitted_effects(fit: Any) -> list[FittedEffect]:
    """A :class:`~hybridtable.six_dof.fit6.Fit6`'s effects with their values,
    standard errors and the parameters fitted (None: none)."""
    if fit is None:
        return []
    return [
        FittedEffect(name, dict(values), dict(fit.std.get(name, {})), tuple(fit.fitted[name]))
        for name, values in fit.values.items()
    ]


def model6_of_runs(
    runs: Sequence[Any],
    effects: Sequence[FittedEffect],
    audit: Any,
    source: str,
    evidence: Mapping[str, Any] | None = None,
) -> RigModel6:
    """The model of the rig of ``runs`` (:class:`~hybridtable.six_dof.run6.Run6`):
    ``effects`` and the registered effects among the ``audit``'s findings
    (``com_offset``; when the runs are of one spacecraft), the audit's sentence
    and its other findings in the evidence."""
    if not runs:
        raise ParameterError("a model needs the runs it describes")
    effects = list(effects)
    left = []
    if audit is not None:
        scale = rig_scale(runs[0].params)
        # an audit's part of one group of runs (one spacecraft, one stated law) is
        # the model's: its findings the 6-DoF loop's computer takes, within their bounds
        for group in (audit.groups, audit.laws):
            for f in (f for g in group for f in g.findings):
                known = len(group) == 1 and f.effect in effect_names()
                known = known and get_effect(f.effect).apply6 is not None
                if known and f.effect not in (e.name for e in effects):
                    try:
                        get_effect(f.effect).check_values(f.values, scale)
                    except ParameterError as err:
                        left.append(f"{f.sentence} (not in the model: {err})")
                        continue
                    effects.append(
                        FittedEffect(f.effect, dict(f.values), dict(f.std), tuple(f.values))
                    )
                else:
                    left.append(f.sentence)
    records = []
    for r in runs:
        csv, sha256 = csv_digest(r.csv_path)
        records.append({"run_id": r.run_id, "csv": csv, "sha256": sha256})
    evidence = dict(evidence or {})
    if audit is not None:
        evidence["audit"] = audit.sentence()
        if left:
            evidence["audit_not_in_the_model"] = left
    return RigModel6(
        scenario=runs[0].scenario,
        scale=rig_scale(runs[0].params),
        effects=tuple(effects),
        runs=tuple(records),
        source=source,
        evidence=evidence,
    )


def model6_from_json(data: Any, where: str) -> RigModel6:
    """A 6-DoF model from its JSON document (``where`` names it in messages).

    Raises
    ------
    ParameterError
        One line naming ``where`` and the key at fault (a 1-D model file
        says so).
    """
    check_document(
        data,
        where,
        MODEL6_FORMAT,
        ("scenario", "scale", "effects"),
        {
            "hybridtable-model/": "a model of a 1-D rig ({fmt}); 6-DoF runs take a "
            f"{MODEL6_FORMAT} model (diagnose or compare --add on 6-DoF runs, --save-model)"
        },
        "6-DoF model file",
    )
    if not isinstance(data["scenario"], dict):
        raise ParameterError(f"{where}: key scenario must be an object (a scenario's sections)")
    parse_scenario(data["scenario"], f"{where}: scenario")  # checked here, once
    scale = scale_from_json(data["scale"], where)
    effects = effects_from_json(data["effects"], scale, where)
    for i, e in enumerate(effects):
        if e.effect.apply6 is None:
            raise ParameterError(
                f"{where}: effects[{i}] ({e.name}) acts on the 1-D loop only (no apply6)"
            )
    return RigModel6(
        scenario=data["scenario"],
        scale=scale,
        effects=effects,
        runs=tuple(runs_from_json(data, where)),
        **provenance(data),
    )


def load_model6(path: str | Path) -> RigModel6:
    """Read and check a 6-DoF model file (one line naming the file and the
    key at fault: :func:`model6_from_json`)."""
    return model6_from_json(read_user_json(path, ParameterError), str(path))
