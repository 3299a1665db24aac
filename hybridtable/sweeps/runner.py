"""One run of a campaign: its inputs -> the loop -> one row of results.

A run never raises: a loop that diverges is recorded as ``diverged``, one
that fails otherwise (no separation, over the simulation budget) as
``failed``, inputs that make no loop (a drawn value out of range, an
integration rule on a continuous computer) as ``invalid``, and anything else
as ``error`` with the exception's type; each with its one-line message and
NaN metrics. Rows are plain dicts of plain values, the same on any worker.
"""

from __future__ import annotations

import math
import time
from typing import Any

from hybridtable.errors import DivergenceError, ParameterError, SimulationError
from hybridtable.laws.separation import DIVERGED_FORCE_RATIO
from hybridtable.sweeps.inputs import NOISE_INPUTS, effect_values, loop_params, noise_params
from hybridtable.sweeps.metrics import MARGINS, METRICS, SIMULATION
from hybridtable.sweeps.plan import RunInputs, SweepSpec

__all__ = [
    "STATUSES",
    "ID_COLUMNS",
    "run_one",
    "run_many",
    "blank_row",
    "empty_metrics",
    "row_problem",
]

#: What became of a run, best first.
STATUSES: tuple[str, ...] = ("ok", "diverged", "failed", "invalid", "error")

#: The columns before the inputs: the run's index, point, sample and seed.
ID_COLUMNS: tuple[str, ...] = ("run", "point", "sample", "seed")

# Per-process caches: a worker builds these once per campaign.
_MODELS: dict[str, Any] = {}
_LINEAR: dict[tuple[int, bool], Any] = {}
_SCENARIOS: dict[str, Any] = {}


def empty_metrics(spec: SweepSpec) -> dict[str, Any]:
    """The metric columns of a run that produced none (NaN; None for flags)."""
    return {m: (None if METRICS[m].kind == "bool" else math.nan) for m in spec.metrics}


def blank_row(spec: SweepSpec, inputs: RunInputs) -> dict[str, Any]:
    """A run's ids, swept inputs, ``compensator`` and empty metrics."""
    row: dict[str, Any] = {
        "run": inputs.index,
        "point": inputs.point,
        "sample": inputs.sample,
        "seed": inputs.seed,
    }
    for name in spec.swept:
        row[name] = inputs.values[name]
    row["compensator"] = inputs.values.get("compensator", "none")
    row.update(empty_metrics(spec))
    return row


#: The largest CoR and energy ratio a run that is ``ok`` can give: a loop
#: whose force passed DIVERGED_FORCE_RATIO times its undamped peak diverged.
_MOST_COR = {"cor": DIVERGED_FORCE_RATIO, "energy_ratio": DIVERGED_FORCE_RATIO**2}


def row_problem(spec: SweepSpec, row: dict[str, Any]) -> str | None:
    """Why a row read back from a campaign's file cannot be kept as run
    ``row["run"]`` of ``spec`` (``--resume``), or ``None``: a run outside the
    spec, a status that is none of :data:`STATUSES`, inputs that are not the
    spec's draw for that run, a run counted ``ok`` with a simulation metric
    that is not a finite number or an undecided ``stable``, or a run that is
    not ``ok`` with numbers."""
    index = row.get("run")
    if not isinstance(index, int) or not 0 <= index < spec.n_runs:
        return f"run {index!r} is not one of the spec's {spec.n_runs}"
    if row.get("status") not in STATUSES:
        return f"status {row.get('status')!r} is none of {', '.join(STATUSES)}"
    expected = blank_row(spec, spec.run_inputs(index))
    for name in ("point", "sample", "seed", *spec.swept, "compensator"):
        got, want = row.get(name), expected[name]
        same = got == want or (
            isinstance(got, float)
            and isinstance(want, float)
            and math.isnan(got)
            and math.isnan(want)
        )
        if not same:
            return f"{name} is {got!r}, not the spec's draw {want!r}"
    for name in spec.metrics:
        value, metric = row.get(name), METRICS[name]
        if row["status"] != "ok":
            if not (value is None or (isinstance(value, float) and math.isnan(value))):
                return f"a {row['status']} run with {name} = {value!r}"
        elif metric.kind == "bool":
            if not isinstance(value, bool):
                return f"an ok run with {name} = {value!r}"
        elif not isinstance(value, int | float) or (
            metric.source == SIMULATION and metric.finite and not math.isfinite(value)
        ):
            return f"an ok run with {name} = {value!r}"
        elif name in ("cor", "energy_ratio") and not 0.0 <= value <= _MOST_COR[name]:
            return f"an ok run with {name} = {value!r}, which no run gives"
    return None


def _model(spec: SweepSpec):
    if spec.model is None:
        return None
    key = spec.fingerprint()
    if key not in _MODELS:
        from hybridtable.effects.model_reader import model_from_json

        _MODELS[key] = model_from_json(spec.model, spec.model_path or "model")
    return _MODELS[key]


def _docking(spec: SweepSpec, inputs: RunInputs) -> dict[str, Any]:
    """The 6-DoF metrics of a run of a spec with a scenario."""
    from hybridtable.sweeps.docking import docking_params, holds_frequency, simulate_docking

    key = spec.fingerprint()
    if key not in _SCENARIOS:
        from hybridtable.six_dof.scenario import parse_scenario

        _SCENARIOS[key] = parse_scenario(spec.scenario, spec.scenario_path or "scenario")
    holds = holds_frequency(spec.scenario)
    params = docking_params(_SCENARIOS[key], inputs.values, inputs.seed, holds)
    return simulate_docking(params, ideal="energy_excess" in spec.metrics)


def _engine(spec: SweepSpec, params, values: dict[str, Any]) -> str:
    """``diagram`` or ``fast`` for this run; raises ParameterError when the
    spec demands the fast engine and it does not apply."""
    needs_diagram = (
        spec.model is not None
        or any(values.get(n, 0.0) for n in NOISE_INPUTS)
        or values.get("table_backend", "second_order") != "second_order"
        or bool(effect_values(values))
    )
    if spec.engine == "diagram" or needs_diagram:
        return "diagram"
    from hybridtable.loop.fast import fast_unsupported

    why = fast_unsupported(params)
    if why is None:
        return "fast"
    if spec.engine == "fast":
        raise ParameterError(f"the fast engine cannot run this: {why}")
    return "diagram"


def _simulate(spec: SweepSpec, params, values: dict[str, Any], seed: int, engine: str):
    """ContactMetrics of one run through the contact."""
    if engine == "fast":
        from hybridtable.loop.fast import simulate_fast

        return simulate_fast(params)
    if values.get("table_backend") == "stewart":
        from hybridtable.stewart.run import simulate_stewart

        return simulate_stewart(params, chirp=False).result.metrics
    model = _model(spec)
    added = effect_values(values)
    if added:
        return _simulate_effects(model, params, added).metrics
    if model is not None:
        from hybridtable.studies.model_compensators import simulate_model

        return simulate_model(model, params).metrics
    from hybridtable.loop.builder import build_hybrid_loop
    from hybridtable.loop.simulation import run_loop

    noise = noise_params(values, seed)
    compensator = None
    if noise is not None:
        from hybridtable.compensators.registry import make_compensator
        from hybridtable.systems.noise import with_measurement_noise

        period = build_hybrid_loop(params, log=False).computer_period_s
        # add_hybrid_loop wraps it in the passivity guard when params.passivity.
        inner = make_compensator(params.with_(passivity=False), period)
        compensator = with_measurement_noise(inner, noise, period)
    return run_loop(build_hybrid_loop(params, compensator=compensator)).metrics


def _simulate_effects(model, params, added: dict[str, dict[str, float]]):
    """The run with the effects ``added`` (on top of the model's, if any):
    each effect's values checked against its bounds at this rig's scale."""
    from dataclasses import replace

    from hybridtable.effects.registry import build_spec, get_effect
    from hybridtable.effects.spec import RigScale
    from hybridtable.studies.model_compensators import simulate_physics

    if params.sample_rate_hz is None:
        raise ParameterError(
            "effects act on a sampled rig computer (the run format's): give sample_rate_hz"
        )
    scale = (
        model.scale if model is not None else RigScale.from_params(params, params.sample_period_s)
    )
    effects = [(e.effect, dict(e.values)) for e in model.effects] if model is not None else []
    for name, given in added.items():
        effect = get_effect(name)
        for e, _ in effects:
            if effect.conflicts_with(e):
                raise ParameterError(f"{name} and {e.name} change the same part of the rig")
        effects.append((effect, effect.check_values(given, scale)))
    model_spec = build_spec(effects, scale)
    physics = model_spec.physics(name="+".join(e.name for e, _ in effects))
    if model is not None and model.computer_for(None):
        physics = replace(physics, computer=model.computer_for(None))
    return simulate_physics(params, physics, model_spec.mass_ratio)


def _margins(spec: SweepSpec, params) -> dict[str, Any]:
    from hybridtable.analysis.margins import critical_sensor_delay, growth_of, loop_margins
    from hybridtable.analysis.sweep import check_supported, model_function

    check_supported(params, (params.compensator,))
    key = (spec.pade_order, params.sample_rate_hz is not None)
    if key not in _LINEAR:
        _LINEAR[key] = model_function(params, spec.pade_order)[0]
    linear = _LINEAR[key]
    model = _model(spec)
    if model is not None:
        from hybridtable.studies.model_compensators import model_transform

        transform = model_transform(model)

        def linear_model(p):
            return _LINEAR[key](transform(p))

        linear = linear_model
    m = loop_margins(linear(params), pm_method="fast")
    out: dict[str, Any] = {"stable": bool(m.stable)}
    for name in (
        "predicted_cor",
        "phase_margin_deg",
        "damping_ratio",
        "growth_rate_per_s",
        "energy_growth_per_contact",
        "effective_delay_s",
        "crossover_rad_per_s",
    ):
        out[name] = float(getattr(m, name))
    if "critical_sensor_delay_s" in spec.metrics:
        max_delay = max(0.25 / params.contact_frequency_hz, params.sensor_delay_s)
        out["critical_sensor_delay_s"] = float(
            critical_sensor_delay(growth_of(linear), params, max_delay_s=max_delay)
        )
    return out


def _run_1d(spec: SweepSpec, inputs: RunInputs, row: dict[str, Any]) -> None:
    """Fill ``row`` (its metrics and ``engine``) with a 1-D run."""
    values = inputs.values
    params = loop_params(values)
    if spec.needs_simulation:
        row["engine"] = _engine(spec, params, values)
        m = _simulate(spec, params, values, inputs.seed, row["engine"])
        found = m.to_dict()
        found["energy_ratio"] = m.cor**2
        for name in spec.metrics:
            if METRICS[name].source == SIMULATION:
                row[name] = float(found[name])
    if spec.needs_margins:
        found = _margins(spec, params)
        for name in spec.metrics:
            if METRICS[name].source == MARGINS:
                row[name] = found[name]


def run_one(spec: SweepSpec, index: int) -> dict[str, Any]:
    """The row of run ``index``: ids, swept inputs, ``compensator``, metrics,
    ``status``, ``message``, ``engine``, ``seconds``."""
    t0 = time.perf_counter()
    inputs = spec.run_inputs(index)
    row = blank_row(spec, inputs)
    status, message = "ok", ""
    row["engine"] = "" if spec.needs_simulation else "linear"
    try:
        if spec.loop == "six_dof":
            row["engine"] = "diagram"
            found = _docking(spec, inputs)
            for name in spec.metrics:
                row[name] = found[name]
        else:
            _run_1d(spec, inputs, row)
    except DivergenceError as err:
        status, message = "diverged", str(err)
    except SimulationError as err:
        status, message = "failed", str(err)
    except ParameterError as err:
        status, message = "invalid", str(err)
    except Exception as err:  # a run must never end the campaign
        status, message = "error", f"{type(err).__name__}: {err}"
    if status != "ok":
        row.update(empty_metrics(spec))
    row["status"] = status
    row["message"] = " ".join(message.split())[:500]
    row["engine"] = row.pop("engine")  # the column's place, after the message
    row["seconds"] = time.perf_counter() - t0
    return row


def run_many(spec: SweepSpec, indices: list[int]) -> list[dict[str, Any]]:
    """The rows of several runs (one task of the campaign)."""
    return [run_one(spec, i) for i in indices]
