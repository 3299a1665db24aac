"""A sweep spec: what a campaign runs (``hybridtable sweep SPEC.toml``).

A spec is a TOML file (``docs/sweeps.md`` has the whole format)::

    name = "delay_vs_table"          # used in reports
    seed = 7                         # Monte Carlo and noise seeds derive from it
    engine = "auto"                  # auto | diagram | fast
    metrics = ["cor", "peak_force_n"]
    compensators = ["none", "SDC", "MDC", "SDMDC"]   # an innermost axis
    scenario = "docking.toml"        # optional: a 6-DoF campaign on this scenario

    [base]                           # fixed inputs of every run
    contact_frequency_hz = 1.0

    [grid]                           # every combination of the axes
    sensor_delay_s = [0.001, 0.003, 0.005]
    table_response_hz = {start = 10.0, stop = 100.0, num = 5, scale = "log"}

    [[points]]                       # explicit rows, run at every grid cell
    contact_stiffness_n_per_m = 1e5

    [monte_carlo]
    samples = 100                    # draws, each run at every point and cell
    [monte_carlo.draw]
    initial_velocity_m_per_s = {distribution = "uniform", low = 0.05, high = 0.2}

Without ``scenario`` the runs are of the 1-D loop (:mod:`.inputs`); with it, of
the 6-DoF docking loop on that scenario (:mod:`.docking`: its inputs, and the
6-DoF metrics of :mod:`.metrics`).

The runs are every point x every sample x every grid cell (the last grid axis,
then ``compensators``, varying fastest). Each Monte Carlo sample is drawn once
and run at every point and cell, so compensators are compared on the same
draws. Run ``i``'s draws come from the seed and the sample's index, its own
seed (noise) from the seed and ``i``: no result depends on the worker, the
number of workers or the order of completion.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from hybridtable.errors import ParameterError, SpecError
from hybridtable.sweeps.distributions import Distribution, parse_distribution
from hybridtable.sweeps.inputs import CONFLICTS, INPUTS, NOISE_INPUTS, check_value
from hybridtable.sweeps.metrics import DEFAULT_DOCKING_METRICS, DEFAULT_METRICS, metrics_of
from hybridtable.sweeps.plan import ENGINES, MAX_RUNS, SPEC_FORMAT, SweepSpec, input_for

__all__ = ["load_spec", "parse_spec"]

#: Most values one grid range may generate.
_MAX_AXIS = 100_000

_TOP_KEYS = (
    "format",
    "name",
    "description",
    "seed",
    "engine",
    "metrics",
    "compensators",
    "model",
    "pade_order",
    "base",
    "grid",
    "points",
    "monte_carlo",
    "scenario",
)


def load_spec(path: str | Path) -> SweepSpec:
    """Read and check a spec file.

    Raises
    ------
    SpecError
        One line naming the file and the key (exit 2 on the command line).
    """
    from hybridtable._files import read_user_toml

    path = Path(path)
    raw = read_user_toml(path, SpecError)
    return parse_spec(raw, source=str(path), folder=path.parent)


def parse_spec(raw: Mapping[str, Any], source: str = "<spec>", folder: Path | None = None):
    """A :class:`SweepSpec` from a spec's parsed TOML (see :func:`load_spec`)."""
    try:
        return _parse(raw, source, folder or Path("."))
    except SpecError:
        raise
    except ParameterError as err:
        raise SpecError(f"{source}: {err}") from None


class _Key:
    """Prefixes a ParameterError raised inside with the key it concerns."""

    def __init__(self, key: str) -> None:
        self.key = key

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind, err, tb) -> bool:
        if kind is not None and issubclass(kind, ParameterError) and kind is not SpecError:
            raise ParameterError(f"{self.key}: {err}") from None
        return False


def _parse(raw: Mapping[str, Any], source: str, folder: Path) -> SweepSpec:
    if not raw:
        raise ParameterError(
            "the spec is empty (a wrong file, or one saved half way?); a spec of one run of "
            'the paper\'s Table 1 point is name = "..."'
        )
    unknown = [k for k in raw if k not in _TOP_KEYS]
    if unknown:
        raise ParameterError(
            f"unknown key {unknown[0]!r} (a spec has {', '.join(_TOP_KEYS)}; "
            "parameters go in [base], [grid], [[points]] or [monte_carlo.draw])"
        )
    if "format" in raw and raw["format"] != SPEC_FORMAT:
        raise ParameterError(f"format must be {SPEC_FORMAT!r} (got {raw['format']!r})")
    name = raw.get("name", Path(source).stem)
    if not isinstance(name, str) or not name.strip():
        raise ParameterError(f"name must be a non-empty string (got {name!r})")
    description = raw.get("description", "")
    if not isinstance(description, str):
        raise ParameterError("description must be a string")
    seed = raw.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ParameterError(f"seed must be a whole number 0..2^63-1 (got {seed!r})")
    engine = raw.get("engine", "auto")
    if engine not in ENGINES:
        raise ParameterError(f"engine must be one of {', '.join(ENGINES)} (got {engine!r})")
    scenario, scenario_path, docking_base = None, None, None
    if "scenario" in raw:
        from hybridtable.sweeps.docking import holds_frequency, read_base_scenario

        with _Key("scenario"):
            scenario, scenario_path, params = read_base_scenario(raw["scenario"], folder)
        docking_base = (params, holds_frequency(scenario))
    loop = "1d" if scenario is None else "six_dof"
    if loop == "six_dof":
        one_d = [k for k in ("model", "pade_order") if k in raw]
        if engine == "fast" or one_d:
            what = f"{one_d[0]} (the 1-D loop's)" if one_d else 'engine = "fast" (1-D only)'
            raise ParameterError(f"a 6-DoF campaign (scenario) runs the docking loop: no {what}")
    defaults = DEFAULT_METRICS if loop == "1d" else DEFAULT_DOCKING_METRICS
    metrics = _metrics(raw.get("metrics", list(defaults)), loop)
    pade_order = raw.get("pade_order", 3)
    if isinstance(pade_order, bool) or not isinstance(pade_order, int) or not 1 <= pade_order <= 10:
        raise ParameterError(f"pade_order must be a whole number 1..10 (got {pade_order!r})")

    where: dict[str, str] = {}
    check = _checker(loop, docking_base)

    def claim(name: str, key: str) -> None:
        if input_for(name, loop) is None:
            known = INPUTS if loop == "1d" else _docking_inputs()
            close = [n for n in known if name.split("_")[0] in n][:3]
            hint = f"; did you mean {' or '.join(close)}?" if close else ""
            raise ParameterError(f"{key}: unknown parameter {name!r}{hint} (see docs/sweeps.md)")
        if name in where:
            raise ParameterError(f"{key}: {name} is already given in {where[name]}")
        where[name] = key.split(".")[0].split("[")[0]

    base = []
    base_raw = _table(raw.get("base", {}), "base")
    for k, v in base_raw.items():
        claim(k, f"base.{k}")
        with _Key(f"base.{k}"):
            base.append((k, check(k, v)))

    grid = []
    for k, v in _table(raw.get("grid", {}), "grid").items():
        claim(k, f"grid.{k}")
        grid.append((k, _axis(k, v, check, loop)))
    if "compensators" in raw:
        claim("compensator", "compensators")
        axis = _axis("compensator", raw["compensators"], check, loop, "compensators")
        grid.append(("compensator", axis))

    points = _points(raw.get("points"), claim, check)

    samples, draws = 1, []
    if "monte_carlo" in raw:
        mc = _table(raw["monte_carlo"], "monte_carlo")
        bad = [k for k in mc if k not in ("samples", "draw")]
        if bad:
            raise ParameterError(f"monte_carlo.{bad[0]}: unknown key (it has samples and draw)")
        if "samples" not in mc:
            raise ParameterError("monte_carlo.samples: missing (how many draws)")
        samples = mc["samples"]
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            raise ParameterError(
                f"monte_carlo.samples: must be a whole number >= 1 (got {samples!r})"
            )
        for k, v in _table(mc.get("draw", {}), "monte_carlo.draw").items():
            key = f"monte_carlo.draw.{k}"
            claim(k, key)
            with _Key(key):
                dist = parse_distribution(v)
                kind = input_for(k, loop).kind
                if kind != "number" and dist.kind != "choice":
                    raise ParameterError(f"{k} is {kind}: only choice can draw it")
                if input_for(k, loop).whole and dist.kind != "choice":
                    raise ParameterError(f"{k} is a whole number: only choice can draw it")
                if kind == "number" and dist.kind == "choice":
                    dist = Distribution(
                        "choice",
                        values=tuple(check(k, x) for x in dist.values),
                        weights=dist.weights,
                    )
                else:
                    for x in dist.extremes():
                        check(k, x)
                    _check_tails(k, dist)
            draws.append((k, dist))

    if loop == "six_dof":
        from hybridtable.sweeps.docking import CONFLICTS as conflicts
    else:
        conflicts = CONFLICTS
    for a, b in conflicts:
        if a in where and b in where:
            raise ParameterError(
                f"{b} (in {where[b]}) and {a} (in {where[a]}) set the same quantity: give one"
            )
    model, model_path = _model(raw.get("model"), folder)
    spec = SweepSpec(
        name=name.strip(),
        seed=seed,
        engine=engine,
        metrics=metrics,
        base=tuple(base),
        grid=tuple(grid),
        points=points,
        samples=samples,
        draws=tuple(draws),
        model=model,
        model_path=model_path,
        pade_order=pade_order,
        description=description,
        scenario=scenario,
        scenario_path=scenario_path,
        source=source,
    )
    if spec.n_runs > MAX_RUNS:
        raise ParameterError(
            f"points x monte_carlo.samples x grid cells = {len(spec.points)} x {spec.samples} x "
            f"{spec.cells} = {spec.n_runs} runs, more than one spec may hold ({MAX_RUNS}); "
            "split the campaign"
        )
    if loop == "six_dof":
        from hybridtable.sweeps.docking import check_devices

        check_devices(docking_base[0], _values_of(spec, "geometry"), where)
        return spec
    _check_effects(where)
    effects = any("." in n for n in where)
    diagram_only = [n for n in NOISE_INPUTS if n in where]
    diagram_only += ["a model file"] if model is not None else []
    diagram_only += ["table_backend"] if "table_backend" in where else []
    diagram_only += ["effects"] if effects else []
    if spec.engine == "fast" and diagram_only:
        raise ParameterError(
            f'engine = "fast" cannot run {", ".join(diagram_only)}: use "auto" or "diagram"'
        )
    noisy = [n for n in NOISE_INPUTS if n in where]
    if noisy and (model is not None or effects):
        raise ParameterError(
            f"{', '.join(noisy)}: the noise inputs act on the nominal rig only, not with "
            + ("a model file" if model is not None else "effects")
            + " (run them as two specs)"
        )
    stewart_with = [x for x in diagram_only if x != "table_backend"]
    if "stewart" in _values_of(spec, "table_backend") and stewart_with:
        raise ParameterError(
            f"the stewart table runs the nominal contact and sensor: not with "
            f"{', '.join(stewart_with)} (sweep those on the second_order table)"
        )
    linear_less = [n for n in (*NOISE_INPUTS, "table_backend") if n in where]
    linear_less += (
        ["effects (a model file carries its effects into the margins)"] if effects else []
    )
    if spec.needs_margins and linear_less:
        raise ParameterError(
            f"margin metrics are of the linear loop; it has no {', '.join(linear_less)}"
        )
    return spec


def _values_of(spec: SweepSpec, name: str) -> set[Any]:
    """Every value ``name`` can take in ``spec``'s runs."""
    out = {v for k, v in spec.base if k == name}
    out |= {v for k, axis in spec.grid if k == name for v in axis}
    out |= {v for p in spec.points for k, v in p if k == name}
    out |= {v for k, d in spec.draws if k == name for v in d.extremes()}
    return out


def _check_effects(where: dict[str, str]) -> None:
    """Every parameter of an effect given, and no two effects changing the
    same part of the rig."""
    from hybridtable.effects.registry import get_effect

    given: dict[str, set[str]] = {}
    for name in where:
        effect, dot, parameter = name.partition(".")
        if dot:
            given.setdefault(effect, set()).add(parameter)
    effects = [get_effect(n) for n in given]
    for e in effects:
        missing = [p for p in e.parameter_names if p not in given[e.name]]
        if missing:
            raise ParameterError(
                f"{e.name}: give {', '.join(f'{e.name}.{p}' for p in missing)} too "
                "(nothing to fit an effect to in a sweep)"
            )
    for i, a in enumerate(effects):
        for b in effects[:i]:
            if a.conflicts_with(b):
                raise ParameterError(
                    f"{a.name} and {b.name} change the same part of the rig: give one"
                )


#: A normal draw may leave its input's plausible range with at most this
#: chance; a draw that does makes its run ``invalid`` (a row, with the reason).
_TAIL_CHANCE = 0.01


def _check_tails(name: str, dist: Distribution) -> None:
    """Refuse a normal that would draw outside ``name``'s plausible range more
    than once in a hundred (a Gaussian stiffness or velocity going negative):
    the user gives ``low`` and ``high`` (a truncated normal). The bounds given
    are already checked to lie in the range."""
    from hybridtable.limits import LIMITS

    if dist.kind != "normal" or name not in LIMITS:
        return
    from scipy.special import ndtr

    limit = LIMITS[name]
    chance = 0.0
    if dist.low is None:
        chance += float(ndtr((limit.low - dist.mean) / dist.std))
        if limit.smallest_nonzero is not None:  # (0, smallest) is refused too
            chance += float(ndtr((limit.smallest_nonzero - dist.mean) / dist.std)) - float(
                ndtr((limit.low - dist.mean) / dist.std)
            )
    if dist.high is None:
        chance += float(ndtr((dist.mean - limit.high) / dist.std))
    if chance > _TAIL_CHANCE:
        raise ParameterError(
            f"a normal with mean {dist.mean:g} and std {dist.std:g} draws outside the plausible "
            f"range of {name} ({limit.words()}) with chance {chance:.2g}: give low and high "
            "(a truncated normal)"
        )


def _table(value: Any, key: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ParameterError(f"{key}: must be a table of parameter = value (got {value!r})")
    return value


def _metrics(value: Any, loop: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        raise ParameterError(f"metrics: must be a non-empty list of names (got {value!r})")
    known = metrics_of(loop)
    for m in value:
        if m not in known:
            which = "a 6-DoF campaign's" if loop == "six_dof" else "a 1-D campaign's"
            raise ParameterError(f"metrics: unknown metric {m!r} ({which} are {', '.join(known)})")
    if len(set(value)) != len(value):
        raise ParameterError("metrics: a metric is listed twice")
    return tuple(value)


def _axis(name: str, value: Any, check, loop: str, key: str | None = None) -> tuple[Any, ...]:
    key = key or f"grid.{name}"
    if isinstance(value, Mapping):
        values = _range(name, value, key, loop)
    elif isinstance(value, list):
        values = value
    else:
        raise ParameterError(
            f"{key}: must be a list of values or a range {{start, stop, num, scale}} "
            f"(got {value!r})"
        )
    if not values:
        raise ParameterError(f"{key}: the axis is empty (give at least one value)")
    out = []
    for i, v in enumerate(values):
        with _Key(f"{key}[{i}]"):
            out.append(check(name, v))
    return tuple(out)


def _range(name: str, value: Mapping[str, Any], key: str, loop: str) -> list[float]:
    bad = [k for k in value if k not in ("start", "stop", "num", "scale")]
    if bad:
        raise ParameterError(f"{key}.{bad[0]}: unknown key (a range has start, stop, num, scale)")
    for k in ("start", "stop", "num"):
        if k not in value:
            raise ParameterError(f"{key}.{k}: missing (a range has start, stop, num, scale)")
    num = value["num"]
    if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= _MAX_AXIS:
        raise ParameterError(f"{key}.num: must be a whole number 1..{_MAX_AXIS} (got {num!r})")
    scale = value.get("scale", "linear")
    if scale not in ("linear", "log"):
        raise ParameterError(f"{key}.scale: must be linear or log (got {scale!r})")
    ends = []
    for k in ("start", "stop"):
        v = value[k]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ParameterError(f"{key}.{k}: must be a finite number (got {v!r})")
        ends.append(float(v))
    if input_for(name, loop).kind != "number":
        raise ParameterError(f"{key}: {name} is not a number; list its values")
    if scale == "log":
        if min(ends) <= 0.0:
            raise ParameterError(f"{key}: a log range needs start and stop > 0")
        return [float(x) for x in np.geomspace(ends[0], ends[1], num)]
    return [float(x) for x in np.linspace(ends[0], ends[1], num)]


def _points(value: Any, claim, check) -> tuple[tuple[tuple[str, Any], ...], ...]:
    if value is None:
        return ((),)
    if not isinstance(value, list) or not value:
        raise ParameterError("points: must be a non-empty array of tables ([[points]])")
    out = []
    keys0: list[str] | None = None
    for i, p in enumerate(value):
        p = _table(p, f"points[{i}]")
        if keys0 is None:
            keys0 = list(p)
            if not keys0:
                raise ParameterError("points[0]: empty (give at least one parameter)")
            for k in keys0:
                claim(k, f"points[0].{k}")
        elif sorted(p) != sorted(keys0):
            raise ParameterError(
                f"points[{i}]: has {', '.join(sorted(p))}; every point must give the same "
                f"parameters as points[0] ({', '.join(sorted(keys0))})"
            )
        row = []
        for k in keys0:
            with _Key(f"points[{i}].{k}"):
                row.append((k, check(k, p[k])))
        out.append(tuple(row))
    return tuple(out)


def _model(value: Any, folder: Path) -> tuple[dict[str, Any] | None, str | None]:
    if value is None:
        return None, None
    if not isinstance(value, str) or not value:
        raise ParameterError(f"model: must be the path of a model file (got {value!r})")
    from hybridtable._files import read_user_json
    from hybridtable.effects.model_reader import model_from_json

    path = Path(value) if Path(value).is_absolute() else folder / value
    with _Key("model"):
        data = read_user_json(path, ParameterError)
        model_from_json(data, str(path))
    return data, str(path)


def _docking_inputs():
    from hybridtable.sweeps.docking import docking_inputs

    return docking_inputs()


def _checker(loop: str, docking_base):
    """``check(name, value)`` of the spec's loop: the 1-D inputs' rules, or
    the 6-DoF base scenario built with the value."""
    if loop == "1d":
        return check_value
    from hybridtable.sweeps.docking import check_docking_value

    params, holds = docking_base

    def check(name: str, value: Any) -> Any:
        return check_docking_value(params, name, value, holds)

    return check
