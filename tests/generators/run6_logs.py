"""Runs of the 6-DoF format ``hybridtable-run6/1``, good and bad, for testing
the library's reader and ``compare`` against data they did not make.

Written from ``docs/run6-format.md`` and ``docs/six_dof.md`` ("A scenario
file") alone: plain numpy and the standard library, the closed loop of the
independent generator :mod:`tests.generators.rig6`, and nothing from
``hybridtable``.

- :func:`scenario` is a nominal scenario (the ``"scenario"`` object of a run's
  JSON): Table 1's spacecraft and rig with a 10 mm lateral offset of the port
  and 2 deg of pitch, a ring of 8 pads on a plate, the table model at 25 Hz,
  no compensation.
- :func:`generate_run6` runs that scenario through ``rig6.simulate_rig6`` and
  returns the format's 33 columns (one contact, ending after the separation),
  with seeded white measurement noise on the logged F/T and table pose.
- :func:`write_run6` writes the CSV and JSON pair.
- :func:`corrupt` breaks one thing of a record, and says the words an error
  line about it should contain; :func:`write_corrupt_run6` writes the broken
  pair (the JSON's own defects too), :func:`message_names` checks a message.
- Hidden effects: ``generate_run6(..., hidden={effect: {parameter: value}})``
  runs a rig that does what its scenario (the JSON) does not say, by the laws
  of the library's effects or of effects outside it (``rig6.simulate_rig6``);
  :func:`truth_record` says what was hidden. :func:`replay_error6` measures
  how far the nominal model's replay of such a run is, per channel, in noise
  levels (and what is left once the library's effects, linearized, are
  projected off); :func:`size_effect6` scales an effect to a target by it;
  :func:`draw_set6` draws a rig, 1-3 approaches and the hidden effects of a
  set (null, single, pair, outside) and :func:`write_set6` writes it.

Conventions of the format (all vectors in W, the target's frame, ``+z`` the
docking axis towards the target): quaternions ``(qw, qx, qy, qz)``, Hamilton,
the rotation from the port's frame to W; the wrench is the one the contact
applies *to the spacecraft*, force and moment about the port origin, so a
head-on press has ``fz < 0``. ``rig6`` uses the same signs (its wrench is the
one on the chaser, ``fz = -k delta``) but orders it ``[moment; force]``; the
columns here are picked by name.
"""

from __future__ import annotations

import copy
import csv
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.generators import rig6

__all__ = [
    "CHANNELS",
    "COLUMNS",
    "CORRUPTIONS",
    "FORMAT",
    "JSON_CORRUPTIONS",
    "LIBRARY_EFFECTS",
    "OUTSIDE_EFFECTS",
    "SET_KINDS",
    "TARGET_RATIO",
    "Set6",
    "corrupt",
    "draw_approach6",
    "draw_rig6",
    "draw_set6",
    "generate_run6",
    "message_names",
    "quaternion_of_rotation_vector",
    "replay_error6",
    "rotation_vector_of_quaternion",
    "scenario",
    "size_effect6",
    "truth_record",
    "write_corrupt_run6",
    "write_run6",
    "write_set6",
]

#: The format's name, the JSON's ``"format"``.
FORMAT = "hybridtable-run6/1"

#: The format's columns, in the order of the document's table (33 of them).
COLUMNS: tuple[str, ...] = (
    "time_s",
    "px_des_m",
    "py_des_m",
    "pz_des_m",
    "qw_des",
    "qx_des",
    "qy_des",
    "qz_des",
    "vx_des_m_per_s",
    "vy_des_m_per_s",
    "vz_des_m_per_s",
    "wx_des_rad_per_s",
    "wy_des_rad_per_s",
    "wz_des_rad_per_s",
    "px_act_m",
    "py_act_m",
    "pz_act_m",
    "qw_act",
    "qx_act",
    "qy_act",
    "qz_act",
    "fx_mea_n",
    "fy_mea_n",
    "fz_mea_n",
    "mx_mea_n_m",
    "my_mea_n_m",
    "mz_mea_n_m",
    "fx_comp_n",
    "fy_comp_n",
    "fz_comp_n",
    "mx_comp_n_m",
    "my_comp_n_m",
    "mz_comp_n_m",
)

#: The kinds :func:`corrupt` makes, each one defect.
CORRUPTIONS: tuple[str, ...] = (
    "missing_column",
    "not_unit_quaternion",
    "quaternion_sign_flip",
    "degrees",
    "time_not_increasing",
    "nan_cell",
    "sign_flipped_velocity",
    "no_contact",
    "bad_format",
)

#: Kinds whose defect is in the JSON: the top-level keys written over the good ones.
JSON_CORRUPTIONS: dict[str, dict] = {"bad_format": {"format": "hybridtable-run6/2"}}

_XYZ = ("x", "y", "z")
_WXYZ = ("w", "x", "y", "z")

#: The nominal scenario (docs/six_dof.md, "A scenario file").
_NOMINAL: dict[str, dict] = {
    "spacecraft": {
        "contact_frequency_hz": 1.0,
        "inertia_kg_m2": [1689.0, 1689.0, 1689.0],
        "port_distance_m": 1.5,
        "lateral_offset_m": [0.01, 0.0],
    },
    "contact": {
        "geometry": "plate",
        "contact_stiffness_n_per_m": 1.0e5,
        "contact_dissipation_s_per_m": 0.0,
        "friction_coefficient": 0.0,
        "pad_count": 8,
        "ring_radius_m": 0.3,
        "pad_radius_m": 0.01,
    },
    "approach": {
        "initial_velocity_m_per_s": 0.1,
        "initial_gap_m": 0.001,
        "misalignment_deg": [0.0, 2.0],
        "angular_rate_rad_per_s": [0.0, 0.0, 0.0],
        "lateral_miss_m": [0.0, 0.0],
    },
    "rig": {
        "sample_rate_hz": 1000.0,
        "sensor_delay_s": 0.005,
        "force_noise_n": 0.0,
        "moment_noise_n_m": 0.0,
        "seed": 0,
    },
    "table": {"backend": "model", "response_hz": 25.0, "damping_ratio": 0.8},
    "compensator": {"name": "none"},
}


# --- the scenario -------------------------------------------------------------


def scenario(**overrides) -> dict:
    """A nominal scenario: the ``"scenario"`` object of a run's JSON.

    Sections ``spacecraft``, ``contact``, ``approach``, ``rig``, ``table`` and
    ``compensator`` with the keys of ``docs/six_dof.md`` ("A scenario file"):
    Table 1's spacecraft (contact frequency 1 Hz with 1e5 N/m, inertia 1689
    kg m^2 about each axis), the port 1.5 m ahead of the centre of mass and
    10 mm off its axis, 8 pads of 10 mm on a 0.3 m ring against a plate
    (``geometry = "plate"``), no dissipation or friction, an approach at
    0.1 m/s from 1 mm pitched by 2 deg, a 1 kHz rig computer with a 5 ms
    sensor delay, the table model at 25 Hz with damping 0.8, no compensator.

    Overrides, either form (applied in the order given):

    - ``"section.key"`` keys: ``scenario(**{"approach.initial_gap_m": 0.01})``;
    - a section name with a dict, merged into the section:
      ``scenario(table={"response_hz": "inf"}, rig={"sensor_delay_s": 0.0})``.

    A value ``None`` removes the key (``**{"spacecraft.contact_frequency_hz":
    None, "spacecraft.mass_kg": 2533.0}``). An unknown section is refused
    (``ValueError``); keys are not checked here (:func:`generate_run6` refuses
    those it cannot run).
    """
    out = copy.deepcopy(_NOMINAL)
    for name, value in overrides.items():
        if "." in name:
            section, key = name.split(".", 1)
            items = {key: value}
        else:
            section = name
            if not isinstance(value, Mapping):
                raise ValueError(f"override {name!r}: a section takes a dict, not {value!r}")
            items = dict(value)
        if section not in out:
            raise ValueError(f"override {name!r}: no section {section!r} (one of {list(out)})")
        for key, item in items.items():
            if item is None:
                out[section].pop(key, None)
            else:
                out[section][key] = copy.deepcopy(item)
    return out


#: The keys :func:`generate_run6` can run, per section.
_KNOWN_KEYS = {
    "spacecraft": {
        "contact_frequency_hz",
        "mass_kg",
        "inertia_kg_m2",
        "port_distance_m",
        "lateral_offset_m",
    },
    "contact": {
        "geometry",
        "contact_stiffness_n_per_m",
        "contact_dissipation_s_per_m",
        "friction_coefficient",
        "pad_count",
        "ring_radius_m",
        "pad_radius_m",
        *rig6.PAD_LAW_KEYS,  # the pad law's (docs/run6-format.md, "The pad law")
    },
    "approach": {
        "initial_velocity_m_per_s",
        "initial_gap_m",
        "misalignment_deg",
        "angular_rate_rad_per_s",
        "lateral_miss_m",
    },
    "rig": {"sample_rate_hz", "sensor_delay_s", "force_noise_n", "moment_noise_n_m", "seed"},
    "table": {"backend", "response_hz", "damping_ratio"},
    "compensator": {
        "name",
        "lead_time_s",
        "force_deadband_n",
        "stiffness_model",
        "stiffness_n_per_m",
    },
}


def _as_float(value, what: str) -> float:
    """A number of the scenario; ``"inf"`` (as the docs write an ideal table) is ``inf``."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity"):
        return math.inf
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{what}: {value!r} is not a number")
    return float(value)


def _rig6_arguments(scen: Mapping) -> tuple[dict, np.ndarray]:
    """``simulate_rig6``'s keyword arguments for a scenario, and the lateral miss (2,)."""
    for section in scen:
        if section not in _KNOWN_KEYS:
            raise ValueError(f"scenario: section {section!r} is not one rig6 can run")
        unknown = set(scen[section]) - _KNOWN_KEYS[section]
        if unknown:
            raise ValueError(f"scenario: [{section}] {sorted(unknown)}: rig6 cannot run them")
    sc = {**_NOMINAL["spacecraft"], **scen.get("spacecraft", {})}
    co = {**_NOMINAL["contact"], **scen.get("contact", {})}
    ap = {**_NOMINAL["approach"], **scen.get("approach", {})}
    rg = {**_NOMINAL["rig"], **scen.get("rig", {})}
    tb = {**_NOMINAL["table"], **scen.get("table", {})}
    cp = dict(scen.get("compensator", _NOMINAL["compensator"]))
    given = scen.get("spacecraft", {})
    if "mass_kg" in given and "contact_frequency_hz" not in given:
        sc.pop("contact_frequency_hz")  # the nominal's, replaced by the mass given

    if co.get("geometry", "plate") != "plate":
        raise ValueError(f"contact.geometry {co['geometry']!r}: rig6 has only the pads on a plate")
    if _as_float(co.get("friction_coefficient", 0.0), "friction_coefficient") != 0.0:
        raise ValueError("contact.friction_coefficient: rig6 has no friction; it must be 0")
    if tb.get("backend", "model") != "model":
        raise ValueError(f"table.backend {tb['backend']!r}: rig6 has only the table model")
    rate = np.asarray(ap.get("angular_rate_rad_per_s", [0.0, 0.0, 0.0]), dtype=float)
    if rate.shape != (3,) or rate.any():
        raise ValueError("approach.angular_rate_rad_per_s: rig6 starts without rotation; 0 only")
    for key in ("force_noise_n", "moment_noise_n_m"):
        if _as_float(rg.get(key, 0.0), key) != 0.0:
            raise ValueError(
                f"rig.{key}: rig6 has no noise inside the loop; use generate_run6's "
                "measurement noise"
            )
    name = str(cp.get("name", "none"))
    names = {c.lower(): c for c in rig6.COMPENSATORS}
    if name.lower() not in names:
        raise ValueError(f"compensator.name {name!r}: rig6 runs {rig6.COMPENSATORS}")
    if cp.get("stiffness_model", "linearized") != "linearized":
        raise ValueError("compensator.stiffness_model: rig6 linearizes at the table's pose only")

    k = _as_float(co["contact_stiffness_n_per_m"], "contact_stiffness_n_per_m")
    if "stiffness_n_per_m" in cp and _as_float(cp["stiffness_n_per_m"], "stiffness_n_per_m") != k:
        raise ValueError("compensator.stiffness_n_per_m: rig6's MDC believes the contact's")
    has_mass, has_freq = "mass_kg" in sc, "contact_frequency_hz" in sc
    if has_mass == has_freq:
        raise ValueError("spacecraft: give one of mass_kg and contact_frequency_hz")
    if has_mass:
        mass = _as_float(sc["mass_kg"], "mass_kg")
    else:
        mass = (
            k / (2.0 * math.pi * _as_float(sc["contact_frequency_hz"], "contact_frequency_hz")) ** 2
        )
    miss = np.asarray(ap.get("lateral_miss_m", [0.0, 0.0]), dtype=float)
    if miss.shape != (2,):
        raise ValueError("approach.lateral_miss_m: two numbers (x, y)")
    kwargs = {
        "mass_kg": mass,
        "inertia_kg_m2": np.asarray(sc["inertia_kg_m2"], dtype=float),
        "port_distance_m": _as_float(sc["port_distance_m"], "port_distance_m"),
        "lateral_offset_m": tuple(float(x) for x in sc["lateral_offset_m"]),
        "misalignment_rad": tuple(math.radians(float(x)) for x in ap["misalignment_deg"]),
        "contact_stiffness_n_per_m": k,
        "hunt_crossley_dissipation_s_per_m": _as_float(
            co["contact_dissipation_s_per_m"], "contact_dissipation_s_per_m"
        ),
        "pad_count": int(co["pad_count"]),
        "ring_radius_m": _as_float(co["ring_radius_m"], "ring_radius_m"),
        "pad_radius_m": _as_float(co["pad_radius_m"], "pad_radius_m"),
        **_pad_law_arguments(co),
        "table_response_hz": _as_float(tb["response_hz"], "response_hz"),
        "table_damping_ratio": _as_float(tb["damping_ratio"], "damping_ratio"),
        "sample_rate_hz": _as_float(rg["sample_rate_hz"], "sample_rate_hz"),
        "sensor_delay_s": _as_float(rg["sensor_delay_s"], "sensor_delay_s"),
        "compensator": names[name.lower()],
        "lead_time_s": None
        if "lead_time_s" not in cp
        else _as_float(cp["lead_time_s"], "lead_time_s"),
        "force_deadband_n": _as_float(cp.get("force_deadband_n", 0.0), "force_deadband_n"),
        "initial_velocity_m_per_s": _as_float(
            ap["initial_velocity_m_per_s"], "initial_velocity_m_per_s"
        ),
        "initial_gap_m": _as_float(ap["initial_gap_m"], "initial_gap_m"),
    }
    if len(kwargs["misalignment_rad"]) != 2:
        raise ValueError("approach.misalignment_deg: two angles (roll, pitch)")
    return kwargs, miss


def _pad_law_arguments(contact: Mapping) -> dict:
    """The pad law's ``[contact]`` keys (``rig6.PAD_LAW_KEYS``) as ``simulate_rig6``
    takes them: each the scenario's, or its default when absent (``reference_press_m``
    and ``normal_friction_velocity_m_per_s`` have none: ``None``, needed only with
    an exponent other than 1 or a friction force above 0); ``ValueError`` naming
    the key for a value out of its range (an exponent, reference press or
    friction velocity not above 0, a negative damping, compliance or force)."""
    out = {}
    for key, default in rig6.PAD_LAW_KEYS.items():
        value = contact.get(key, default)
        out[key] = None if value is None else _as_float(value, key)
        if out[key] is not None and not math.isfinite(out[key]):
            raise ValueError(f"contact.{key}: {out[key]} is not finite")
    for key in ("contact_exponent", "reference_press_m", "normal_friction_velocity_m_per_s"):
        if out[key] is not None and not out[key] > 0.0:
            raise ValueError(f"contact.{key}: {out[key]} must be above 0")
    for key in ("contact_damping_n_s_per_m", "series_compliance_m_per_n"):
        if out[key] < 0.0:
            raise ValueError(f"contact.{key}: {out[key]} must be at least 0")
    if out["normal_friction_force_n"] < 0.0:
        raise ValueError(
            f"contact.normal_friction_force_n: {out['normal_friction_force_n']} must be at least 0"
        )
    if out["contact_exponent"] != 1.0 and out["reference_press_m"] is None:
        raise ValueError("contact.reference_press_m: needed with a contact_exponent other than 1")
    if out["normal_friction_force_n"] > 0.0 and out["normal_friction_velocity_m_per_s"] is None:
        raise ValueError(
            "contact.normal_friction_velocity_m_per_s: needed with a normal_friction_force_n"
        )
    return out


# --- rotations ----------------------------------------------------------------


def quaternion_of_rotation_vector(theta: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(qw, qx, qy, qz)`` (..., 4) of rotation vectors (..., 3) [rad],
    ``qw = cos(|theta|/2) >= 0`` for angles up to pi."""
    theta = np.asarray(theta, dtype=float)
    angle = np.linalg.norm(theta, axis=-1, keepdims=True)
    half = 0.5 * angle
    small = angle < 1e-6
    safe = np.where(small, 1.0, angle)
    # sin(a/2)/a, its series below 1e-6 rad (exact to double precision)
    s = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    return np.concatenate([np.cos(half), s * theta], axis=-1)


def rotation_vector_of_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) [rad] of quaternions (..., 4) (either sign, any norm)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q = np.where(q[..., :1] < 0.0, -q, q)
    sin_half = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(sin_half, q[..., :1])
    small = sin_half < 1e-12
    scale = np.where(small, 2.0, angle / np.where(small, 1.0, sin_half))
    return scale * q[..., 1:]


def _hamilton(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products ``a b`` of quaternion rows (..., 4)."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def _sign_continuous(q: np.ndarray) -> np.ndarray:
    """The format's sign: the first row's ``qw >= 0``, each row on the side of the one before."""
    q = np.array(q, dtype=float)
    if q[0, 0] < 0.0:
        q[0] = -q[0]
    for k in range(1, len(q)):
        if q[k] @ q[k - 1] < 0.0:
            q[k] = -q[k]
    return q


# --- the record ---------------------------------------------------------------


def generate_run6(
    scenario: Mapping,
    *,
    seed: int = 0,
    force_noise_n: float = 0.0,
    moment_noise_n_m: float = 0.0,
    position_noise_m: float = 0.0,
    attitude_noise_rad: float = 0.0,
    duration_s: float | None = None,
    hidden: Mapping | None = None,
    table_start: str = "previous_tick",
    hold_s: float = 0.05,
) -> dict[str, np.ndarray]:
    """A closed-loop record of ``scenario`` in the format's 33 columns.

    The loop is ``rig6.simulate_rig6`` (plain numpy): the spacecraft's rigid
    body stepped by the rig computer as the format's step 3 says, the table
    model (second order per pose coordinate, exact per tick; ``"inf"``: the
    ideal table), the pads' springs (and Hunt-Crossley dissipation, and the
    pad law's ``[contact]`` keys: ``contact_exponent``, ``reference_press_m``,
    ``contact_damping_n_s_per_m``, ``series_compliance_m_per_n``,
    ``normal_friction_force_n``, ``normal_friction_velocity_m_per_s``) on the
    plate, a sensor delay of whole ticks and the compensators none / SDC /
    MDC / SDMDC (MDC's ``K`` and ``C`` by finite differences at the table's
    pose, the ``"linearized"`` stiffness model with the contact's stiffness).
    Row k is tick k: ``p_des``/``q_des`` and ``v_des``/``w_des`` the port's pose
    and twist after the tick's update, ``p_act``/``q_act`` the table's pose under
    the command of tick k-1, ``w_mea[k]`` the contact's wrench of tick
    ``k - delay`` (zero before the record), ``w_comp[k]`` what the model was fed.
    ``time_s`` is ``k / sample_rate_hz``. Without ``duration_s`` the record
    holds one contact and ends 0.05 s after it (the table clear, nothing left
    in the delay line); with it, the record is ``duration_s`` long whatever
    the contact does.

    The twist is rig6's state made explicit: the centre of mass's velocity
    replayed from the compensated force (rig6's own ``v += h f / m``), the
    angular velocity from the angular momentum rig6 returns (``R I^-1 R^T L``),
    the port's velocity ``v + omega x R r_port``. ``approach.lateral_miss_m``
    moves every position across the axis (the plate is infinite, so the
    contact does not change). Quaternions come from the rotation vectors,
    made sign-continuous with the first ``qw >= 0``.

    Noise (seeded with ``seed``, drawn in this order, white and Gaussian): the
    measured force and moment columns (``*_mea_*``), the measured position
    (``p*_act_m``) and the measured attitude (``q_act`` turned by a small rotation
    in W of ``attitude_noise_rad`` per axis, then made sign-continuous). It is
    measurement noise only: rig6 has none inside its loop, so ``w_comp`` is
    the loop's noise-free value (for no compensator, ``w_mea`` before the noise).

    What rig6 cannot run is refused with ``ValueError``: friction
    (``friction_coefficient`` must be 0), the probe and drogue
    (``geometry`` other than ``"plate"``), the Stewart backend, an initial
    angular rate, noise inside the loop (``[rig] force_noise_n`` /
    ``moment_noise_n_m`` other than 0), a stiffness model other than
    ``"linearized"`` or a believed stiffness other than the contact's, a
    sensor delay that is not a whole number of ticks, any key it does not know.
    Sections or keys missing from ``scenario`` take :func:`scenario`'s nominal
    values.
    ``misalignment_deg = [roll, pitch]`` is the attitude ``Ry(pitch) Rx(roll)``
    (rig6's; Drake's roll-pitch-yaw with no yaw), the port starting
    ``initial_gap_m`` from the plate at the pad nearest to it.

    ``hidden`` (``{effect: {parameter: value}}``, ``rig6.normalize_hidden``)
    gives the rig what the scenario does not say: a library effect of
    ``docs/run6-format.md`` ("The effects, as laws", e.g. ``{"sensor_crosstalk":
    {"fz_to_fx": 0.01}}``) or one outside the library (``rig6.OUTSIDE_EFFECTS``,
    e.g. ``{"pad_proud": {"proud_m": 1e-4}}``); their laws are
    ``rig6.simulate_rig6``'s. The rig computer, the scenario (the JSON) and
    the measurement noise are unchanged; :func:`truth_record` says what was
    hidden. ``table_start`` is ``rig6.simulate_rig6``'s (``"previous_tick"``,
    the default, or ``"tick0"``: the table at the command less its ramp lag
    when tick 0 reads it, as ``hybridtable`` reads the format). ``None`` or
    ``{}`` and the default start give the record without them, bit for bit.
    Without ``duration_s`` the record ends ``hold_s`` after the contact.
    """
    kwargs, miss, out = _closed_loop(scenario, hidden, table_start, duration_s, hold_s)
    rate = kwargs["sample_rate_hz"]
    h = 1.0 / rate
    n = len(out["t_s"])
    q_des, q_act = out["q_des"], out["q_act"]
    w_comp = out["wrench_comp"]  # [moment; force] on the spacecraft
    w_mea = out["wrench_mea"]  # the reading the rig computer used, before the noise

    # the twist after each tick's update
    mass = kwargs["mass_kg"]
    inertia = np.asarray(kwargs["inertia_kg_m2"], dtype=float)
    inertia = np.diag(inertia) if inertia.ndim == 1 else inertia
    inertia_inv = np.linalg.inv(inertia)
    r_port = out["port_position_model_m"]  # from the rig computer's centre of mass
    v = np.array([0.0, 0.0, kwargs["initial_velocity_m_per_s"]])
    v_port, omega = np.zeros((n, 3)), np.zeros((n, 3))
    for k in range(n):
        v = v + h * w_comp[k, 3:] / mass
        rot = rig6.exp_so3(q_des[k, 3:])
        omega[k] = rot @ (inertia_inv @ (rot.T @ out["angular_momentum_n_m_s"][k]))
        v_port[k] = v + np.cross(omega[k], rot @ r_port)

    rng = np.random.default_rng(seed)
    f_mea = w_mea[:, 3:] + force_noise_n * rng.standard_normal((n, 3))
    m_mea = w_mea[:, :3] + moment_noise_n_m * rng.standard_normal((n, 3))
    shift = np.array([miss[0], miss[1], 0.0])
    p_des = q_des[:, :3] + shift
    p_act = q_act[:, :3] + shift + position_noise_m * rng.standard_normal((n, 3))
    quat_des = _sign_continuous(quaternion_of_rotation_vector(q_des[:, 3:]))
    quat_act = quaternion_of_rotation_vector(q_act[:, 3:])
    turn = quaternion_of_rotation_vector(attitude_noise_rad * rng.standard_normal((n, 3)))
    quat_act = _hamilton(turn, quat_act)
    quat_act = _sign_continuous(quat_act / np.linalg.norm(quat_act, axis=1, keepdims=True))

    rows: dict[str, np.ndarray] = {"time_s": np.arange(n) / rate}
    blocks = (
        ("p{}_des_m", _XYZ, p_des),
        ("q{}_des", _WXYZ, quat_des),
        ("v{}_des_m_per_s", _XYZ, v_port),
        ("w{}_des_rad_per_s", _XYZ, omega),
        ("p{}_act_m", _XYZ, p_act),
        ("q{}_act", _WXYZ, quat_act),
        ("f{}_mea_n", _XYZ, f_mea),
        ("m{}_mea_n_m", _XYZ, m_mea),
        ("f{}_comp_n", _XYZ, w_comp[:, 3:]),
        ("m{}_comp_n_m", _XYZ, w_comp[:, :3]),
    )
    for pattern, axes, values in blocks:
        for i, axis in enumerate(axes):
            rows[pattern.format(axis)] = np.array(values[:, i], dtype=float)
    assert tuple(rows) == COLUMNS
    return rows


def _closed_loop(
    scenario: Mapping,
    hidden: Mapping | None,
    table_start: str,
    duration_s: float | None,
    hold_s: float = 0.05,
) -> tuple[dict, np.ndarray, dict]:
    """``rig6.simulate_rig6``'s arguments for ``scenario``, its lateral miss and its run."""
    kwargs, miss = _rig6_arguments(scenario)
    out = rig6.simulate_rig6(
        **kwargs,
        duration_s=duration_s,
        hidden=hidden,
        table_start=table_start,
        lateral_miss_m=tuple(miss),
        hold_s=hold_s,
    )
    return kwargs, miss, out


# --- writing ------------------------------------------------------------------


def _json_safe(value):
    """Scenario values as JSON: infinities as ``"inf"`` (as the docs write them),
    numpy scalars and arrays as Python numbers and lists."""
    if isinstance(value, Mapping):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return value


def write_run6(
    folder: Path | str,
    stem: str,
    scenario: Mapping,
    rows: Mapping[str, np.ndarray],
    run_id: str | None = None,
    *,
    json_fields: Mapping | None = None,
) -> tuple[Path, Path]:
    """Write ``folder/stem.csv`` and ``folder/stem.json``; return their paths.

    The CSV's header is the format's columns present in ``rows`` in the
    document's order, then any other columns of ``rows`` (a reader skips them);
    each value is ``repr`` of the float (``nan`` as ``nan``). The JSON is
    ``{"format": FORMAT, "run_id": run_id or stem, "scenario": scenario}`` with
    ``json_fields`` written over its top-level keys (for a bad JSON). The
    folder is made if missing; existing files are replaced.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = [c for c in COLUMNS if c in rows] + [c for c in rows if c not in COLUMNS]
    lengths = {len(rows[c]) for c in names}
    if len(lengths) != 1:
        raise ValueError(f"columns of different lengths: {sorted(lengths)}")
    csv_path, json_path = folder / f"{stem}.csv", folder / f"{stem}.json"
    columns = [np.asarray(rows[c], dtype=float) for c in names]
    with open(csv_path, "w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(names)
        for k in range(lengths.pop()):
            writer.writerow([repr(float(col[k])) for col in columns])
    document = {"format": FORMAT, "run_id": stem if run_id is None else run_id}
    document["scenario"] = _json_safe(scenario)
    document.update(json_fields or {})
    json_path.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    return csv_path, json_path


# --- hidden effects: sizing and sets of runs ------------------------------------

#: The channels a replay predicts, in this order (the library's component names).
CHANNELS: tuple[str, ...] = (
    "fx_mea",
    "fy_mea",
    "fz_mea",
    "mx_mea",
    "my_mea",
    "mz_mea",
    "px_act",
    "py_act",
    "pz_act",
    "thetax_act",
    "thetay_act",
    "thetaz_act",
)

#: The library's effects of a six-axis rig and the ones outside it (rig6's laws).
LIBRARY_EFFECTS: tuple[str, ...] = tuple(rig6.LIBRARY_EFFECTS)
OUTSIDE_EFFECTS: tuple[str, ...] = tuple(rig6.OUTSIDE_EFFECTS)

#: The kinds of set :func:`draw_set6` draws.
SET_KINDS: tuple[str, ...] = ("null", "single", "pair", "outside")

#: Effects only a finite table (the table model at a finite frequency) shows.
_NEEDS_TABLE = frozenset({"table_response", "table_damping", "lateral_lag"})

#: Effects a replay cannot see (the rig computer's): drawn, not sized.
_COMPUTER_EFFECTS = frozenset({"com_offset"})

#: The sizing's target band: the nominal model's worst channel, RMS over the
#: contact, in that channel's noise levels.
TARGET_RATIO = (3.75, 6.5)
_TOLERANCE = 1.2  # a ratio within this factor of the target is taken


def truth_record(hidden: Mapping | None, **extra) -> dict:
    """What a run or set hid, as JSON: every parameter of every effect.

    Parameters
    ----------
    hidden : mapping or None
        ``{effect: {parameter: value}}`` as ``generate_run6`` takes it.
    **extra
        Keys written over the record's (the set's kind, seed, sizing, ...).

    Returns
    -------
    dict
        ``{"hidden": {effect: {parameter: value}}, "library": [...], "outside":
        [...]}``: ``rig6.normalize_hidden``'s values (every parameter), the
        library's effects and the ones outside it by name, JSON-safe.
    """
    effects = rig6.normalize_hidden(hidden)
    record = {
        "hidden": effects,
        "library": [name for name in effects if name in rig6.LIBRARY_EFFECTS],
        "outside": [name for name in effects if name in rig6.OUTSIDE_EFFECTS],
    }
    return _json_safe(record | extra)


def _channels(wrench_mea: np.ndarray, q_act: np.ndarray) -> np.ndarray:
    """``(N, 12)`` in :data:`CHANNELS`' order from rig6's ``[m; f]`` and ``[p; theta]``."""
    return np.column_stack([wrench_mea[:, 3:], wrench_mea[:, :3], q_act[:, :3], q_act[:, 3:]])


def _noise_vector(noise: Mapping[str, float]) -> np.ndarray:
    """Each channel's noise level (12,) from the four noise sizes."""
    keys = ("force_noise_n", "moment_noise_n_m", "position_noise_m", "attitude_noise_rad")
    sizes = [float(noise[k]) for k in keys]
    if min(sizes) <= 0.0:
        raise ValueError(f"noise: every size must be above 0, not {dict(noise)}")
    return np.repeat(sizes, 3)


def _contact_window(out: Mapping, model: Mapping, delay_ticks: int) -> slice:
    """The contact as the library reads it: from the first tick a pad touches
    (in the run or the replay) to the last, plus the sensor's delay and two
    ticks (the reading of the last touch)."""
    ticks = np.flatnonzero(out["in_contact"] | model["in_contact"])
    if not len(ticks):
        raise RuntimeError("no contact in the run")
    return slice(int(ticks[0]), min(int(ticks[-1]) + delay_ticks + 3, len(out["in_contact"])))


def _library_probes(kwargs: Mapping) -> list[dict]:
    """Small library effects whose replays span (to first order) what the
    library can change in a replay, for :func:`replay_error6`'s projection."""
    h = 1.0 / kwargs["sample_rate_hz"]
    k = kwargs["contact_stiffness_n_per_m"]
    probes: list[dict] = [
        {"stiffness_error": {"contact_stiffness_n_per_m": 1.01 * k}},
        {"hunt_crossley": {"damping_factor_s_per_m": 0.05}},
        {"friction_across_face": {"extra_friction_coefficient": 0.01}},
        {"force_bias": {"bias_n": 1.0}},
    ]
    probes += [{"extra_delay": {"extra_delay_s": n * h}} for n in (1, 2, 4)]
    probes += [{"sensor_filter": {"time_constant_s": n * h}} for n in (1, 4)]
    for name in ("sensor_misalignment", "sensor_crosstalk", "table_misalignment"):
        probes += [{name: {key: 1e-3}} for key in rig6.LIBRARY_EFFECTS[name]]
    if not math.isinf(kwargs["table_response_hz"]):
        probes.append({"table_response": {"table_response_ratio": 1.01}})
        probes.append({"table_damping": {"table_damping_factor": 1.01}})
    return probes


def replay_error6(
    scenario: Mapping,
    hidden: Mapping | None,
    noise: Mapping[str, float],
    *,
    table_start: str = "tick0",
    hold_s: float = 0.05,
    project: bool = False,
) -> dict:
    """How far the nominal model's replay is from a run with ``hidden``, per channel.

    The run is the closed loop of :func:`generate_run6` without measurement
    noise; the replay drives the scenario's own physical part (table, contact,
    sensor: ``rig6.replay_rig6``) with the run's commands, as ``hybridtable
    compare`` replays a record. Each of :data:`CHANNELS` (force, moment,
    table position, rotation vector) is compared in its noise level
    (``noise``: ``force_noise_n``, ``moment_noise_n_m``, ``position_noise_m``,
    ``attitude_noise_rad``), RMS over the contact (from the first tick a pad
    touches, in the run or the replay, to the last, plus the sensor's delay
    and two ticks) and over the whole record.

    With ``project``, the difference is also projected off the span of the
    library's effects, linearized (small ones of each, replayed on the same
    commands: stiffness, dissipation, friction, bias, delays of 1, 2, 4 ticks,
    low passes of 1 and 4 ticks, each angle of a turned sensor and table, each
    cross-talk coefficient, the table's frequency and damping), by least
    squares over every channel of the contact: what is left is what no
    combination of small library effects explains (a superset of what the
    library can fit, so a lower bound of what it leaves, to first order).

    Parameters
    ----------
    scenario : mapping
        The run's scenario (:func:`scenario`'s form).
    hidden : mapping or None
        The effects the rig hides.
    noise : mapping
        ``force_noise_n`` (N), ``moment_noise_n_m`` (N m), ``position_noise_m``
        (m), ``attitude_noise_rad`` (rad): each channel's noise level.
    table_start, hold_s
        As :func:`generate_run6`'s.
    project : bool
        Also project the difference off the library's effects.

    Returns
    -------
    dict
        ``ratios`` (channel -> RMS / noise over the contact), ``ratio`` and
        ``worst`` (the largest and its channel), ``record_ratio`` (the largest
        over the whole record), ``window`` (the contact's first and last tick),
        ``ticks``;
        with ``project`` also ``residual_ratios``, ``residual_ratio`` and
        ``residual_worst``.
    """
    kwargs, miss, out = _closed_loop(scenario, hidden, table_start, None, hold_s)
    scale = _noise_vector(noise)

    def replay(probe):
        return rig6.replay_rig6(
            out["command_initial"],
            out["command_rate_initial"],
            out["q_des"],
            out["qd_des"],
            **kwargs,
            hidden=probe,
            table_start=table_start,
            lateral_miss_m=tuple(miss),
        )

    base = replay(None)
    model = _channels(base["wrench_mea"], base["q_act"])
    diff = (_channels(out["wrench_mea"], out["q_act"]) - model) / scale
    extra = rig6.normalize_hidden(hidden).get("extra_delay", {}).get("extra_delay_s", 0.0)
    delay_ticks = round((kwargs["sensor_delay_s"] + extra) * kwargs["sample_rate_hz"])
    window = _contact_window(out, base, delay_ticks)
    ratios = np.sqrt(np.mean(diff[window] ** 2, axis=0))
    worst = int(np.argmax(ratios))
    result = {
        "ratios": dict(zip(CHANNELS, ratios.tolist(), strict=True)),
        "ratio": float(ratios[worst]),
        "worst": CHANNELS[worst],
        "record_ratio": float(np.sqrt(np.mean(diff**2, axis=0)).max()),
        "window": [window.start, window.stop - 1],
        "ticks": len(out["t_s"]),
    }
    if project:
        columns = []
        for probe in _library_probes(kwargs):
            rep = replay(probe)
            change = (_channels(rep["wrench_mea"], rep["q_act"]) - model) / scale
            columns.append(change[window].ravel())
        basis = np.column_stack(columns)
        y = diff[window].ravel()
        coef = np.linalg.lstsq(basis, y, rcond=None)[0]
        left = (y - basis @ coef).reshape(-1, len(CHANNELS))
        residual = np.sqrt(np.mean(left**2, axis=0))
        worst = int(np.argmax(residual))
        result["residual_ratios"] = dict(zip(CHANNELS, residual.tolist(), strict=True))
        result["residual_ratio"] = float(residual[worst])
        result["residual_worst"] = CHANNELS[worst]
    return result


def _unit(rng: np.random.Generator, n: int, weights=None) -> np.ndarray:
    u = rng.standard_normal(n) * (1.0 if weights is None else np.asarray(weights))
    return u / np.linalg.norm(u)


def _family(name: str, rng: np.random.Generator, kwargs: Mapping, noise: Mapping, gap_m: float):
    """How an effect grows with one scale ``s`` (its direction drawn here):
    ``(make(s) -> parameters, s0, s_max, whole_ticks)``."""
    h = 1.0 / kwargs["sample_rate_hz"]
    sign = float(rng.choice([-1.0, 1.0]))
    keys = tuple(rig6.LIBRARY_EFFECTS.get(name, rig6.OUTSIDE_EFFECTS.get(name, {})))

    def along(u):
        return lambda s: {key: float(s * x) for key, x in zip(keys, u, strict=True)}

    if name == "stiffness_error":
        k = kwargs["contact_stiffness_n_per_m"]
        return (lambda s: {keys[0]: k * (1.0 + sign * s)}), 0.02, (0.8 if sign < 0 else 3.0), False
    if name == "hunt_crossley":
        return (lambda s: {keys[0]: s}), 0.1, 30.0, False
    if name == "friction_across_face":
        return (lambda s: {keys[0]: s}), 0.02, 1.0, False
    # the pad law's terms, each in its own scale of the scenario's contact:
    # the critical damping 2 sqrt(k m), the stiffness's compliance 1 / k, the
    # undamped peak force v0 sqrt(k m); the exponent about the scenario's k
    k, mass = kwargs["contact_stiffness_n_per_m"], kwargs["mass_kg"]
    if name == "contact_damping":
        critical = 2.0 * math.sqrt(k * mass)
        return (lambda s: {keys[0]: s * critical}), 0.005, 0.5, False
    if name == "nonlinear_stiffness":
        return (lambda s: {keys[0]: 1.0 + sign * s, keys[1]: k}), 0.01, 0.5, False
    if name == "series_compliance":
        return (lambda s: {keys[0]: s / k}), 0.005, 1.0, False
    if name == "coulomb_friction":
        peak = kwargs["initial_velocity_m_per_s"] * math.sqrt(k * mass)
        return (lambda s: {keys[0]: s * peak}), 0.002, 0.2, False
    if name == "extra_delay":
        return (lambda n: {keys[0]: n * h}), 1, 25, True
    if name == "sensor_filter":
        return (lambda s: {keys[0]: s}), 2.0 * h, 0.1, False
    if name == "force_bias":
        return (lambda s: {keys[0]: sign * s}), 3.0 * noise["force_noise_n"], 1000.0, False
    if name in ("sensor_misalignment", "table_misalignment"):
        return along(_unit(rng, 3)), 1e-3, 0.3, False
    if name == "sensor_crosstalk":  # the four channels alike in their noise levels
        lever = noise["moment_noise_n_m"] / noise["force_noise_n"]
        return along(_unit(rng, 4, [1.0, 1.0, lever, lever])), 1e-3, 0.5, False
    if name in ("table_response", "table_damping"):
        return (lambda s: {keys[0]: math.exp(sign * s)}), 0.02, 1.2, False
    if name == "mount_resonance":
        zeta = float(rng.uniform(0.1, 0.3))
        return (lambda s: {keys[0]: 1.0 / s, keys[1]: zeta}), 1.0 / 150.0, 1.0 / 10.0, False
    if name == "table_resonance":  # s: the mode's period, 1/450 s up to 1/15 s
        zeta = float(rng.uniform(0.03, 0.2))
        return (lambda s: {keys[0]: 1.0 / s, keys[1]: zeta}), 1.0 / 450.0, 1.0 / 15.0, False
    if name == "lateral_backlash":
        axis = keys[int(rng.integers(2))]
        return (lambda s: {axis: s}), 5.0 * noise["position_noise_m"], 5e-3, False
    if name == "pad_proud":
        index = int(rng.integers(kwargs["pad_count"]))
        return (lambda s: {"proud_m": s, "pad_index": index}), 2e-5, 0.5 * gap_m, False
    if name == "fz_quadratic_gain":  # s: the gain's change at the undamped peak force
        peak = kwargs["initial_velocity_m_per_s"] * math.sqrt(
            kwargs["contact_stiffness_n_per_m"] * kwargs["mass_kg"]
        )
        return (lambda s: {keys[0]: sign * s / peak}), 0.005, 0.3, False
    if name == "lateral_lag":
        return (lambda s: {keys[0]: math.exp(-s)}), 0.1, 1.6, False
    raise ValueError(f"no sizing for {name!r}")


def size_effect6(
    scenario: Mapping,
    name: str,
    noise: Mapping[str, float],
    target: float,
    rng: np.random.Generator,
    *,
    table_start: str = "tick0",
    hold_s: float = 0.05,
    gap_m: float | None = None,
) -> tuple[dict, dict] | None:
    """An effect's parameters sized by the generator's own runs.

    The effect's direction is drawn (a sign, a unit vector of its angles or
    coefficients, a pad, an axis, a damping ratio) and its size ``s`` scaled
    until :func:`replay_error6` on ``scenario`` puts the nominal model's worst
    channel ``target`` noise levels off (RMS over the contact), within a factor
    1.2; an effect outside the library is scaled on what is left after the
    projection off the library's effects, so that ``target`` is what no library
    effect explains. A delay takes whole ticks: the first whose error reaches
    ``target`` or the one before it, whichever is nearer (in ratio).
    ``gap_m`` bounds a proud pad (half of it; default the scenario's gap).

    Parameters
    ----------
    scenario : mapping
        The run the effect is sized on.
    name : str
        An effect of ``rig6.LIBRARY_EFFECTS`` (not ``com_offset``: a replay
        does not see it) or ``rig6.OUTSIDE_EFFECTS``.
    noise : mapping
        The rig's noise levels (:func:`replay_error6`).
    target : float
        The worst channel's RMS error over the contact, in noise levels.
    rng : numpy.random.Generator
        Draws the effect's direction.
    table_start, hold_s
        As :func:`generate_run6`'s.
    gap_m : float, optional
        The smallest initial gap of the set's runs (m).

    Returns
    -------
    tuple or None
        ``(parameters, report)``, the report with ``ratio`` (the sized figure),
        ``nominal_ratio``, ``worst``, ``target`` and every try; ``None`` when
        the effect cannot reach the target on this scenario within its range
        (e.g. a lateral effect on a run that barely moves sideways).
    """
    kwargs, _ = _rig6_arguments(scenario)
    if gap_m is None:
        gap_m = kwargs["initial_gap_m"]
    make, s, s_max, whole = _family(name, rng, kwargs, noise, gap_m)
    outside = name in rig6.OUTSIDE_EFFECTS
    tried: list[dict] = []

    def evaluate(size):
        err = replay_error6(
            scenario,
            {name: make(size)},
            noise,
            table_start=table_start,
            hold_s=hold_s,
            project=outside,
        )
        ratio = err["residual_ratio"] if outside else err["ratio"]
        worst = err["residual_worst"] if outside else err["worst"]
        tried.append(
            {
                "s": size,
                "ratio": ratio,
                "nominal_ratio": err["ratio"],
                "worst": worst,
                "record_ratio": err["record_ratio"],
            }
        )
        return ratio

    def report(size):
        best = next(t for t in tried if t["s"] == size)
        return make(size), {**best, "target": target, "tried": tried}

    if whole:
        previous = None
        for n in range(1, int(s_max) + 1):
            r = evaluate(n)
            if r >= target:
                choices = [(n, r)]
                if previous is not None and previous[1] >= 3.0:
                    choices.append(previous)
                return report(min(choices, key=lambda c: abs(math.log(c[1] / target)))[0])
            previous = (n, r)
        return None
    for _ in range(12):
        r = evaluate(s)
        if r > 0.0 and abs(math.log(r / target)) < math.log(_TOLERANCE):
            return report(s)
        if r <= 0.0:
            s_new = 10.0 * s
        else:
            slope = 1.0
            pts = [(t["s"], t["ratio"]) for t in tried if t["ratio"] > 0.0]
            if len(pts) >= 2 and pts[-1][0] != pts[-2][0]:
                slope = math.log(pts[-1][1] / pts[-2][1]) / math.log(pts[-1][0] / pts[-2][0])
                slope = min(max(slope, 0.3), 3.0)
            s_new = s * (target / r) ** (1.0 / slope)
        s_new = min(max(s_new, s / 30.0), 30.0 * s, s_max)
        if s_new == s:  # at the range's end, short of the target
            return None
        s = s_new
    return None


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def draw_rig6(rng: np.random.Generator, *, finite_table: bool = False) -> dict:
    """A rig drawn within sensible ranges: ``{"scenario": ..., "noise": ...}``.

    The scenario (no approach yet) of a rig6 can run: the sample rate 500, 1000
    or 2000 Hz; a sensor delay of 1-8 ms in whole ticks; the compensator none,
    SDC, MDC or SDMDC (lead: the delay); mass 800-8000 kg and contact stiffness
    3e4-3e5 N/m (log-uniform) with a contact of 0.15-0.8 s; radii of gyration
    0.6-1.2 m (a real body's inertia); the port 1-2 m ahead of the centre of
    mass and up to 20 mm off its axis; 3, 4, 6 or 8 pads of 5-20 mm on a
    0.15-0.4 m ring; no dissipation or up to 0.5 s/m; the table model at
    15-40 Hz with damping 0.6-1 (or the ideal table, one rig in seven, unless
    ``finite_table``). Noise: F/T 0.5-3 N and 0.1-0.3 m times that in N m,
    encoders 1-10 um and 0.5-5 urad (log-uniform).

    Parameters
    ----------
    rng : numpy.random.Generator
        The draws.
    finite_table : bool
        Never the ideal table (for an effect of the table's response).

    Returns
    -------
    dict
        ``scenario`` (its ``[approach]`` the nominal's) and ``noise``
        (:func:`replay_error6`'s keys).
    """
    rate = float(rng.choice([500.0, 1000.0, 2000.0], p=[0.25, 0.5, 0.25]))
    n_delay = max(1, round(rng.uniform(1e-3, 8e-3) * rate))
    while True:
        mass = _log_uniform(rng, 800.0, 8000.0)
        k = _log_uniform(rng, 3e4, 3e5)
        if 0.15 <= math.pi * math.sqrt(mass / k) <= 0.8:
            break
    while True:
        inertia = mass * rng.uniform(0.6, 1.2, size=3) ** 2
        if all(inertia.sum() - 2 * i >= 0.0 for i in inertia):  # I1 + I2 >= I3, each
            break
    ideal = not finite_table and rng.random() < 1.0 / 7.0
    force_noise = float(rng.uniform(0.5, 3.0))
    scen = scenario(
        spacecraft={
            "contact_frequency_hz": None,
            "mass_kg": mass,
            "inertia_kg_m2": inertia.tolist(),
            "port_distance_m": float(rng.uniform(1.0, 2.0)),
            "lateral_offset_m": rng.uniform(-0.02, 0.02, size=2).tolist(),
        },
        contact={
            "contact_stiffness_n_per_m": k,
            "contact_dissipation_s_per_m": 0.0
            if rng.random() < 0.5
            else float(rng.uniform(0.05, 0.5)),
            "pad_count": int(rng.choice([3, 4, 6, 8])),
            "ring_radius_m": float(rng.uniform(0.15, 0.4)),
            "pad_radius_m": float(rng.uniform(0.005, 0.02)),
        },
        rig={"sample_rate_hz": rate, "sensor_delay_s": n_delay / rate},
        table={
            "response_hz": "inf" if ideal else float(rng.uniform(15.0, 40.0)),
            "damping_ratio": float(rng.uniform(0.6, 1.0)),
        },
        compensator={"name": str(rng.choice(rig6.COMPENSATORS))},
    )
    noise = {
        "force_noise_n": force_noise,
        "moment_noise_n_m": force_noise * float(rng.uniform(0.1, 0.3)),
        "position_noise_m": _log_uniform(rng, 1e-6, 1e-5),
        "attitude_noise_rad": _log_uniform(rng, 5e-7, 5e-6),
    }
    return {"scenario": scen, "noise": noise}


def draw_approach6(rng: np.random.Generator, rate_hz: float) -> dict:
    """An approach (the scenario's ``[approach]``): 0.04-0.15 m/s, roll and pitch
    within 3 deg (at least 0.5 deg of tilt: the ring touches on one side and
    the body turns, so the pads slide), a lateral miss within 30 mm, and a gap
    of 2-6 mm, at least 100 ticks of free flight.

    Parameters
    ----------
    rng : numpy.random.Generator
        The draws.
    rate_hz : float
        The rig computer's sample rate (Hz).

    Returns
    -------
    dict
        The ``[approach]`` section.
    """
    v0 = float(rng.uniform(0.04, 0.15))
    while True:
        tilt = rng.uniform(-3.0, 3.0, size=2)
        if np.hypot(*tilt) >= 0.5:
            break
    return {
        "initial_velocity_m_per_s": v0,
        "initial_gap_m": max(float(rng.uniform(2e-3, 6e-3)), 100.0 * v0 / rate_hz),
        "misalignment_deg": tilt.tolist(),
        "angular_rate_rad_per_s": [0.0, 0.0, 0.0],
        "lateral_miss_m": rng.uniform(-0.03, 0.03, size=2).tolist(),
    }


def _pick_pair(rng: np.random.Generator) -> list[str]:
    """Two library effects acting on different parts of the rig."""
    pairs = [
        (a, b)
        for i, a in enumerate(LIBRARY_EFFECTS)
        for b in LIBRARY_EFFECTS[i + 1 :]
        if rig6.EFFECT_PARTS[a] != rig6.EFFECT_PARTS[b]
    ]
    return list(pairs[int(rng.integers(len(pairs)))])


def _scale_noise(noise: dict, factor: float, report: dict) -> None:
    """Every noise level times ``factor``, and a sizing report's figures over it
    (a replay's error in noise levels is inversely proportional to the noise)."""
    for key in noise:
        noise[key] *= factor
    report["noise_scaled_by"] = factor
    for entry in [report, *report["tried"]]:
        for key in ("ratio", "nominal_ratio", "record_ratio"):
            entry[key] /= factor


@dataclass
class Set6:
    """A set: 1-3 runs of one rig at different approaches, and what it hid.

    ``runs`` holds ``(scenario, rows)`` pairs (the JSON's scenario, the CSV's
    columns); ``truth`` is JSON (:func:`truth_record` with the set's kind,
    seed, rig, noise, sizing and each run's error figures).
    """

    kind: str
    effects: list[str]
    hidden: dict
    runs: list[tuple[dict, dict]]
    truth: dict


def draw_set6(
    seed: int,
    kind: str,
    effects: list[str] | tuple[str, ...] | None = None,
    *,
    n_runs: int | None = None,
    table_start: str = "tick0",
    max_attempts: int = 8,
) -> Set6:
    """Draw a rig, its approaches and its hidden effects; size and run them.

    ``kind`` is one of :data:`SET_KINDS`: ``"null"`` hides nothing;
    ``"single"`` one library effect, ``"pair"`` two on different parts of the
    rig (``rig6.EFFECT_PARTS``), ``"outside"`` one of ``rig6.OUTSIDE_EFFECTS``:
    ``effects`` names them (default: drawn). Each effect is sized alone on the
    set's first run (:func:`size_effect6`, the target drawn in
    :data:`TARGET_RATIO`), ``com_offset`` drawn (2-10 cm; a replay cannot see
    it). A delay is sized first: when one tick already puts the model further
    off than the target, the rig's noise levels are raised to bring it there. A rig on which an effect cannot reach its target is drawn again (up
    to ``max_attempts``, then ``RuntimeError``). ``n_runs`` (default 1, 2 or 3,
    weights 1:2:2) runs of the rig at different approaches
    (:func:`draw_approach6`) are generated with ``table_start`` and noise
    seeded from ``seed``; each record ends 100 ticks after its contact.

    Parameters
    ----------
    seed : int
        Seeds every draw and the runs' noise: the same seed, the same set.
    kind : str
        ``"null"``, ``"single"``, ``"pair"`` or ``"outside"``.
    effects : list of str, optional
        The effects to hide (default: drawn for the kind).
    n_runs : int, optional
        Runs in the set (default: drawn).
    table_start : str
        As :func:`generate_run6`'s (default ``"tick0"``, the library's reading).
    max_attempts : int
        Rigs drawn before giving up.

    Returns
    -------
    Set6
        The runs, the hidden effects and the truth record.

    Raises
    ------
    ValueError
        An unknown kind, or effects that do not fit it.
    RuntimeError
        No rig of ``max_attempts`` could take the effects at their targets.
    """
    if kind not in SET_KINDS:
        raise ValueError(f"kind {kind!r}: one of {SET_KINDS}")
    rng = np.random.default_rng(seed)
    if effects is None:
        if kind == "single":
            effects = [str(rng.choice(LIBRARY_EFFECTS))]
        elif kind == "pair":
            effects = _pick_pair(rng)
        elif kind == "outside":
            effects = [str(rng.choice(OUTSIDE_EFFECTS))]
        else:
            effects = []
    effects = list(effects)
    want = {"null": 0, "single": 1, "pair": 2, "outside": 1}[kind]
    pool = OUTSIDE_EFFECTS if kind == "outside" else LIBRARY_EFFECTS
    if len(effects) != want or any(e not in pool for e in effects):
        raise ValueError(f"a {kind} set hides {want} of {pool}, not {effects}")
    if kind == "pair" and rig6.EFFECT_PARTS[effects[0]] == rig6.EFFECT_PARTS[effects[1]]:
        raise ValueError(f"a pair acts on two parts of the rig, not {effects}")
    if n_runs is None:
        n_runs = int(rng.choice([1, 2, 3], p=[0.2, 0.4, 0.4]))
    finite = any(e in _NEEDS_TABLE for e in effects)
    failures = []
    for attempt in range(1, max_attempts + 1):
        rig = draw_rig6(rng, finite_table=finite)
        rate = rig["scenario"]["rig"]["sample_rate_hz"]
        hold_s = 100.0 / rate
        scens = [
            copy.deepcopy(rig["scenario"]) | {"approach": draw_approach6(rng, rate)}
            for _ in range(n_runs)
        ]
        gap = min(s["approach"]["initial_gap_m"] for s in scens)
        hidden, sizing, targets = {}, {}, {}
        for name in sorted(effects, key=lambda e: e != "extra_delay"):  # the delay first
            if name in _COMPUTER_EFFECTS:
                offset = rng.uniform(0.02, 0.1) * _unit(rng, 3)
                keys = rig6.LIBRARY_EFFECTS[name]
                hidden[name] = {k: float(x) for k, x in zip(keys, offset, strict=True)}
                continue
            targets[name] = float(rng.uniform(*TARGET_RATIO))
            sized = size_effect6(
                scens[0],
                name,
                rig["noise"],
                targets[name],
                rng,
                table_start=table_start,
                hold_s=hold_s,
                gap_m=gap,
            )
            if sized is None:
                failures.append({"attempt": attempt, "effect": name})
                break
            hidden[name], sizing[name] = sized
            excess = sizing[name]["ratio"] / targets[name]
            if excess > _TOLERANCE:  # a whole tick of delay is already more: a noisier rig
                _scale_noise(rig["noise"], excess, sizing[name])
        else:
            break
    else:
        raise RuntimeError(f"seed {seed}: {effects} could not be sized on {max_attempts} rigs")
    runs, errors = [], []
    for i, scen in enumerate(scens):
        rows = generate_run6(
            scen,
            seed=seed * 10 + i,
            **rig["noise"],
            hidden=hidden,
            table_start=table_start,
            hold_s=hold_s,
        )
        runs.append((scen, rows))
        if hidden and set(hidden) - _COMPUTER_EFFECTS:
            err = replay_error6(scen, hidden, rig["noise"], table_start=table_start, hold_s=hold_s)
            errors.append({k: err[k] for k in ("ratio", "worst", "record_ratio", "ratios")})
    truth = truth_record(
        hidden,
        kind=kind,
        seed=seed,
        effects=effects,
        noise=rig["noise"],
        targets=targets,
        sizing=sizing,
        run_errors=errors,
        rig=rig["scenario"],
        approaches=[s["approach"] for s in scens],
        attempts=attempt,
        failures=failures,
        table_start=table_start,
    )
    return Set6(kind=kind, effects=effects, hidden=hidden, runs=runs, truth=truth)


def write_set6(folder: Path | str, set6: Set6, *, truth: bool = False) -> list[Path]:
    """Write a set's runs as ``run1.csv``/``run1.json``, ``run2...`` into ``folder``.

    Parameters
    ----------
    folder : path
        Made if missing (:func:`write_run6`).
    set6 : Set6
        The set.
    truth : bool
        Also write ``truth.json`` (the set's truth record) beside the runs; a
        reader of the format skips it.

    Returns
    -------
    list of Path
        The CSV files.
    """
    paths = []
    for i, (scen, rows) in enumerate(set6.runs, 1):
        paths.append(write_run6(folder, f"run{i}", scen, rows)[0])
    if truth:
        (Path(folder) / "truth.json").write_text(
            json.dumps(set6.truth, indent=2) + "\n", encoding="utf-8"
        )
    return paths


# --- bad runs -----------------------------------------------------------------


def _contact_row(rows: Mapping[str, np.ndarray]) -> int:
    """The row of the largest measured force: the middle of the contact."""
    force = np.sqrt(sum(np.asarray(rows[f"f{a}_mea_n"]) ** 2 for a in _XYZ))
    return int(np.argmax(force))


def corrupt(
    rows: Mapping[str, np.ndarray], kind: str
) -> tuple[dict[str, np.ndarray], list[tuple[str, ...]]]:
    """A copy of ``rows`` with one defect, and the words an error line about it
    should contain.

    The words are groups in lower case: the message (compared in lower case)
    names the defect if it holds, for every group, at least one of its words
    (:func:`message_names`). ``r`` below is the row of the largest measured
    force (mid-contact). Kinds:

    - ``"missing_column"``: ``my_mea_n_m`` dropped. Words: ``my_mea_n_m``.
    - ``"not_unit_quaternion"``: ``q_act`` times 1.2 on rows ``r`` to ``r + 9``
      (norm 1.2). Words: ``quaternion`` or ``norm``.
    - ``"quaternion_sign_flip"``: ``q_des`` negated from row ``r`` on (still
      unit, the first row still ``qw >= 0``). Words: ``sign``.
    - ``"degrees"``: the three ``w*_des_rad_per_s`` columns times ``180 / pi``
      (a log in deg/s under the rad/s names). Needs a record whose attitude
      turns (the nominal scenario's: 2 deg of pitch and a 10 mm offset), else
      ``ValueError``. Words: ``degree``.
    - ``"time_not_increasing"``: ``time_s`` of rows ``r`` and ``r + 1`` swapped.
      Words: ``time``, and ``increasing`` or ``decreasing`` or ``order``.
    - ``"nan_cell"``: ``fz_mea_n`` of row ``r`` is NaN (written ``nan``).
      Words: ``fz_mea_n``, and ``nan`` or ``finite``.
    - ``"sign_flipped_velocity"``: the three ``v*_des_m_per_s`` columns negated.
      Words: ``v_des`` or ``velocity``.
    - ``"no_contact"``: the record cut to the first half of its rows before
      the model is first fed a wrench (so the table is clear of the plate for
      any sensor delay up to that half): a free flight whose gap is never
      closed. Needs at least 6 such rows (``ValueError``; generate with a
      larger ``initial_gap_m``, e.g. 0.01). Words: ``contact``.
    - ``"bad_format"``: the rows unchanged; the defect is the JSON's
      ``"format": "hybridtable-run6/2"`` (:data:`JSON_CORRUPTIONS`, written by
      :func:`write_corrupt_run6`). Words: ``format``.
    """
    out = {name: np.array(values, dtype=float) for name, values in rows.items()}
    r = _contact_row(rows)
    if kind == "missing_column":
        del out["my_mea_n_m"]
        return out, [("my_mea_n_m",)]
    if kind == "not_unit_quaternion":
        for a in _WXYZ:
            out[f"q{a}_act"][r : r + 10] *= 1.2
        return out, [("quaternion", "norm")]
    if kind == "quaternion_sign_flip":
        if r == 0:
            raise ValueError("quaternion_sign_flip: the contact is at the first row")
        for a in _WXYZ:
            out[f"q{a}_des"][r:] *= -1.0
        return out, [("sign",)]
    if kind == "degrees":
        peak = max(np.abs(out[f"w{a}_des_rad_per_s"]).max() for a in _XYZ)
        if peak < 1e-4:
            raise ValueError("degrees: the attitude does not turn in this record (|w| < 1e-4)")
        for a in _XYZ:
            out[f"w{a}_des_rad_per_s"] *= 180.0 / math.pi
        return out, [("degree",)]
    if kind == "time_not_increasing":
        t = out["time_s"]
        t[r], t[r + 1] = t[r + 1], t[r]
        return out, [("time",), ("increasing", "decreasing", "order")]
    if kind == "nan_cell":
        out["fz_mea_n"][r] = math.nan
        return out, [("fz_mea_n",), ("nan", "finite")]
    if kind == "sign_flipped_velocity":
        for a in _XYZ:
            out[f"v{a}_des_m_per_s"] *= -1.0
        return out, [("v_des", "velocity")]
    if kind == "no_contact":
        fed = np.zeros(len(out["time_s"]), dtype=bool)
        for a in _XYZ:
            fed |= (out[f"f{a}_comp_n"] != 0.0) | (out[f"m{a}_comp_n_m"] != 0.0)
        first = int(np.argmax(fed)) if fed.any() else len(fed)
        keep = first // 2
        if keep < 6:
            raise ValueError(
                f"no_contact: only {first} rows before the contact; use a larger initial_gap_m"
            )
        return {name: values[:keep] for name, values in out.items()}, [("contact",)]
    if kind == "bad_format":
        return out, [("format",)]
    raise ValueError(f"unknown corruption {kind!r}: one of {CORRUPTIONS}")


def write_corrupt_run6(
    folder: Path | str,
    stem: str,
    scenario: Mapping,
    rows: Mapping[str, np.ndarray],
    kind: str,
    run_id: str | None = None,
) -> tuple[Path, Path, list[tuple[str, ...]]]:
    """Write a run with the defect ``kind`` (:func:`corrupt`, and the JSON's own
    defects of :data:`JSON_CORRUPTIONS`); return the CSV, the JSON and the words."""
    bad, words = corrupt(rows, kind)
    csv_path, json_path = write_run6(
        folder, stem, scenario, bad, run_id, json_fields=JSON_CORRUPTIONS.get(kind)
    )
    return csv_path, json_path, words


def message_names(message: str, words: list[tuple[str, ...]]) -> bool:
    """Whether ``message`` (case-insensitive) holds a word of every group of ``words``."""
    text = message.lower()
    return all(any(word.lower() in text for word in group) for group in words)
