"""A scenario file (TOML): the rig in nested sections, one per component.

The 1-D loop (``hybridtable simulate --scenario FILE``) and the 6-DoF loop
(``hybridtable simulate6 FILE``, :mod:`hybridtable.six_dof.scenario`) read the
same sections, and the keys both have with the same rules (below, before the
``|``); each loop adds its own (after it: the 1-D loop's here, the 6-DoF
loop's in its module)::

    title = "..."                 # free text
    [spacecraft]   mass_kg or contact_frequency_hz (exactly one)
    [contact]      contact_stiffness_n_per_m (required) | contact_damping_n_s_per_m
    [approach]     initial_velocity_m_per_s, initial_gap_m
    [rig]          sample_rate_hz (none: a continuous rig computer), sensor_delay_s
                   | time_step_s (continuous: the largest step)
    [table]        response_hz (a number or "inf": an ideal table), damping_ratio
    [compensator]  name, lead_time_s, force_deadband_n | stiffness_n_per_m,
                   damping_n_s_per_m (what it believes: default the contact's),
                   clamp_nonnegative, contact_gate, passivity

Units are SI and in every key. A key left out takes the loop's default (for
the 1-D loop, the paper's Table 1 point where it has one:
:data:`hybridtable.limits.TABLE1_DEFAULTS`). Any other key, a wrong type or a
value out of range raises :class:`~hybridtable.errors.SpecError` in one line
naming the file, the section and the key.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from hybridtable.errors import ParameterError, SpecError
from hybridtable.laws.contact import mass_for_contact_frequency_kg
from hybridtable.limits import TABLE1_DEFAULTS
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "LOOP_SCENARIO_KEYS",
    "keyed",
    "load_loop_scenario",
    "number",
    "parse_loop_scenario",
    "read_scenario",
    "section",
    "spacecraft_mass_kg",
    "table_response_hz",
    "top_level",
]

#: The keys of each section of a 1-D scenario ("": the top level).
LOOP_SCENARIO_KEYS: dict[str, tuple[str, ...]] = {
    "": ("title", "spacecraft", "contact", "approach", "rig", "table", "compensator"),
    "spacecraft": ("mass_kg", "contact_frequency_hz"),
    "contact": ("contact_stiffness_n_per_m", "contact_damping_n_s_per_m"),
    "approach": ("initial_velocity_m_per_s", "initial_gap_m"),
    "rig": ("sample_rate_hz", "sensor_delay_s", "time_step_s"),
    "table": ("response_hz", "damping_ratio"),
    "compensator": (
        "name",
        "lead_time_s",
        "stiffness_n_per_m",
        "damping_n_s_per_m",
        "force_deadband_n",
        "clamp_nonnegative",
        "contact_gate",
        "passivity",
    ),
}


def read_scenario(path: str | Path) -> dict[str, Any]:
    """The parsed TOML of a scenario file (``SpecError``: unreadable, not TOML)."""
    from hybridtable._files import read_user_toml

    return read_user_toml(Path(path), SpecError)


def section(
    raw: Mapping[str, Any], name: str, keys: Mapping[str, tuple[str, ...]]
) -> dict[str, Any]:
    """Section ``name`` of ``raw`` (empty when absent), its keys among ``keys[name]``."""
    value = raw.get(name, {})
    if not isinstance(value, Mapping):
        raise SpecError(f"[{name}] must be a table (got {value!r})")
    allowed = keys[name]
    for key in value:
        if key not in allowed:
            raise SpecError(f"[{name}] unknown key {key!r} (known: {', '.join(allowed)})")
    return dict(value)


def top_level(raw: Mapping[str, Any], keys: Mapping[str, tuple[str, ...]]) -> str:
    """Check the top level's keys and return the title."""
    for key in raw:
        if key not in keys[""]:
            raise SpecError(f"unknown section or key {key!r} (known: {', '.join(keys[''])})")
    title = raw.get("title", "")
    if not isinstance(title, str):
        raise SpecError(f"title must be text (got {title!r})")
    return title


def number(section: str, key: str, value: Any) -> Any:
    """``value`` if it is a number (or a list, checked by its consumer)."""
    if isinstance(value, bool) or not isinstance(value, int | float | list):
        raise SpecError(f"[{section}] {key} must be a number (got {value!r})")
    return value


def keyed(section: str, key: str, build: Callable[[], Any]) -> Any:
    """``build()``, its ``ParameterError`` said as the section's (and key's)."""
    try:
        return build()
    except SpecError:
        raise
    except ParameterError as err:
        where = f"[{section}] {key}:" if key else f"[{section}]"
        raise SpecError(f"{where} {err}") from None


def spacecraft_mass_kg(spacecraft: dict[str, Any], stiffness_n_per_m: float) -> float:
    """The mass of ``[spacecraft]``: ``mass_kg``, or the one that gives
    ``contact_frequency_hz`` with the contact's stiffness (exactly one of them;
    the key is taken out of ``spacecraft``)."""
    if ("mass_kg" in spacecraft) == ("contact_frequency_hz" in spacecraft):
        raise SpecError("[spacecraft] give exactly one of mass_kg and contact_frequency_hz")
    if "mass_kg" in spacecraft:
        return number("spacecraft", "mass_kg", spacecraft.pop("mass_kg"))
    f = spacecraft.pop("contact_frequency_hz")
    if isinstance(f, bool) or not isinstance(f, int | float) or not f > 0 or math.isinf(f):
        raise SpecError(f"[spacecraft] contact_frequency_hz must be a number > 0 (got {f!r})")
    return mass_for_contact_frequency_kg(stiffness_n_per_m, f)


def table_response_hz(table: Mapping[str, Any]) -> float:
    """``[table] response_hz``: a number, or ``"inf"`` for an ideal table."""
    value = table["response_hz"]
    return number("table", "response_hz", math.inf if value == "inf" else value)


def _flag(section: str, key: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise SpecError(f"[{section}] {key} must be true or false (got {value!r})")
    return value


def parse_loop_scenario(raw: Mapping[str, Any], source: str = "<scenario>") -> HybridLoopParams:
    """:class:`~hybridtable.loop.params.HybridLoopParams` of a 1-D scenario's
    parsed TOML (``SpecError`` names ``source``, the section and the key)."""
    try:
        return _parse_loop(raw)
    except SpecError as err:
        raise SpecError(f"{source}: {err}") from None
    except ParameterError as err:
        raise SpecError(f"{source}: {err}") from None


def load_loop_scenario(path: str | Path) -> HybridLoopParams:
    """Read and check a 1-D scenario file (:func:`parse_loop_scenario`)."""
    return parse_loop_scenario(read_scenario(path), str(path))


#: Where each 1-D scenario key lands in HybridLoopParams (section, key) -> field.
_FIELDS: dict[tuple[str, str], str] = {
    ("contact", "contact_stiffness_n_per_m"): "contact_stiffness_n_per_m",
    ("contact", "contact_damping_n_s_per_m"): "contact_damping_n_s_per_m",
    ("approach", "initial_velocity_m_per_s"): "initial_velocity_m_per_s",
    ("approach", "initial_gap_m"): "initial_gap_m",
    ("rig", "sample_rate_hz"): "sample_rate_hz",
    ("rig", "sensor_delay_s"): "sensor_delay_s",
    ("rig", "time_step_s"): "time_step_s",
    ("table", "damping_ratio"): "table_damping_ratio",
    ("compensator", "name"): "compensator",
    ("compensator", "lead_time_s"): "lead_time_s",
    ("compensator", "stiffness_n_per_m"): "compensator_stiffness_n_per_m",
    ("compensator", "damping_n_s_per_m"): "compensator_damping_n_s_per_m",
    ("compensator", "force_deadband_n"): "force_deadband_n",
    ("compensator", "clamp_nonnegative"): "clamp_nonnegative",
    ("compensator", "contact_gate"): "contact_gate",
    ("compensator", "passivity"): "passivity",
}


def _parse_loop(raw: Mapping[str, Any]) -> HybridLoopParams:
    keys = LOOP_SCENARIO_KEYS
    top_level(raw, keys)
    sections = {name: section(raw, name, keys) for name in keys if name}
    # What the Table 1 point gives besides the contact and the mass (required).
    defaulted = ("sensor_delay_s", "table_response_hz", "table_damping_ratio")
    values: dict[str, Any] = {
        name: TABLE1_DEFAULTS[name] for name in (*defaulted, "initial_velocity_m_per_s")
    }
    for (name, key), field in _FIELDS.items():
        if key not in sections[name]:
            continue
        value = sections[name][key]
        if field in ("clamp_nonnegative", "passivity"):
            value = _flag(name, key, value)
        elif field in ("compensator", "contact_gate"):
            if not isinstance(value, str):
                raise SpecError(f"[{name}] {key} must be text (got {value!r})")
        else:
            value = number(name, key, value)
        values[field] = value
    if "response_hz" in sections["table"]:
        values["table_response_hz"] = table_response_hz(sections["table"])
    if "contact_stiffness_n_per_m" not in values:
        raise SpecError("[contact] contact_stiffness_n_per_m is required")
    mass = spacecraft_mass_kg(sections["spacecraft"], values["contact_stiffness_n_per_m"])
    try:
        return HybridLoopParams(spacecraft_mass_kg=mass, **values)
    except ParameterError as err:  # said as the key the file wrote
        where = {field: f"[{name}] {key}" for (name, key), field in _FIELDS.items()}
        where |= {"table_response_hz": "[table] response_hz", "spacecraft_mass_kg": "[spacecraft]"}
        text = str(err)
        field = next((f for f in sorted(where, key=len, reverse=True) if f in text), None)
        raise SpecError(f"{where[field]}: {text}" if field else text) from None
