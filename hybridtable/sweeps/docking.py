"""A 6-DoF campaign: what it varies and how one of its runs goes.

A spec that names a 6-DoF scenario (``scenario = "docking.toml"``, the file
``hybridtable simulate6`` reads) runs the docking loop
(:func:`~hybridtable.six_dof.simulation.simulate6`) at each of its runs: the
scenario is every run's base, and the spec's ``[base]``, grid, points and
draws change it by flat name. The inputs (:func:`docking_inputs`) are made
from :class:`~hybridtable.six_dof.params.DockingLoopParams` itself: every
quantity of its tree that is one number, word or flag, under its flat name
(``initial_velocity_m_per_s``, ``friction_coefficient``, ``sensor_delay_s``,
``compensator``...), and each component of its vectors
(:data:`COMPONENTS`: ``lateral_offset_x_m``, ``misalignment_pitch_rad``,
``angular_rate_y_rad_per_s``, ``inertia_z_kg_m2``...), plus two derived inputs as in 1-D:

- ``contact_frequency_hz`` sets the spacecraft's mass from the run's contact
  stiffness, ``m = k / (2 pi f)^2``; a scenario that gives
  ``[spacecraft] contact_frequency_hz`` holds that frequency while a campaign
  varies the stiffness (its mass follows, as the scenario says), one that
  gives ``mass_kg`` holds the mass;
- ``compensator_stiffness_ratio``: the stiffness the compensator believes over
  the run's true one.

The F/T noise's seed is the run's own seed. A run's values are checked by the
configs that take them (one rule per quantity, wherever it is set), and the
spec checks each value it gives against the base scenario before any run.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any, get_type_hints

from hybridtable.errors import ParameterError
from hybridtable.limits import LIMITS
from hybridtable.sweeps.inputs import CONFLICTS as ONE_D_CONFLICTS
from hybridtable.sweeps.inputs import INPUTS, Input, check_kind

DERIVED_NAMES = ("contact_frequency_hz", "compensator_stiffness_ratio")

__all__ = [
    "COMPONENTS",
    "DERIVED",
    "CONFLICTS",
    "docking_inputs",
    "docking_params",
    "check_docking_value",
    "check_devices",
    "read_base_scenario",
    "holds_frequency",
    "simulate_docking",
]

#: Vector quantities a campaign varies by component: name -> component names.
#: ``inertia_kg_m2``'s are the principal moments on the body axes (a scenario
#: with products of inertia cannot vary them one by one).
COMPONENTS: dict[str, tuple[str, ...]] = {
    "lateral_offset_m": ("x", "y"),
    "lateral_miss_m": ("x", "y"),
    "misalignment_rad": ("roll", "pitch"),
    "angular_rate_rad_per_s": ("x", "y", "z"),
    "inertia_kg_m2": ("x", "y", "z"),
}

#: Quantities a campaign does not vary: whole configs, the 6x6 matrix, and
#: the noise's seed (each run's own).
_NOT_INPUTS = ("spacecraft", "contact", "stewart", "compensator_stiffness_matrix", "seed")

#: Units by the ending of a quantity's name, longest first.
_UNITS: tuple[tuple[str, str], ...] = (
    ("_n_per_m", "N/m"),
    ("_s_per_m", "s/m"),
    ("_m_per_s", "m/s"),
    ("_rad_per_s", "rad/s"),
    ("_kg_m2", "kg m^2"),
    ("_n_m", "N m"),
    ("_kg", "kg"),
    ("_hz", "Hz"),
    ("_rad", "rad"),
    ("_s", "s"),
    ("_m", "m"),
    ("_n", "N"),
)

#: The derived inputs (see the module docstring): the 1-D campaign's.
DERIVED: dict[str, Input] = {n: INPUTS[n] for n in DERIVED_NAMES}

#: Pairs of inputs that set the same quantity: the 1-D campaign's pairs of a
#: derived input (the 6-DoF loop's contact has no damping ratio).
CONFLICTS: tuple[tuple[str, str], ...] = tuple(
    pair for pair in ONE_D_CONFLICTS if set(pair) & set(DERIVED_NAMES)
)


def _unit(name: str) -> str:
    if name in LIMITS:
        return LIMITS[name].unit
    for ending, unit in _UNITS:
        if name.endswith(ending):
            return unit
    return "1" if name.endswith(("_ratio", "_coefficient", "_count")) else ""


def _words(name: str, unit: str) -> str:
    for ending, u in _UNITS:
        if u == unit and name.endswith(ending):
            return name[: -len(ending)].replace("_", " ")
    return name.replace("_", " ")


def _leaf_type(path: tuple[str, ...]) -> Any:
    """The annotated type of the field at ``path`` in the params' tree."""
    from hybridtable.six_dof.params import DockingLoopParams

    kind: Any = DockingLoopParams
    hints = {name: cls for name, cls in DockingLoopParams.PARTS.items()}
    for key in path:
        kind = hints[key]
        hints = get_type_hints(kind) if hasattr(kind, "__dataclass_fields__") else {}
    return kind


@cache
def docking_inputs() -> dict[str, Input]:
    """Every input a 6-DoF spec may set, by name (see the module docstring)."""
    from hybridtable.six_dof.params import DockingLoopParams

    out: dict[str, Input] = {}
    for name, path in DockingLoopParams.FIELDS.items():
        if name in _NOT_INPUTS:
            continue
        unit = _unit(name)
        if name in COMPONENTS:
            for component, axis in zip(_component_names(name), COMPONENTS[name], strict=True):
                words = f"{_words(name, unit)} ({axis})"
                out[component] = Input(component, "number", unit, words)
            continue
        kind = _leaf_type(path)
        text = str(kind)
        if kind is bool or text == "bool":
            out[name] = Input(name, "bool", "", _words(name, unit))
        elif kind is str or text == "str":
            out[name] = Input(name, "text", "", _words(name, unit))
        else:
            whole = kind is int or text == "int"
            out[name] = Input(name, "number", unit or "1", _words(name, unit), whole)
    out.update(DERIVED)
    return out


def _unit_ending(name: str) -> str:
    """The unit part of a quantity's name (``lateral_offset_m`` -> ``_m``)."""
    for ending, _ in _UNITS:
        if name.endswith(ending):
            return ending
    return ""


def _component_names(vector: str) -> list[str]:
    """The inputs of a vector's components (``lateral_offset_m`` ->
    ``lateral_offset_x_m``, ``lateral_offset_y_m``)."""
    ending = _unit_ending(vector)
    stem = vector[: -len(ending)]
    return [f"{stem}_{axis}{ending}" for axis in COMPONENTS[vector]]


#: Each component's input -> its vector and index.
_COMPONENT_OF: dict[str, tuple[str, int]] = {
    name: (vector, i) for vector in COMPONENTS for i, name in enumerate(_component_names(vector))
}


def _choices(name: str) -> tuple[str, ...] | None:
    if name == "compensator":
        from hybridtable.six_dof.registry import wrench_compensator_names

        return tuple(wrench_compensator_names())
    if name == "table":
        from hybridtable.six_dof.params import TABLE_BACKENDS

        return TABLE_BACKENDS
    if name == "geometry":
        from hybridtable.six_dof.devices import GEOMETRIES

        return GEOMETRIES
    if name == "stiffness_model":
        from hybridtable.six_dof.params import STIFFNESS_MODELS

        return STIFFNESS_MODELS
    return None


def docking_params(base, values: dict[str, Any], seed: int, holds: bool = False):
    """The :class:`~hybridtable.six_dof.params.DockingLoopParams` of one run:
    ``base`` (the scenario's) with the run's ``values`` (inputs by name) and
    the noise seeded by ``seed``. ``holds``: the scenario gave the contact
    frequency, which a varied stiffness keeps (:func:`holds_frequency`).

    Raises
    ------
    ParameterError
        Naming the input whose value makes no loop.
    """
    from hybridtable.laws.contact import mass_for_contact_frequency_kg

    changes: dict[str, Any] = {}
    vectors: dict[str, list[float]] = {}
    for name, value in values.items():
        if name in DERIVED:
            continue
        component = _COMPONENT_OF.get(name)
        if component is None:
            changes[name] = value
            continue
        vector, i = component
        if vector not in vectors:
            current = getattr(base, vector)
            if vector == "inertia_kg_m2":
                matrix = [list(row) for row in current]
                if any(matrix[r][c] for r in range(3) for c in range(3) if r != c):
                    raise ParameterError(
                        f"{name}: the scenario's inertia_kg_m2 has products of inertia; "
                        "give its principal moments on the body axes to vary them"
                    )
                current = [matrix[j][j] for j in range(3)]
            vectors[vector] = [float(x) for x in current]
        vectors[vector][i] = float(value)
    changes.update({k: tuple(v) for k, v in vectors.items()})
    if "seed" not in changes:
        changes["seed"] = int(seed) % 2**63
    stiffness = changes.get("contact_stiffness_n_per_m", base.contact.contact_stiffness_n_per_m)
    frequency = values.get("contact_frequency_hz")
    varied = "contact_stiffness_n_per_m" in changes and "spacecraft_mass_kg" not in changes
    if frequency is None and holds and varied:
        frequency = base.contact_frequency_hz  # the scenario's, kept with the new stiffness
    if frequency is not None:
        changes["spacecraft_mass_kg"] = mass_for_contact_frequency_kg(
            float(stiffness), float(frequency)
        )
    ratio = values.get("compensator_stiffness_ratio")
    if ratio is not None:
        changes["compensator_stiffness_n_per_m"] = float(ratio) * float(stiffness)
    return base.with_(**changes)


def check_devices(base, geometries: set[str], where: dict[str, str]) -> None:
    """Refuse an input of the devices no run of the campaign docks with (the
    pads' with only a drogue, the drogue's with only the plate): it would
    vary nothing. ``geometries``: the values the spec gives ``geometry``
    (none: the base scenario's); ``where``: each input's table in the spec.

    Raises
    ------
    ParameterError
        Naming the input, its table and the geometry that reads it.
    """
    from hybridtable.six_dof.devices import DEVICE_FIELDS

    used = set(geometries) or {base.contact.geometry}
    for geometry, fields in DEVICE_FIELDS.items():
        for name in fields:
            if geometry not in used and name in where:
                raise ParameterError(
                    f"{name} (in {where[name]}) belongs to the {geometry}'s devices, and every "
                    f"run of this campaign docks with geometry {' or '.join(sorted(used))}: it "
                    "would vary nothing (give geometry as an input, or leave it out)"
                )


def holds_frequency(raw: dict[str, Any]) -> bool:
    """Whether a scenario's TOML gives the contact frequency (not the mass):
    a campaign varying the stiffness then keeps the frequency."""
    spacecraft = raw.get("spacecraft", {})
    return isinstance(spacecraft, dict) and "contact_frequency_hz" in spacecraft


def check_docking_value(base, name: str, value: Any, holds: bool = False) -> Any:
    """``value`` of input ``name`` as a spec gives it, checked by building the
    base scenario with it (a derived input with the quantity it sets;
    ``holds``: :func:`holds_frequency` of the scenario).

    Raises
    ------
    ParameterError
        One line: of the value's kind naming ``name``, else the config's
        own (the spec prefixes the key that gave the value).
    """
    spec = docking_inputs().get(name)
    if spec is None:
        raise ParameterError(f"unknown parameter {name!r}")
    check_kind(spec, value, _choices(name))
    if spec.kind == "number" and not math.isfinite(value) and name != "table_response_hz":
        raise ParameterError(f"{name} must be a finite number (got {value!r})")
    if name in DERIVED:
        from hybridtable.limits import check_plausible

        value = check_plausible(name, value)
    if spec.whole and value != int(value):
        raise ParameterError(f"{name} must be a whole number (got {value!r})")
    docking_params(base, {name: value}, 0, holds)  # the spec names the key: grid.NAME[i]
    if spec.whole:
        return int(value)
    return float(value) if spec.kind == "number" else value


def simulate_docking(params, ideal: bool = False) -> dict[str, Any]:
    """The metrics of one 6-DoF run by name (every 6-DoF metric of
    :data:`~hybridtable.sweeps.metrics.METRICS`; ``energy_excess`` only with
    ``ideal``: the same docking on the ideal rig is simulated too)."""
    from hybridtable.six_dof.simulation import simulate6

    run = simulate6(params)
    found: dict[str, Any] = run.metrics.to_dict()
    found["identified_stiffness_n_per_m"] = run.extra.get("identified_stiffness_n_per_m", math.nan)
    if ideal:
        reference = simulate6(params.ideal_rig()).metrics
        found["energy_excess"] = run.metrics.energy_ratio - reference.energy_ratio
    return found


def read_base_scenario(value: Any, folder):
    """A spec's ``scenario = "FILE.toml"`` (relative to the spec's ``folder``):
    its TOML, its path and its :class:`~hybridtable.six_dof.params.DockingLoopParams`.

    Raises
    ------
    ParameterError
        Not a path; SpecError: the file's own error, naming it and the key.
    """
    from pathlib import Path

    from hybridtable.errors import SpecError
    from hybridtable.loop.scenario import read_scenario
    from hybridtable.six_dof.scenario import parse_scenario

    if not isinstance(value, str) or not value:
        raise ParameterError(f"must be the path of a 6-DoF scenario file (got {value!r})")
    path = Path(value) if Path(value).is_absolute() else Path(folder) / value
    try:
        raw = read_scenario(path)
        return raw, str(path), parse_scenario(raw, str(path))
    except SpecError as err:  # said under the spec's key, as a model file's errors are
        raise ParameterError(str(err)) from None
