"""Parameters of the Stewart-platform table back-end: servo gains and reference model.

:class:`StewartParams` holds the platform's geometry, the legs' digital PD
servo (:func:`heave_servo_gains` sets its default gains from a heave
bandwidth), the plant's time step, gravity, friction, the F/T sensor's
resolution and the servo's discrete reference model
(:func:`reference_matrices`). The plant built from them is in
:mod:`hybridtable.stewart.plant`; ``docs/stewart.md`` describes the model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.laws.table import second_order_tick
from hybridtable.stewart.geometry import StewartGeometry

__all__ = [
    "StewartParams",
    "heave_mass_kg",
    "heave_servo_gains",
    "reference_matrices",
]


@dataclass(frozen=True)
class StewartParams:
    """Parameters of the Stewart-platform table back-end, SI units.

    The legs are driven by a digital PD servo at the plant's time step. Two
    ways to give the table its response (see ``docs/stewart.md``):

    - with a reference model (default): the command passes through a
      discrete second-order model (``reference_response_hz``,
      ``reference_damping_ratio``) whose position and velocity stiff legs
      track; the table stays stiff under the contact force;
    - without (``reference_response_hz=None``): the leg gains alone shape the
      response (tune them with :func:`hybridtable.stewart.identify.tune_leg_gains`);
      the table is then as compliant as its response is slow.

    Parameters
    ----------
    geometry : StewartGeometry
    leg_stiffness_n_per_m, leg_damping_n_s_per_m : float or None
        PD gains Kp (> 0) and Kd (>= 0) of each leg's servo; ``None``: from
        ``servo_bandwidth_hz`` and ``servo_damping_ratio`` for the plate's
        heave mass (:func:`heave_servo_gains`).
    servo_bandwidth_hz : float or None
        Heave natural frequency of the servo loop that sets default gains;
        ``None``: ``0.08 / time_step_s`` (80 Hz at 1 ms). The explicit servo
        is stable up to about ``servo_bandwidth_hz * time_step_s = 0.1``.
    servo_damping_ratio : float
        Damping ratio of that servo loop.
    time_step_s : float
        Time step of the discrete plant and the servo's sample period, > 0.
    gravity_m_per_s2 : float
        Gravity along -z (the docking axis is +z), >= 0. The servo adds the
        static leg forces that hold the platform at home, and the sensor
        reading is compensated for the device's weight and inertia.
    friction_coefficient : float
        Coulomb friction of the contact pair, >= 0.
    sensor_resolution_n : float
        Resolution of the F/T sensor's force reading, > 0: the reading is
        rounded to a multiple of it, so the round-off of the reaction wrench
        (~1e-14 N) reads as an exact zero when the devices are apart.
    reference_response_hz : float or None
        Natural frequency of the reference model, > 0 and below the Nyquist
        rate, or ``None`` for none.
    reference_damping_ratio : float
        Damping ratio of the reference model, >= 0.
    """

    geometry: StewartGeometry = field(default_factory=StewartGeometry)
    leg_stiffness_n_per_m: float | None = None
    leg_damping_n_s_per_m: float | None = None
    servo_bandwidth_hz: float | None = None
    servo_damping_ratio: float = 0.7
    time_step_s: float = 1e-3
    gravity_m_per_s2: float = 9.81
    friction_coefficient: float = 0.3
    sensor_resolution_n: float = 1e-6
    reference_response_hz: float | None = 25.0
    reference_damping_ratio: float = 0.8

    def __post_init__(self) -> None:
        s = object.__setattr__
        if not isinstance(self.geometry, StewartGeometry):
            raise ParameterError(f"geometry must be a StewartGeometry (got {self.geometry!r})")
        for name in ("time_step_s", "sensor_resolution_n"):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in (
            "servo_damping_ratio",
            "gravity_m_per_s2",
            "friction_coefficient",
            "reference_damping_ratio",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.leg_stiffness_n_per_m is not None:
            s(
                self,
                "leg_stiffness_n_per_m",
                check_positive("leg_stiffness_n_per_m", self.leg_stiffness_n_per_m),
            )
        if self.leg_damping_n_s_per_m is not None:
            s(
                self,
                "leg_damping_n_s_per_m",
                check_nonnegative("leg_damping_n_s_per_m", self.leg_damping_n_s_per_m),
            )
        if self.servo_bandwidth_hz is not None:
            f_s = check_positive("servo_bandwidth_hz", self.servo_bandwidth_hz)
            s(self, "servo_bandwidth_hz", f_s)
            if self.leg_stiffness_n_per_m is None and f_s * self.time_step_s > 0.1:
                raise ParameterError(
                    f"servo_bandwidth_hz {f_s:g} is too fast for time_step_s "
                    f"{self.time_step_s:g} (need servo_bandwidth_hz * time_step_s <= 0.1)"
                )
        if self.reference_response_hz is not None:
            f = check_positive("reference_response_hz", self.reference_response_hz)
            if f * self.time_step_s >= 0.5:
                raise ParameterError(
                    "reference_response_hz must be below the Nyquist rate "
                    f"{0.5 / self.time_step_s:g} Hz (got {f!r})"
                )
            s(self, "reference_response_hz", f)

    @property
    def effective_servo_bandwidth_hz(self) -> float:
        """``servo_bandwidth_hz``, or its default ``0.08 / time_step_s``."""
        if self.servo_bandwidth_hz is None:
            return 0.08 / self.time_step_s
        return self.servo_bandwidth_hz

    def servo_gains(self) -> tuple[float, float]:
        """The legs' (Kp, Kd): the given ones, or from the servo bandwidth."""
        kp, kd = heave_servo_gains(
            self.geometry, self.effective_servo_bandwidth_hz, self.servo_damping_ratio
        )
        if self.leg_stiffness_n_per_m is not None:
            kp = self.leg_stiffness_n_per_m
        if self.leg_damping_n_s_per_m is not None:
            kd = self.leg_damping_n_s_per_m
        return kp, kd

    def with_gains(self, stiffness_n_per_m: float, damping_n_s_per_m: float) -> StewartParams:
        """A copy with other leg servo gains."""
        return replace(
            self, leg_stiffness_n_per_m=stiffness_n_per_m, leg_damping_n_s_per_m=damping_n_s_per_m
        )

    def with_reference(self, response_hz: float | None, damping_ratio: float) -> StewartParams:
        """A copy with another reference model (``None``: none)."""
        return replace(
            self, reference_response_hz=response_hz, reference_damping_ratio=damping_ratio
        )


def heave_mass_kg(geometry: StewartGeometry) -> float:
    """Rough mass moving with the plate in heave: plate, device, pistons and a
    third of each cylinder."""
    g = geometry
    return g.plate_mass_kg + g.device_mass_kg + 6.0 * (g.piston_mass_kg + g.cylinder_mass_kg / 3)


def heave_servo_gains(
    geometry: StewartGeometry, bandwidth_hz: float, damping_ratio: float
) -> tuple[float, float]:
    """Leg gains (Kp, Kd) giving the plate's heave (rigid-body estimate) the
    natural frequency ``bandwidth_hz`` and damping ratio ``damping_ratio``:
    the heave stiffness is ``Kp sum(u_z^2)`` with ``u`` the leg directions."""
    w = 2.0 * math.pi * check_positive("bandwidth_hz", bandwidth_hz)
    z = check_nonnegative("damping_ratio", damping_ratio)
    uz = geometry.home_leg_directions[:, 2]
    scale = heave_mass_kg(geometry) / float(np.sum(uz * uz))
    return scale * w * w, 2.0 * z * w * scale


def reference_matrices(
    params: StewartParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Discrete (A, B, C, D) of the servo's reference model, exact for a
    command held over each time step: state and output ``[p_r, v_r]``, input
    ``[p_des, v_des]`` (``v_des`` unused)."""
    if params.reference_response_hz is None:
        raise ParameterError("these StewartParams have no reference model")
    Phi, gamma = second_order_tick(
        params.reference_response_hz, params.reference_damping_ratio, params.time_step_s
    )
    B = np.zeros((2, 2))
    B[:, 0] = gamma
    return Phi, B, np.eye(2), np.zeros((2, 2))
