"""Every compensator on the rig as a model file describes it
(``hybridtable compensators --model``), and the loop of a modelled rig.

The rig of a :class:`~hybridtable.effects.model_file.RigModel`: its sampled
rig computer (:func:`~hybridtable.measurement.rig.rig_params` of its nominal
run: clamp, gate, dead band, sample rate), at each approach velocity of the
runs the model was fitted to (or the nominal one), with the model's physics:
the effects' Drake systems, the rig computer as the audit found it, the mass
the spacecraft model integrates with (:func:`simulate_model`);
:func:`model_transform` is the same rig as the linear models of
:mod:`hybridtable.analysis` see it (``margins --model``).

Every registered compensator runs on it, with and without the passivity
guard, against a reference at the same approach velocity: an ideal rig
(continuous loop, no sensor delay, ideal table, no compensation) with the
model's *contact* only (the ``contact`` part of the
:class:`~hybridtable.effects.effect.ModelSpec` and its contact wrappers).
A damped contact's own CoR is below 1, and the best compensator reproduces
it, not 1.

Metrics of a run, as in :mod:`hybridtable.studies.compensator_sweep`:

- ``cor_error``: CoR minus the reference CoR;
- ``peak_force_error``: peak actual contact force over the reference's, minus 1;
- ``energy_created``: the largest excess of the spacecraft's kinetic energy
  over its value before the contact, relative to it.

:func:`rank` orders compensator and guard by the largest ``|cor_error|`` over
the approach velocities (a failed run ranks last).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

__all__ = [
    "ModelCase",
    "ModelCompensatorResult",
    "model_physics",
    "model_loop_params",
    "physics_loop_params",
    "simulate_physics",
    "model_transform",
    "simulate_model",
    "rig_points",
    "reference_params",
    "reference_physics",
    "run_model_case",
    "run_model_compensators",
    "rank",
]


def model_physics(model, keep_compensator: bool = True):
    """The model's :class:`~hybridtable.measurement.rig.RigPhysics` (shared
    rig-computer changes); ``keep_compensator``: without the audit's
    compensator kind, so that the loop's own choice stays."""
    physics = model.physics()
    if keep_compensator and "compensator" in physics.computer:
        computer = {k: v for k, v in physics.computer.items() if k != "compensator"}
        physics = replace(physics, computer=computer)
    return physics


def physics_loop_params(params, physics, mass_ratio: float = 1.0):
    """``params`` as a rig with ``physics`` runs them: the physics' parameter
    changes and rig-computer changes, and the spacecraft mass the rig
    computer integrates with (the audited one in ``physics``, else ``params``'
    mass times ``mass_ratio``:
    :func:`~hybridtable.measurement.rig.computer_with_model_mass`)."""
    from hybridtable.measurement.rig import computer_with_model_mass

    q = physics.apply(params)  # the beliefs pinned for any compensator (with_physics)
    computer = computer_with_model_mass(physics.computer, params.spacecraft_mass_kg, mass_ratio)
    mass = computer.get("spacecraft_mass_kg", q.spacecraft_mass_kg)
    return q if mass == q.spacecraft_mass_kg else q.with_(spacecraft_mass_kg=mass)


def model_loop_params(model, params, physics=None, rig_computer: bool = True):
    """``params`` as the model's rig runs them (:func:`physics_loop_params`
    with the model's physics and, when ``rig_computer``, its mass ratio, as
    :meth:`~hybridtable.effects.model_file.RigModel.linear_params` has it)."""
    physics = physics or model_physics(model)
    return physics_loop_params(params, physics, model.spec().mass_ratio if rig_computer else 1.0)


def model_transform(model):
    """``params -> params`` with the model's physics as the linear models see
    it (:meth:`~hybridtable.effects.model_file.RigModel.linear_params`,
    the compensator kept). On a sampled rig an extra delay may put the sensor
    delay between two ticks, which the sampled model reads as the two
    neighbouring samples mixed, as the rig computer does."""

    def transform(p):
        return model.linear_params(p)[0]

    return transform


def simulate_physics(params, physics, mass_ratio: float = 1.0, **kwargs):
    """The nonlinear loop of ``params`` with ``physics`` (a
    :class:`~hybridtable.measurement.rig.RigPhysics`: its table, contact and
    sensor systems, its parameter and rig-computer changes) and the rig
    computer's ``mass_ratio``, run through one contact by
    :func:`~hybridtable.loop.simulation.run_loop` (``kwargs``).

    Raises
    ------
    SimulationError
        If the loop diverges or never separates.
    """
    from pydrake.systems.framework import DiagramBuilder

    from hybridtable.loop.builder import add_hybrid_loop
    from hybridtable.loop.simulation import run_loop

    q = physics_loop_params(params, physics, mass_ratio)
    builder = DiagramBuilder()
    loop = add_hybrid_loop(
        builder,
        q,
        table=physics.make_table(q),
        contact=physics.make_contact(q),
        sensor=physics.make_sensor(q),
    )
    loop.diagram = builder.Build()
    return run_loop(loop, **kwargs)


def simulate_model(model, params, physics=None, rig_computer: bool = True, **kwargs):
    """The nonlinear loop of ``params`` (a
    :class:`~hybridtable.loop.params.HybridLoopParams`, nominal physics) with
    the model's physics (:func:`simulate_physics`); ``physics`` replaces the
    model's (:func:`model_physics`); ``rig_computer=False`` leaves the
    spacecraft mass as ``params`` has it (a reference).

    Raises
    ------
    SimulationError
        If the loop diverges or never separates.
    """
    physics = physics or model_physics(model)
    ratio = model.spec().mass_ratio if rig_computer else 1.0
    return simulate_physics(params, physics, ratio, **kwargs)


def rig_points(model) -> list:
    """The model's nominal :class:`~hybridtable.measurement.run_format.RunInfo`
    at each distinct approach velocity of its runs (the nominal one if it
    lists no runs), slowest first."""
    velocities = sorted({r.nominal.initial_velocity_m_per_s for r in model.runs}) or [
        model.nominal.initial_velocity_m_per_s
    ]
    return [replace(model.nominal, initial_velocity_m_per_s=v) for v in velocities]


def reference_params(info):
    """The ideal rig of ``info``: continuous loop, no delay, ideal table, no
    compensation, the run's spacecraft mass and approach."""
    from hybridtable.measurement.rig import rig_params

    return rig_params(info).with_(
        compensator="none",
        sensor_delay_s=0.0,
        table_response_hz=math.inf,
        sample_rate_hz=None,
        force_deadband_n=0.0,
    )


def reference_physics(model):
    """The model's contact alone (its ``ModelSpec.contact`` and contact
    wrappers) as a :class:`~hybridtable.measurement.rig.RigPhysics`."""
    from hybridtable.effects.spec import ModelSpec

    spec = model.spec()
    contact_only = ModelSpec(
        contact=spec.contact,
        wrappers=tuple((c, w) for c, w in spec.wrappers if c == "contact"),
    )
    return contact_only.physics(name="contact")


@dataclass(frozen=True)
class ModelCase:
    """One run: approach point, compensator (``"ideal"``: the reference), guard."""

    point: int
    compensator: str
    passivity: bool

    @property
    def is_reference(self) -> bool:
        return self.compensator == "ideal"

    @property
    def key(self) -> str:
        return self.compensator + (" +passivity" if self.passivity else "")


def _metrics(result) -> dict[str, Any]:
    m = result.metrics
    ke_in = 0.5 * m.v_in_m_per_s**2
    ke_max = float(np.max(0.5 * np.asarray(result.v_des_m_per_s) ** 2))
    return {
        "cor": m.cor,
        "peak_force_n": m.peak_force_n,
        "v_in_m_per_s": m.v_in_m_per_s,
        "v_out_m_per_s": m.v_out_m_per_s,
        "energy_created": max(0.0, ke_max - ke_in) / ke_in,
        "steps": result.steps,
    }


def run_model_case(model, case: ModelCase) -> dict[str, Any]:
    """Run one case; a failed run is kept with its error and NaN metrics."""
    from hybridtable.errors import SimulationError

    info = rig_points(model)[case.point]
    out: dict[str, Any] = {
        "point": case.point,
        "initial_velocity_m_per_s": info.initial_velocity_m_per_s,
        "compensator": case.compensator,
        "passivity": case.passivity,
        "error": None,
    }
    try:
        if case.is_reference:
            result = simulate_model(
                model, reference_params(info), reference_physics(model), rig_computer=False
            )
        else:
            from hybridtable.measurement.rig import rig_params

            params = rig_params(info).with_(compensator=case.compensator, passivity=case.passivity)
            result = simulate_model(model, params)
    except SimulationError as err:
        out.update(cor=math.nan, peak_force_n=math.nan, energy_created=math.nan, error=str(err))
        return out
    out.update(_metrics(result))
    return out


@dataclass
class ModelCompensatorResult:
    """The runs of :func:`run_model_compensators` (dicts, JSON-ready)."""

    description: str
    compensators: tuple[str, ...]
    passivity: tuple[bool, ...]
    points: list[dict[str, Any]]
    references: list[dict[str, Any]]
    runs: list[dict[str, Any]]
    wall_time_s: float = 0.0
    figures: list[str] = field(default_factory=list)

    def ranking(self) -> list[dict[str, Any]]:
        return rank(self)

    def to_json(self) -> dict[str, Any]:
        from hybridtable.studies.run_json import run_json

        return {
            "compensators": list(self.compensators),
            "passivity": list(self.passivity),
            "points": self.points,
            "references": [run_json(r) for r in self.references],
            "runs": [run_json(r) for r in self.runs],
            "ranking": self.ranking(),
            "figures": self.figures,
            "wall_time_s": self.wall_time_s,
        }


def _run_indexed(item):
    index, model, case = item
    return index, run_model_case(model, case)


def run_model_compensators(
    model,
    compensators: Sequence[str] = (),
    passivity: Sequence[bool] = (False, True),
    jobs: int = 1,
    progress: bool = False,
) -> ModelCompensatorResult:
    """Run the references and every compensator (default: all registered)
    with each guard setting on the model's rig, at each of
    :func:`rig_points`; ``jobs`` worker processes (forked, so that the
    plug-ins registered here are there too; one process where fork is not
    available).

    Raises
    ------
    ParameterError
        For a compensator that is not registered.
    """
    from tqdm import tqdm

    from hybridtable.compensators.registry import compensator_names
    from hybridtable.errors import ParameterError

    t0 = time.perf_counter()
    names = compensator_names()
    comps = tuple(compensators) or names
    for c in comps:
        if c not in names:
            raise ParameterError(f"compensator must be one of {', '.join(names)} (got {c!r})")
    guards = tuple(bool(g) for g in passivity) or (False,)
    infos = rig_points(model)
    refs = [ModelCase(i, "ideal", False) for i in range(len(infos))]
    cases = [ModelCase(i, c, g) for i in range(len(infos)) for c in comps for g in guards]
    items = [(i, model, c) for i, c in enumerate(refs + cases)]
    results: list[dict[str, Any] | None] = [None] * len(items)
    bar = tqdm(total=len(items), desc="compensators", unit="run", disable=not progress)
    import multiprocessing

    if jobs > 1 and "fork" in multiprocessing.get_all_start_methods():
        from concurrent.futures import ProcessPoolExecutor

        ctx = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            for i, r in pool.map(_run_indexed, items):
                results[i] = r
                bar.update(1)
    else:
        for item in items:
            i, r = _run_indexed(item)
            results[i] = r
            bar.update(1)
    bar.close()
    ref_runs = results[: len(refs)]
    runs = results[len(refs) :]
    for r in runs:
        ref = ref_runs[r["point"]]
        r["cor_reference"] = ref["cor"]
        r["cor_error"] = r["cor"] - ref["cor"]
        r["peak_force_error"] = r["peak_force_n"] / ref["peak_force_n"] - 1.0
    points = [
        {
            "initial_velocity_m_per_s": info.initial_velocity_m_per_s,
            "cor_reference": ref["cor"],
            "peak_force_reference_n": ref["peak_force_n"],
        }
        for info, ref in zip(infos, ref_runs, strict=True)
    ]
    return ModelCompensatorResult(
        description=model.describe(),
        compensators=comps,
        passivity=guards,
        points=points,
        references=ref_runs,
        runs=runs,
        wall_time_s=time.perf_counter() - t0,
    )


def rank(result: ModelCompensatorResult) -> list[dict[str, Any]]:
    """Compensator and guard, best first, by the largest ``|cor_error|`` over
    the approach points (a failed run counts as infinite; ties keep the
    registry's order). Each entry holds the values of its worst point, the
    largest ``|peak_force_error|`` and ``energy_created`` over the points,
    and the number of failed runs."""
    by_key: dict[str, list[dict[str, Any]]] = {}
    for r in result.runs:
        by_key.setdefault(r["compensator"] + (" +passivity" if r["passivity"] else ""), []).append(
            r
        )
    entries = []
    for key, rs in by_key.items():
        failed = sum(r["error"] is not None for r in rs)

        def bad(x: float) -> float:
            return math.inf if not math.isfinite(x) else abs(x)

        worst = max(rs, key=lambda r: bad(r["cor_error"]))
        entries.append(
            {
                "key": key,
                "compensator": rs[0]["compensator"],
                "passivity": rs[0]["passivity"],
                "cor": worst["cor"],
                "cor_reference": worst["cor_reference"],
                "cor_error": worst["cor_error"],
                "max_abs_cor_error": bad(worst["cor_error"]),
                "initial_velocity_m_per_s": worst["initial_velocity_m_per_s"],
                "max_abs_peak_force_error": max(bad(r["peak_force_error"]) for r in rs),
                "max_energy_created": max(bad(r["energy_created"]) for r in rs),
                "failed": failed,
            }
        )
    entries.sort(key=lambda e: e["max_abs_cor_error"])  # stable: registry order on ties
    for i, e in enumerate(entries, 1):
        e["rank"] = i
    return entries
