"""What a six-axis rig's physical part does differently from its scenario:
the 6-DoF counterpart of the 1-D :class:`~hybridtable.measurement.rig.RigPhysics`.

A :class:`DockingPhysics` is what the 6-DoF effects change
(:attr:`~hybridtable.effects.effect.Effect.apply6`):

- ``changes``: quantities of the scenario by flat name
  (:data:`~hybridtable.six_dof.params.DockingLoopParams.FIELDS`) that the real
  contact, table or sensor has otherwise: a stiffer contact, a longer sensor
  delay; ``offsets`` and ``factors`` change one relative to the scenario's
  value (friction across the face added to the stated coefficient, the
  table's damping ratio times a factor). The rig computer keeps the
  scenario's (its compensator believes them, its spacecraft is the
  scenario's);
- ``sensor_gain`` (6x6): the F/T sensor reads ``G w`` where the contact
  applies ``w = [moment; force]`` (W, about the port): a sensor frame turned
  by ``R`` is ``G = diag(R, R)``, cross-talk between channels an off-diagonal
  ``G``;
- ``table_gain`` (6x6): the table reaches ``T q`` where it is commanded to
  pose ``q = [p; theta]`` (and ``T qd`` for the twist): its axes turned or
  coupled;
- ``sensor_time_constant_s``: the sensor's reading through a first-order low
  pass on each channel (a compliant mount, a filter; the 1-D measurement
  chain's law, before the delay), ``sensor_mount`` (``(f, zeta)``: Hz, 1): the
  sensor on a compliant mount, each channel ringing as the 1-D chain's mount
  (after the low pass, before the delay), and ``sensor_bias`` (6): an offset
  of the reading (after the delay);
- ``table_mode`` (``(f, zeta)``: Hz, 1): a structural mode between the
  table's servo and its device on each pose coordinate (the 1-D
  ``table_resonance``'s law; the table model only);
- ``com_offset_m`` (3) and, in ``offsets`` and ``factors``, the
  compensator's lead and stiffness (:data:`COMPUTER_FIELDS`): changes of the
  rig *computer*: its spacecraft model's centre of mass this far from the
  scenario's (body frame), so its port sits at ``port_position_m -
  com_offset_m`` from it; its lead offset from, its contact model's
  stiffness scaled from what it believes (:meth:`DockingPhysics.computer`).
  The replay of the physical part does not see them; the audits of the
  computer's arithmetic do (:mod:`~hybridtable.six_dof.audit6`,
  :mod:`~hybridtable.six_dof.audit_law6`).

They are Drake primitives in the diagram (``MatrixGain``, a discrete
``LinearSystem``, ``Adder``: :func:`~hybridtable.six_dof.builder.add_rig_part`),
in the closed loop (:func:`~hybridtable.six_dof.builder.add_docking_loop`)
and the replay (:func:`~hybridtable.six_dof.replay6.replay_run6`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from hybridtable.effects.effect import Effect
from hybridtable.effects.registry import apply_in_order
from hybridtable.effects.spec import RigScale
from hybridtable.errors import ParameterError
from hybridtable.six_dof.devices import PAD_LAW_FIELDS
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.pose import rotation_exp

__all__ = [
    "COMPUTER_FIELDS",
    "DockingPhysics",
    "NOMINAL_PHYSICS",
    "PHYSICAL_FIELDS",
    "physics_with",
    "rig_scale",
]

#: The rig computer's compensator's constants an effect may offset or scale
#: from what it believes (:meth:`DockingPhysics.computer`): its lead (s, offset)
#: and its contact model's stiffness (a factor; of a given matrix, the matrix's).
COMPUTER_FIELDS: tuple[str, ...] = ("lead_time_s", "compensator_stiffness_n_per_m")

#: The scenario's own quantities an effect may change (the rig computer's
#: beliefs, the approach and the spacecraft are the scenario's, never the rig's).
PHYSICAL_FIELDS: tuple[str, ...] = (
    "contact_stiffness_n_per_m",
    "contact_dissipation_s_per_m",
    "friction_coefficient",
    "sensor_delay_s",
    "table_response_hz",
    "table_damping_ratio",
    *PAD_LAW_FIELDS,  # the pads' law beyond Drake's
)


def _matrix(name: str, value: Any) -> tuple[tuple[float, ...], ...] | None:
    if value is None:
        return None
    m = np.asarray(value, dtype=float)
    if m.shape != (6, 6) or not np.all(np.isfinite(m)):
        raise ParameterError(f"{name} must be a finite 6x6 matrix (got shape {m.shape})")
    return tuple(tuple(float(x) for x in row) for row in m)


@dataclass(frozen=True)
class DockingPhysics:
    """The rig's physical part as it is (see the module); the default is the
    scenario's own."""

    changes: Mapping[str, Any] = field(default_factory=dict)
    sensor_gain: tuple[tuple[float, ...], ...] | None = None
    table_gain: tuple[tuple[float, ...], ...] | None = None
    offsets: Mapping[str, float] = field(default_factory=dict)
    factors: Mapping[str, float] = field(default_factory=dict)
    sensor_time_constant_s: float = 0.0
    #: The sensor mount's natural frequency (Hz) and damping ratio (1), or None.
    sensor_mount: tuple[float, float] | None = None
    #: The reading's offset ``[m; f]`` (N m, N).
    sensor_bias: tuple[float, ...] | None = None
    #: The rig computer's centre of mass from the scenario's, body frame (m).
    com_offset_m: tuple[float, float, float] | None = None
    #: A structural mode between the table's servo and its device: natural
    #: frequency (Hz) and damping ratio (1), or None.
    table_mode: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("changes", "offsets", "factors"):
            given = dict(getattr(self, name))
            allowed = PHYSICAL_FIELDS + (COMPUTER_FIELDS if name != "changes" else ())
            unknown = [k for k in given if k not in allowed]
            if unknown:
                raise ParameterError(
                    f"a 6-DoF effect may change {', '.join(allowed)} (got {unknown[0]!r})"
                )
            object.__setattr__(self, name, given)  # a copy (picklable for workers)
        object.__setattr__(self, "sensor_gain", _matrix("sensor_gain", self.sensor_gain))
        object.__setattr__(self, "table_gain", _matrix("table_gain", self.table_gain))
        tau = float(self.sensor_time_constant_s)
        if not (math.isfinite(tau) and tau >= 0.0):
            raise ParameterError(f"sensor_time_constant_s must be >= 0 (got {tau!r})")
        object.__setattr__(self, "sensor_time_constant_s", tau)
        for name in ("sensor_mount", "table_mode"):
            value = getattr(self, name)
            if value is None:
                continue
            f, zeta = (float(x) for x in value)
            if not (math.isfinite(f) and f > 0.0 and math.isfinite(zeta) and zeta > 0.0):
                raise ParameterError(
                    f"{name} must be a frequency > 0 Hz and a damping ratio > 0 (got {value!r})"
                )
            object.__setattr__(self, name, (f, zeta))
        if self.sensor_bias is not None:
            bias = np.asarray(self.sensor_bias, dtype=float)
            if bias.shape != (6,) or not np.all(np.isfinite(bias)):
                raise ParameterError("sensor_bias must be 6 finite numbers [N m, N]")
            object.__setattr__(self, "sensor_bias", tuple(float(x) for x in bias))
        if self.com_offset_m is not None:
            com = np.asarray(self.com_offset_m, dtype=float)
            if com.shape != (3,) or not np.all(np.isfinite(com)):
                raise ParameterError("com_offset_m must be 3 finite numbers [m]")
            object.__setattr__(self, "com_offset_m", tuple(float(x) for x in com))

    @property
    def nominal(self) -> bool:
        return not (self.changes or self.offsets or self.factors) and (
            self.sensor_gain is None
            and self.table_gain is None
            and self.sensor_time_constant_s == 0.0
            and self.sensor_mount is None
            and self.sensor_bias is None
            and self.com_offset_m is None
            and self.table_mode is None
        )

    def low_pass(self, time_constant_s: float) -> DockingPhysics:
        """The sensor's reading through a first-order low pass of this time
        constant (s; the 1-D ``sensor_filter``'s law on each channel)."""
        return replace(self, sensor_time_constant_s=float(time_constant_s))

    def mount(self, frequency_hz: float, damping_ratio: float) -> DockingPhysics:
        """The sensor on a compliant mount of this natural frequency (Hz) and
        damping ratio: each channel reads ``y'' = w^2 (u - y) - 2 zeta w y'``
        (the 1-D ``mount_resonance``'s law)."""
        return replace(self, sensor_mount=(float(frequency_hz), float(damping_ratio)))

    def resonant(self, frequency_hz: float, damping_ratio: float) -> DockingPhysics:
        """A structural mode of this natural frequency (Hz) and damping ratio
        between the table's servo and its device, on each pose coordinate
        (the 1-D ``table_resonance``'s law)."""
        return replace(self, table_mode=(float(frequency_hz), float(damping_ratio)))

    def biased(self, bias: Any) -> DockingPhysics:
        """The sensor's reading offset by ``bias`` (6: N m, N; added to earlier ones)."""
        old = np.zeros(6) if self.sensor_bias is None else np.array(self.sensor_bias)
        return replace(self, sensor_bias=old + np.asarray(bias, dtype=float))

    def with_(self, **changes: Any) -> DockingPhysics:
        """These quantities changed (by flat name)."""
        return replace(self, changes={**self.changes, **changes})

    def plus(self, **offsets: float) -> DockingPhysics:
        """These quantities the scenario's plus an offset (added to earlier ones)."""
        total = {k: self.offsets.get(k, 0.0) + float(v) for k, v in offsets.items()}
        return replace(self, offsets={**self.offsets, **total})

    def times(self, **factors: float) -> DockingPhysics:
        """These quantities the scenario's times a factor (times earlier ones)."""
        total = {k: self.factors.get(k, 1.0) * float(v) for k, v in factors.items()}
        return replace(self, factors={**self.factors, **total})

    def times_sensor(self, gain: np.ndarray) -> DockingPhysics:
        """The sensor reading ``gain`` times what it read."""
        old = np.eye(6) if self.sensor_gain is None else np.array(self.sensor_gain)
        return replace(self, sensor_gain=np.asarray(gain) @ old)

    def times_table(self, gain: np.ndarray) -> DockingPhysics:
        """The table reaching ``gain`` times what it reached."""
        old = np.eye(6) if self.table_gain is None else np.array(self.table_gain)
        return replace(self, table_gain=np.asarray(gain) @ old)

    def turn_sensor(self, rotation_vector_rad: Any) -> DockingPhysics:
        """The F/T sensor's reading turned by ``R = exp(theta)``: it reads
        ``[R m; R f]`` of the wrench ``[m; f]`` (its frame turned by ``R^T``)."""
        R = rotation_exp(np.asarray(rotation_vector_rad, dtype=float))
        return self.times_sensor(np.block([[R, np.zeros((3, 3))], [np.zeros((3, 3)), R]]))

    def turn_table(self, rotation_vector_rad: Any) -> DockingPhysics:
        """The table's axes turned by ``exp(theta)``: commanded to ``[p;
        theta]`` it reaches ``[R p; R theta]`` (the rotation vector turned to
        first order)."""
        R = rotation_exp(np.asarray(rotation_vector_rad, dtype=float))
        return self.times_table(np.block([[R, np.zeros((3, 3))], [np.zeros((3, 3)), R]]))

    def shift_com(self, offset_m: Any) -> DockingPhysics:
        """The rig computer's centre of mass moved by ``offset_m`` (3, body
        frame, m; added to earlier ones)."""
        old = np.zeros(3) if self.com_offset_m is None else np.array(self.com_offset_m)
        return replace(self, com_offset_m=old + np.asarray(offset_m, dtype=float))

    def computer(self, params: DockingLoopParams) -> DockingLoopParams:
        """The rig computer's parameters: ``params`` with its spacecraft's
        centre of mass moved by :attr:`com_offset_m` (the port's position from
        it less the offset; the body's mass and inertia are the scenario's),
        and its compensator's lead and stiffness offset and scaled from what it
        believes (:data:`COMPUTER_FIELDS` in :attr:`offsets` and
        :attr:`factors`; a lead below 0 is 0)."""
        values: dict[str, Any] = {}
        if self.com_offset_m is not None:
            port = params.spacecraft.port_position_m - np.array(self.com_offset_m)
            values.update(lateral_offset_m=(port[0], port[1]), port_distance_m=port[2])
        if "lead_time_s" in self.offsets:
            values["lead_time_s"] = max(
                0.0, params.effective_lead_time_s + self.offsets["lead_time_s"]
            )
        factor = self.factors.get("compensator_stiffness_n_per_m")
        if factor is not None and params.stiffness_model == "given":
            K = np.array(params.compensator_stiffness_matrix) * factor
            values["compensator_stiffness_matrix"] = K
        elif factor is not None:
            values["compensator_stiffness_n_per_m"] = (
                factor * params.believed_contact.contact_stiffness_n_per_m
            )
        return params.with_(**values) if values else params

    def apply(self, params: DockingLoopParams) -> DockingLoopParams:
        """The loop's parameters of the rig's physical part (the contact, the
        table, the sensor): ``params`` with :attr:`changes`, then the
        :attr:`offsets` and :attr:`factors` on their values (a friction or a
        delay below 0 is 0).

        Raises
        ------
        ParameterError
            A change the rig cannot take: a term of the pads' law on a drogue
            or on the Stewart platform's plant, a structural mode of the table
            on the Stewart platform (its dynamics are its MultibodyPlant's).
        """
        if self.table_mode is not None and params.table == "stewart":
            raise ParameterError(
                "a structural mode of the table (table_resonance) acts on the table model "
                "only: the Stewart platform's dynamics are its MultibodyPlant's"
            )
        values: dict[str, Any] = dict(self.changes)
        for name, delta in self.offsets.items():
            if name in PHYSICAL_FIELDS:
                values[name] = max(0.0, float(values.get(name, getattr(params, name))) + delta)
        for name, factor in self.factors.items():
            if name in PHYSICAL_FIELDS:
                values[name] = float(values.get(name, getattr(params, name))) * factor
        return params.with_(**values) if values else params

    def to_dict(self) -> dict:
        return {
            "changes": dict(self.changes),
            "offsets": dict(self.offsets),
            "factors": dict(self.factors),
            "sensor_gain": None
            if self.sensor_gain is None
            else [list(r) for r in self.sensor_gain],
            "table_gain": None if self.table_gain is None else [list(r) for r in self.table_gain],
            "sensor_time_constant_s": self.sensor_time_constant_s,
            "sensor_mount": None if self.sensor_mount is None else list(self.sensor_mount),
            "sensor_bias": None if self.sensor_bias is None else list(self.sensor_bias),
            "com_offset_m": None if self.com_offset_m is None else list(self.com_offset_m),
            "table_mode": None if self.table_mode is None else list(self.table_mode),
        }


#: The scenario's own physics.
NOMINAL_PHYSICS = DockingPhysics()


def rig_scale(params: DockingLoopParams) -> RigScale:
    """The magnitudes an effect's bounds are taken at: the scenario's contact
    stiffness, spacecraft mass, tick, delay, approach speed and table."""
    return RigScale.from_params(params, params.sample_period_s)


def physics_with(
    effects: Sequence[tuple[Effect, Mapping[str, float]]],
    scale: RigScale,
    base: DockingPhysics = NOMINAL_PHYSICS,
) -> DockingPhysics:
    """The rig's physical part with ``effects`` (each with its values) applied
    in order to ``base`` (:attr:`~hybridtable.effects.effect.Effect.apply6`).

    Raises
    ------
    ParameterError
        For an effect of the 1-D loop only.
    """
    return apply_in_order(effects, scale, base, "6-DoF")
