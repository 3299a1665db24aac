"""The model of a rig as a file (``hybridtable-model/1``): what ``diagnose``
(:func:`~hybridtable.diagnosis.diagnose.model_from_diagnosis`) or ``compare
--add`` found, carried into ``simulate``, ``margins``, ``compensators``,
``compare`` and ``sweep``. It is the effect core's, not a front end's: the
effects with their values, standard errors and provenance, whichever front
end fitted them; a six-axis rig's model file (:mod:`~hybridtable.six_dof.model6`)
shares its entries (:func:`effects_json`, :func:`file_header`,
:func:`csv_digest`, and the reader's checks).

A :class:`RigModel` holds

- the nominal parameters of the rig (the runs' JSON: ``nominal``) and the
  scale the effects' bounds were taken at (``scale``);
- the effects with their values, standard errors and which values were
  fitted rather than given (``effects``);
- what the audit found the rig computer used where its JSON differs, for the
  whole rig (``computer``: the values every run shares) and per run;
- the runs it was fitted to (id, files, SHA-256 of the CSV, the measured CoR,
  their nominal parameters), where it came from, the evidence (verdict,
  errors), the tool version and the time it was written.

The file is JSON::

    {"format": "hybridtable-model/1", "tool_version": "0.1.0",
     "created": "2026-11-23T10:00:00+00:00", "source": "diagnose",
     "nominal": {...the run format's keys...}, "scale": {...},
     "effects": [{"name": "contact_damping",
                  "parameters": {"damping_n_s_per_m": {"value": 301.2,
                                  "std": 4.1, "unit": "N s/m", "fitted": true}}}],
     "computer": {}, "runs": [...], "evidence": {...}}

:func:`~hybridtable.effects.model_reader.load_model` reads it back,
checking every key.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from hybridtable.effects.effect import Effect
from hybridtable.effects.registry import build_spec, get_effect
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError
from hybridtable.measurement.phases import record_cor
from hybridtable.measurement.rig import RigPhysics, computer_with_model_mass
from hybridtable.measurement.run_format import Run, RunInfo

__all__ = [
    "MODEL_FORMAT",
    "MODEL6_FORMAT",
    "RIG_KEYS",
    "FittedEffect",
    "ModelRun",
    "RigModel",
    "tool_version",
    "created_now",
    "describe_effects",
    "file_header",
    "csv_digest",
    "effects_json",
]

#: Keys of the run format that describe the rig itself (not one run of it).
RIG_KEYS: tuple[str, ...] = (
    "sample_rate_hz",
    "spacecraft_mass_kg",
    "contact_stiffness_n_per_m",
    "sensor_delay_s",
    "table_natural_frequency_hz",
    "table_damping_ratio",
)

#: Value of the model file's ``format`` key.
MODEL_FORMAT = "hybridtable-model/1"

#: Value of a six-axis rig's model file's ``format`` key
#: (:mod:`hybridtable.six_dof.model6`).
MODEL6_FORMAT = "hybridtable-model6/1"


def created_now() -> str:
    """Now, as a model file's ``created`` (UTC, ISO 8601, to the second)."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def tool_version() -> str:
    """The installed hybridtable's version (``"unknown"`` when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("hybridtable")
    except PackageNotFoundError:
        return "unknown"


@dataclass(frozen=True)
class FittedEffect:
    """An effect of a model with its values (SI units).

    Attributes
    ----------
    name : str
        A registered effect.
    values : mapping
        Parameter -> value.
    std : mapping
        Parameter -> standard error (None: given, or not estimated).
    fitted : tuple of str
        The parameters fitted to the runs (the others were given).
    """

    name: str
    values: Mapping[str, float]
    std: Mapping[str, float | None] = field(default_factory=dict)
    fitted: tuple[str, ...] = ()

    @property
    def effect(self) -> Effect:
        return get_effect(self.name)


@dataclass(frozen=True)
class ModelRun:
    """A run a model was fitted to."""

    run_id: str
    nominal: RunInfo
    computer: Mapping[str, Any] = field(default_factory=dict)
    cor_measured: float | None = None
    csv: str | None = None
    sha256: str | None = None


@dataclass(frozen=True)
class RigModel:
    """A rig's model: the nominal parameters plus effects (see the module doc)."""

    nominal: RunInfo
    scale: RigScale
    effects: tuple[FittedEffect, ...] = ()
    computer: Mapping[str, Any] = field(default_factory=dict)
    runs: tuple[ModelRun, ...] = ()
    source: str = "user"
    evidence: Mapping[str, Any] = field(default_factory=dict)
    tool_version: str = field(default_factory=tool_version)
    created: str = field(default_factory=created_now)

    # -- building ----------------------------------------------------------
    @classmethod
    def from_runs(
        cls,
        runs: Sequence[Run],
        effects: Sequence[FittedEffect],
        computer: Mapping[str, Mapping[str, Any]] | None = None,
        source: str = "user",
        evidence: Mapping[str, Any] | None = None,
    ) -> RigModel:
        """The model of the rig of ``runs`` with ``effects``; ``computer``
        maps run ids to the audit's changes of the rig computer."""
        if not runs:
            raise ParameterError("a model needs the runs it describes")
        computer = {k: dict(v) for k, v in (computer or {}).items()}
        per_run = [computer.get(r.run_id, {}) for r in runs]
        shared = {
            k: v for k, v in per_run[0].items() if all(k in c and c[k] == v for c in per_run[1:])
        }
        model_runs = []
        for r, c in zip(runs, per_run, strict=True):
            try:
                cor, _, _ = record_cor(r)
            except ValueError:
                cor = None
            model_runs.append(ModelRun(r.run_id, r.info, c, cor, *csv_digest(r.csv_path)))
        return cls(
            nominal=runs[0].info,
            scale=RigScale.from_runs(runs),
            effects=tuple(effects),
            computer=shared,
            runs=tuple(model_runs),
            source=source,
            evidence=dict(evidence or {}),
        )

    # -- using ---------------------------------------------------------------
    @property
    def effect_names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.effects)

    def spec(self) -> ModelSpec:
        """The :class:`~hybridtable.effects.effect.ModelSpec` of the effects."""
        return build_spec([(e.effect, dict(e.values)) for e in self.effects], self.scale)

    def computer_for(self, run_id: str | None = None) -> dict[str, Any]:
        """The rig computer's changes for run ``run_id`` (one the model was
        fitted to), else those every run shared."""
        for r in self.runs:
            if r.run_id == run_id:
                return dict(r.computer)
        return dict(self.computer)

    def physics(self, run_id: str | None = None, name: str = "model") -> RigPhysics:
        """The :class:`~hybridtable.measurement.rig.RigPhysics` of the model
        (its effects, and the rig computer as the audit found it, with the mass
        it found the computer integrating with, if any). The ``mass_error``
        ratio is not in it: the closed loop takes it from
        :meth:`closed_loop_run`."""
        physics = self.spec().physics(name=name)
        computer = self.computer_for(run_id)
        return replace(physics, computer=computer) if computer else physics

    def linear_params(self, params: Any, keep_compensator: bool = True) -> tuple[Any, list[str]]:
        """``params`` (a :class:`~hybridtable.loop.params.HybridLoopParams`)
        with the model's physics as the linear models see it
        (:meth:`~hybridtable.effects.effect.ModelSpec.linear_changes`), the
        compensator's beliefs left at their nominal values, and the rig
        computer as the audit found it (its compensator kind only when
        ``keep_compensator`` is false) integrating with the mass of
        :func:`~hybridtable.measurement.rig.computer_with_model_mass` (the
        audited one, else the ``mass_error`` ratio times ``params``' mass: the
        closed loop's rule). Also returns what the linear models leave out, in
        words."""
        spec = self.spec()
        changes, left = spec.linear_changes(params)
        computer = computer_with_model_mass(
            self.computer_for(None), params.spacecraft_mass_kg, spec.mass_ratio
        )
        if keep_compensator:
            computer.pop("compensator", None)
        return RigPhysics(changes=changes, computer=computer, loop=spec.loop).apply(params), left

    def closed_loop_run(self, run: Run) -> Run:
        """``run`` with the spacecraft mass the model's computer integrates with
        (:func:`~hybridtable.measurement.rig.run_with_model_mass` of the
        ``mass_error`` ratio); an audited mass in :meth:`physics` replaces it."""
        return self.spec().closed_loop_run(run)

    def rig_differences(self, runs: Sequence[Run]) -> list[str]:
        """Where the rig of ``runs`` differs from the model's (its nominal
        physics and rate): the model's effects were fitted to another rig."""
        out = []
        for r in runs:
            diffs = [
                f"{k} {getattr(r.info, k):g} (model: {getattr(self.nominal, k):g})"
                for k in RIG_KEYS
                if not math.isclose(getattr(r.info, k), getattr(self.nominal, k), rel_tol=1e-9)
            ]
            if diffs:
                out.append(f"run {r.run_id} is of another rig than the model's: {', '.join(diffs)}")
        return out

    def describe(self) -> str:
        """One line: the effects and their values with standard errors."""
        parts = [describe_effects(self.effects)]
        if self.computer:
            parts.append(
                "rig computer: " + ", ".join(f"{k} = {v}" for k, v in self.computer.items())
            )
        return "; ".join(parts)

    # -- the file ------------------------------------------------------------
    def to_json(self) -> dict:
        return {
            **file_header(MODEL_FORMAT, self),
            "nominal": self.nominal.to_dict(),
            "scale": asdict(self.scale),
            "effects": effects_json(self.effects),
            "computer": dict(self.computer),
            "runs": [
                {
                    "run_id": r.run_id,
                    "csv": r.csv,
                    "sha256": r.sha256,
                    "cor_measured": r.cor_measured,
                    "computer": dict(r.computer),
                    "nominal": r.nominal.to_dict(),
                }
                for r in self.runs
            ],
            "evidence": dict(self.evidence),
        }


def file_header(fmt: str, model: Any) -> dict:
    """The first keys of a model file of format ``fmt`` (1-D or six-axis):
    where ``model`` came from and its one-line description."""
    return {
        "format": fmt,
        "tool_version": model.tool_version,
        "created": model.created,
        "source": model.source,
        "description": model.describe(),
    }


def csv_digest(path: str | Path | None) -> tuple[str | None, str | None]:
    """A run's CSV as a model file names it: its path and SHA-256 (None, None: no file)."""
    if not path:
        return None, None
    return str(path), hashlib.sha256(Path(path).read_bytes()).hexdigest()


def describe_effects(effects: Sequence[FittedEffect]) -> str:
    """The effects and their values with standard errors and units, one
    clause an effect ("the nominal model (no effect)" without one)."""
    if not effects:
        return "the nominal model (no effect)"
    parts = []
    for e in effects:
        units = {p.name: p.unit for p in e.effect.parameters}
        vals = []
        for k, v in e.values.items():
            s = e.std.get(k)
            err = f" +- {s:.3g}" if s is not None else ""
            unit = "" if units.get(k, "1") == "1" else f" {units[k]}"
            tag = "" if k in e.fitted else " (given)"
            vals.append(f"{k} = {v:.6g}{err}{unit}{tag}")
        parts.append(f"{e.name}: {', '.join(vals)}")
    return "; ".join(parts)


def effects_json(effects: Sequence[FittedEffect]) -> list[dict]:
    """The model file's ``effects``: each effect's name, description and
    parameters (value, standard error, unit, fitted or given)."""
    out = []
    for e in effects:
        units = {p.name: p.unit for p in e.effect.parameters}
        out.append(
            {
                "name": e.name,
                "description": e.effect.description,
                "parameters": {
                    k: {
                        "value": float(v),
                        "std": e.std.get(k),
                        "unit": units.get(k, ""),
                        "fitted": k in e.fitted,
                    }
                    for k, v in e.values.items()
                },
            }
        )
    return out
