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
from pathlib import Path

import numpy as np

from tests.generators import rig6

__all__ = [
    "COLUMNS",
    "CORRUPTIONS",
    "FORMAT",
    "JSON_CORRUPTIONS",
    "corrupt",
    "generate_run6",
    "message_names",
    "quaternion_of_rotation_vector",
    "rotation_vector_of_quaternion",
    "scenario",
    "write_corrupt_run6",
    "write_run6",
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
) -> dict[str, np.ndarray]:
    """A closed-loop record of ``scenario`` in the format's 33 columns.

    The loop is ``rig6.simulate_rig6`` (plain numpy): the spacecraft's rigid
    body stepped by the rig computer as the format's step 3 says, the table
    model (second order per pose coordinate, exact per tick; ``"inf"``: the
    ideal table), the pads' springs (and Hunt-Crossley dissipation) on the
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
    """
    kwargs, miss = _rig6_arguments(scenario)
    out = rig6.simulate_rig6(**kwargs, duration_s=duration_s)
    rate = kwargs["sample_rate_hz"]
    h = 1.0 / rate
    n = len(out["t_s"])
    n_delay = round(kwargs["sensor_delay_s"] * rate)
    q_des, q_act = out["q_des"], out["q_act"]
    w_act, w_comp = out["wrench_act"], out["wrench_comp"]  # [moment; force] on the spacecraft
    w_mea = np.zeros_like(w_act)
    w_mea[n_delay:] = w_act[: n - n_delay]

    # the twist after each tick's update
    mass = kwargs["mass_kg"]
    inertia = np.asarray(kwargs["inertia_kg_m2"], dtype=float)
    inertia = np.diag(inertia) if inertia.ndim == 1 else inertia
    inertia_inv = np.linalg.inv(inertia)
    r_port = np.array([*kwargs["lateral_offset_m"], kwargs["port_distance_m"]], dtype=float)
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
