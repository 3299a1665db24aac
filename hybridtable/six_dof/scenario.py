"""A 6-DoF docking scenario file (TOML) -> :class:`DockingLoopParams`.

The sections, their shared keys and rules are the 1-D loop's
(:mod:`hybridtable.loop.scenario`); the 6-DoF loop adds its own keys.
Sections and keys (SI units; every key optional unless marked)::

    title = "..."                       # free text
    [spacecraft]   mass_kg | contact_frequency_hz (one of them, required),
                   inertia_kg_m2 (3 numbers or 3x3), port_distance_m,
                   lateral_offset_m = [x, y]
    [contact]      contact_stiffness_n_per_m (required), contact_dissipation_s_per_m,
                   friction_coefficient, geometry = "plate" | "cone";
                   plate: pad_count, ring_radius_m, pad_radius_m;
                   cone: cone_half_angle_rad, mouth_radius_m, throat_radius_m,
                   socket_depth_m, probe_radius_m
    [approach]     initial_velocity_m_per_s, initial_gap_m, misalignment_deg = [roll, pitch],
                   angular_rate_rad_per_s = [x, y, z] (body frame),
                   lateral_miss_m = [x, y]
    [rig]          sample_rate_hz, sensor_delay_s, force_noise_n, moment_noise_n_m,
                   position_noise_m, attitude_noise_rad (the table's encoders),
                   seed, duration_s
    [table]        backend = "model" | "stewart", response_hz (a number or "inf"),
                   damping_ratio
    [table.stewart]           StewartParams fields (not geometry or time_step_s:
                              the plant steps at the rig's tick)
    [table.stewart.geometry]  StewartGeometry fields
    [compensator]  name, lead_time_s, stiffness_model = "linearized" | "nominal" |
                   "given", stiffness_matrix (6x6), force_deadband_n,
                   stiffness_n_per_m (the contact stiffness it believes),
                   deadband_reading = "force_norm" | "axial_force",
                   clamp_nonnegative (true: the 1-D run format's clamp)

Any other key, a wrong type or a value out of range raises
:class:`~hybridtable.errors.SpecError` in one line naming the file and the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import Any

from hybridtable.errors import ParameterError, SpecError
from hybridtable.loop.scenario import (
    keyed,
    number,
    read_scenario,
    section,
    spacecraft_mass_kg,
    table_response_hz,
    top_level,
)
from hybridtable.six_dof.devices import DEVICE_FIELDS
from hybridtable.six_dof.params import (
    MAX_MISALIGNMENT_RAD,
    ApproachParams,
    DockingContactParams,
    DockingLoopParams,
    RigidBodyParams,
)

__all__ = ["load_scenario", "parse_scenario", "SCENARIO_KEYS"]

#: The keys of each section.
SCENARIO_KEYS: dict[str, tuple[str, ...]] = {
    "": ("title", "spacecraft", "contact", "approach", "rig", "table", "compensator"),
    "spacecraft": (
        "mass_kg",
        "contact_frequency_hz",
        "inertia_kg_m2",
        "port_distance_m",
        "lateral_offset_m",
    ),
    "contact": tuple(f.name for f in fields(DockingContactParams)),
    "approach": (
        "initial_velocity_m_per_s",
        "initial_gap_m",
        "misalignment_deg",
        "angular_rate_rad_per_s",
        "lateral_miss_m",
    ),
    "rig": (
        "sample_rate_hz",
        "sensor_delay_s",
        "force_noise_n",
        "moment_noise_n_m",
        "position_noise_m",
        "attitude_noise_rad",
        "seed",
        "duration_s",
    ),
    "table": ("backend", "response_hz", "damping_ratio", "stewart"),
    "compensator": (
        "name",
        "lead_time_s",
        "stiffness_model",
        "stiffness_matrix",
        "force_deadband_n",
        "stiffness_n_per_m",
        "deadband_reading",
        "clamp_nonnegative",
    ),
}


def load_scenario(path: str | Path, **overrides: Any) -> DockingLoopParams:
    """Read and check a scenario file; ``overrides`` replace fields of the
    result (e.g. ``compensator="SDC"``).

    Raises
    ------
    SpecError
        One line naming the file and the key.
    """
    return parse_scenario(read_scenario(path), str(path), **overrides)


def parse_scenario(raw: Mapping[str, Any], source: str = "<scenario>", **overrides: Any):
    """:class:`DockingLoopParams` from a scenario's parsed TOML."""
    try:
        params = _parse(raw)
        return params.with_(**overrides) if overrides else params
    except SpecError as err:
        raise SpecError(f"{source}: {err}") from None
    except ParameterError as err:
        raise SpecError(f"{source}: {err}") from None


def _parse(raw: Mapping[str, Any]) -> DockingLoopParams:
    top_level(raw, SCENARIO_KEYS)
    sc, ct, ap, rig, tb, cp = (
        section(raw, name, SCENARIO_KEYS)
        for name in ("spacecraft", "contact", "approach", "rig", "table", "compensator")
    )
    for name, values in (("spacecraft", sc), ("contact", ct), ("approach", ap), ("rig", rig)):
        for key, value in values.items():
            if key not in ("seed", "pad_count", "geometry"):
                number(name, key, value)
    _one_geometry(ct)
    if "contact_stiffness_n_per_m" not in ct:
        raise SpecError("[contact] contact_stiffness_n_per_m is required")
    contact = keyed("contact", "", lambda: DockingContactParams(**ct))
    sc["mass_kg"] = spacecraft_mass_kg(sc, contact.contact_stiffness_n_per_m)
    body = keyed("spacecraft", "", lambda: RigidBodyParams(**sc))
    if "misalignment_deg" in ap:
        value = ap.pop("misalignment_deg")
        if not isinstance(value, list) or len(value) != 2:
            raise SpecError(f"[approach] misalignment_deg must be [roll, pitch] (got {value!r})")
        degrees = [number("approach", "misalignment_deg", v) for v in value]
        if not all(isinstance(v, int | float) and math.isfinite(v) for v in degrees):
            raise SpecError(f"[approach] misalignment_deg must be 2 finite numbers (got {value!r})")
        ap["misalignment_rad"] = [math.radians(v) for v in degrees]
    try:
        approach = keyed("approach", "", lambda: ApproachParams(**ap))
    except SpecError as err:  # said in the file's own key and unit
        if "misalignment_rad" not in str(err) or "misalignment_rad" not in ap:
            raise
        raise SpecError(
            f"[approach] misalignment_deg must be within +-{math.degrees(MAX_MISALIGNMENT_RAD):.3g} "
            "deg per "
            f"axis (got {value!r})"
        ) from None
    kwargs: dict[str, Any] = dict(rig)
    if "backend" in tb:
        kwargs["table"] = tb["backend"]
    if "response_hz" in tb:
        kwargs["table_response_hz"] = table_response_hz(tb)
    if "damping_ratio" in tb:
        kwargs["table_damping_ratio"] = number("table", "damping_ratio", tb["damping_ratio"])
    if "stewart" in tb and kwargs.get("table") != "stewart":
        raise SpecError('[table.stewart] needs backend = "stewart"')
    if kwargs.get("table") == "stewart":
        # [table] response_hz / damping_ratio are the legs' reference model.
        stewart = dict(tb.get("stewart", {}))
        for key, field_name in (
            ("table_response_hz", "reference_response_hz"),
            ("table_damping_ratio", "reference_damping_ratio"),
        ):
            if key in kwargs and field_name not in stewart:
                value = kwargs[key]
                stewart[field_name] = None if value == math.inf else value
        kwargs["stewart"] = _stewart(stewart)
    renames = {
        "name": "compensator",
        "stiffness_matrix": "compensator_stiffness_matrix",
        "stiffness_n_per_m": "compensator_stiffness_n_per_m",
    }
    for key, value in cp.items():
        kwargs[renames.get(key, key)] = value
    return DockingLoopParams(spacecraft=body, contact=contact, approach=approach, **kwargs)


def _one_geometry(contact: Mapping[str, Any]) -> None:
    """Refuse the other geometry's device keys (a pad ring given to a cone
    is a mistake, not a default)."""
    geometry = contact.get("geometry", "plate")
    if geometry not in DEVICE_FIELDS:
        return  # the contact's own check names the choices
    for other, keys in DEVICE_FIELDS.items():
        if other == geometry:
            continue
        for key in keys:
            if key in contact:
                raise SpecError(
                    f"[contact] {key} describes the {other}'s devices, but geometry is {geometry!r}"
                )


def _stewart(value: Any):
    from hybridtable.stewart.geometry import StewartGeometry
    from hybridtable.stewart.params import StewartParams

    if not isinstance(value, Mapping):
        raise SpecError(f"[table.stewart] must be a table (got {value!r})")
    allowed = tuple(f.name for f in fields(StewartParams) if f.name not in ("time_step_s",))
    values = dict(value)
    for key in values:
        if key not in allowed:
            raise SpecError(f"[table.stewart] unknown key {key!r} (known: {', '.join(allowed)})")
    if "geometry" in values:
        geometry = values.pop("geometry")
        known = tuple(f.name for f in fields(StewartGeometry))
        if not isinstance(geometry, Mapping):
            raise SpecError("[table.stewart.geometry] must be a table")
        for key in geometry:
            if key not in known:
                raise SpecError(
                    f"[table.stewart.geometry] unknown key {key!r} (known: {', '.join(known)})"
                )
        values["geometry"] = keyed(
            "table.stewart.geometry", "", lambda: StewartGeometry(**geometry)
        )
    return keyed("table.stewart", "", lambda: StewartParams(**values))
