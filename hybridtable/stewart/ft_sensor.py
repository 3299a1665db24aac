"""The F/T sensor's payload compensation: the contact wrench from the sensor's reading.

The 6-axis force/torque sensor sits between the Stewart platform's top plate
and the active docking device (the plant's weld of the device to the plate,
:mod:`hybridtable.stewart.plant`). It measures the wrench the plate exerts on
the device, which carries the device's own weight and inertia besides the
contact. A rig's sensor with *payload compensation* reports the contact
wrench instead; :func:`payload_compensated_wrench` is that law, written once
for the two back-ends that read it
(:class:`~hybridtable.stewart.backend.DeviceSensor`, the axial force, and
:class:`~hybridtable.six_dof.stewart_backend.PoseDeviceSensor`, the full
wrench).

Frames. W is the world (any inertial frame with gravity ``g``); D is the
device's frame, whose origin ``o`` is the sensor's reference point and whose
rotation in W is ``R`` (W <- D). The device is one rigid body of mass ``m``,
centre of mass ``c`` at ``r = R c_D`` from ``o``, and rotational inertia
``I_D`` about ``c`` (axes of D; ``I = R I_D R^T`` in W). Its motion is the
angular velocity ``w``, the angular acceleration ``dw`` and the acceleration
``a_o`` of its origin, all in W. The sensor reads the force ``f_s`` and the
torque ``t_s`` about ``o``, both on the device, in D.

The law. Three wrenches act on the device: the sensor's, its weight ``m g``
at ``c`` and the contact's ``(f, t)``. By Newton–Euler, with
``a_c = a_o + dw x r + w x (w x r)`` the acceleration of the centre of mass:

- Newton: ``m a_c = R f_s + f + m g``, so ``f = m (a_c - g) - R f_s``;
- Euler about ``c``: ``I dw + w x I w = (R t_s - r x R f_s) + t_c``, so
  ``t_c = I dw + w x I w - (R t_s - r x R f_s)``;
- about a point ``p`` fixed on the device at ``R p_D`` from ``o``:
  ``t_p = t_c + (r - R p_D) x f``.

The result is ``[t_p; f]`` in W (N m, N): the contact wrench on the device.
A device that moves, spins and hangs in gravity with nothing touching it
reads zero; a device at rest reads the contact alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from pydrake.systems.framework import LeafSystem

from hybridtable.laws.compiled import compiled_kernel
from hybridtable.stewart.geometry import cross, rotation_from_quaternion

if TYPE_CHECKING:
    from hybridtable.stewart.plant import StewartPlant

__all__ = ["DevicePayload", "DeviceSensorBase", "device_payload", "payload_compensated_wrench"]


@dataclass(frozen=True)
class DevicePayload:
    """The payload a sensor compensates: the rigid device beyond the sensor.

    Attributes
    ----------
    mass_kg : float
        The device's mass ``m``.
    com_m : ndarray (3,)
        Its centre of mass ``c_D`` in its frame D (m from the sensor's origin).
    inertia_kg_m2 : ndarray (3, 3)
        Its rotational inertia ``I_D`` about the centre of mass, axes of D.
    gravity_m_per_s2 : ndarray (3,)
        The gravity vector ``g`` in the world W.
    """

    mass_kg: float
    com_m: np.ndarray
    inertia_kg_m2: np.ndarray
    gravity_m_per_s2: np.ndarray


def device_payload(handles: StewartPlant) -> DevicePayload:
    """The payload of the platform's F/T sensor: the device welded to the
    plate (its mass, centre of mass and central inertia as the plant has
    them) in the plant's gravity along ``-z``."""
    device = handles.device
    com = np.array(device.default_com())
    inertia = device.default_spatial_inertia().Shift(com).CalcRotationalInertia()
    return DevicePayload(
        mass_kg=handles.geometry.device_mass_kg,
        com_m=com,
        inertia_kg_m2=inertia.CopyToFullMatrix3(),
        gravity_m_per_s2=np.array([0.0, 0.0, -handles.params.gravity_m_per_s2]),
    )


def payload_compensated_wrench(
    payload: DevicePayload,
    rotation: np.ndarray,
    angular_velocity_rad_per_s: Sequence[float],
    angular_acceleration_rad_per_s2: Sequence[float],
    origin_acceleration_m_per_s2: Sequence[float],
    sensor_torque_n_m: Sequence[float],
    sensor_force_n: Sequence[float],
    moment_point_m: np.ndarray | None = None,
) -> np.ndarray:
    """The contact wrench on the device from the sensor's reading (see the module).

    Parameters
    ----------
    payload : DevicePayload
        The device beyond the sensor.
    rotation : ndarray (3, 3)
        ``R``: the device frame D in the world W (W <- D).
    angular_velocity_rad_per_s, angular_acceleration_rad_per_s2 : array (3,)
        ``w`` and ``dw`` of the device, in W.
    origin_acceleration_m_per_s2 : array (3,)
        ``a_o``: the acceleration of D's origin (the sensor's point), in W.
    sensor_torque_n_m, sensor_force_n : array (3,)
        The sensor's reading on the device, ``t_s`` about D's origin and
        ``f_s``, in D.
    moment_point_m : ndarray (3,), optional
        ``p_D``: the point of the device (in D, m) about which the moment is
        reported; default D's origin.

    Returns
    -------
    ndarray (6,)
        ``[t_p; f]``: the contact's moment about the point (N m) and force
        (N) on the device, in W.
    """
    return _compensate(
        payload.mass_kg,
        np.asarray(payload.com_m, dtype=float),
        np.asarray(payload.inertia_kg_m2, dtype=float),
        np.asarray(payload.gravity_m_per_s2, dtype=float),
        np.asarray(rotation, dtype=float),
        np.asarray(angular_velocity_rad_per_s, dtype=float),
        np.asarray(angular_acceleration_rad_per_s2, dtype=float),
        np.asarray(origin_acceleration_m_per_s2, dtype=float),
        np.asarray(sensor_torque_n_m, dtype=float),
        np.asarray(sensor_force_n, dtype=float),
        np.zeros(3) if moment_point_m is None else np.asarray(moment_point_m, dtype=float),
    )


def _compensate(mass, com, inertia, gravity, R, w, dw, a_o, t_s, f_s, point) -> np.ndarray:
    """:func:`payload_compensated_wrench` on arrays (``point``: ``p_D``, zeros
    for D's origin), the law written once: numba compiles it for the sensors."""
    f_sensor = R @ f_s
    t_sensor = R @ t_s  # about D's origin
    r = R @ com
    a_com = a_o + cross(dw, r) + cross(w, cross(w, r))
    # Newton: m a_com = f_sensor + f_contact + m g.
    f = mass * (a_com - gravity) - f_sensor
    # Euler about the centre of mass: I dw + w x I w = t_sensor,com + t_contact,com.
    I_w = R @ inertia @ R.T
    t_com = I_w @ dw + cross(w, I_w @ w) - (t_sensor - cross(r, f_sensor))
    # About the point.
    arm = r - R @ point
    return np.concatenate((t_com + cross(arm, f), f))


def _reading(x, a, quaternion_start, velocity_start, mass, com, inertia, gravity, t_s, f_s, point):
    """``(R, wrench)``: the plate's rotation and the compensated wrench, from
    the plant's state ``x`` (the plate's quaternion at ``quaternion_start``,
    its angular velocity at ``velocity_start``), the plate's accelerations
    ``a = [dw; dv]`` and the sensor's reading ``t_s``, ``f_s``."""
    R = rotation_from_quaternion(x[quaternion_start : quaternion_start + 4])
    w = x[velocity_start : velocity_start + 3]
    return R, _compensate(mass, com, inertia, gravity, R, w, a[0:3], a[3:6], t_s, f_s, point)


#: The plain functions the kernels call.
_HELPERS = (cross, rotation_from_quaternion, _compensate)


class DeviceSensorBase(LeafSystem):
    """The F/T sensor on the active device: the plant's ports it reads, the
    plate's pose and twist, and the payload-compensated contact wrench
    (:func:`~hybridtable.stewart.ft_sensor.payload_compensated_wrench`). The
    1-D :class:`~hybridtable.stewart.backend.DeviceSensor` reads its axial component, the 6-DoF
    :class:`~hybridtable.six_dof.stewart_backend.PoseDeviceSensor` all of it.

    Input ``plant_state``, ``generalized_acceleration``, ``reaction_forces``
        From the plant.
    """

    def __init__(self, handles: StewartPlant) -> None:
        LeafSystem.__init__(self)
        plant = handles.plant
        self._nq = plant.num_positions()
        self._iq = handles.plate_position_start
        self._iv = handles.plate_velocity_start
        self._payload = device_payload(handles)
        self._weld = int(handles.sensor_weld.index())
        self._resolution = handles.params.sensor_resolution_n
        self._state = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        self._accel = self.DeclareVectorInputPort(
            "generalized_acceleration", plant.num_velocities()
        )
        self._reading = compiled_kernel(_reading, _HELPERS)
        self._origin = np.zeros(3)
        self._reaction = self.DeclareAbstractInputPort(
            "reaction_forces", plant.get_reaction_forces_output_port().Allocate()
        )

    def _pose_twist(self, x):
        q = x[self._iq : self._iq + 7]
        v = x[self._nq + self._iv : self._nq + self._iv + 6]
        return rotation_from_quaternion(q[:4]), q[4:], v[:3], v[3:]

    def _weld_wrench(self, context):
        """The weld's reaction on the device (a ``SpatialForce``, device frame)."""
        return self._reaction.Eval(context)[self._weld]

    def _compensated(self, context, moment_point_m=None):
        """``(R, w, dw, dv, wrench)``: the plate's rotation, angular velocity
        and accelerations, and the payload-compensated contact wrench (W, moment
        about ``moment_point_m`` in the plate frame, default its origin)."""
        x = self._state.Eval(context)
        a = self._accel.Eval(context)[self._iv : self._iv + 6]
        F = self._weld_wrench(context)
        p = self._payload
        R, wrench = self._reading(
            x,
            a,
            self._iq,
            self._nq + self._iv,
            p.mass_kg,
            p.com_m,
            p.inertia_kg_m2,
            p.gravity_m_per_s2,
            F.rotational(),
            F.translational(),
            self._origin if moment_point_m is None else moment_point_m,
        )
        w = x[self._nq + self._iv : self._nq + self._iv + 3]
        return R, w, a[:3], a[3:], wrench
