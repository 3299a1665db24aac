"""The F/T sensor's payload compensation against physical facts with a closed
form: statics of a known contact, a free-falling spinning device, and the
momentum balance of a device driven through an arbitrary motion (the sensor's
reading from finite differences of the device's momenta, not from the law)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from hybridtable.stewart.ft_sensor import (
    DevicePayload,
    device_payload,
    payload_compensated_wrench,
)
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.plant import add_stewart_plant

G = np.array([0.0, 0.0, -9.81])
MASS_KG = 2.3
COM_M = np.array([0.02, -0.01, 0.12])
#: A full (non-diagonal) central inertia, positive definite (kg m^2).
INERTIA_KG_M2 = np.array([[0.030, 0.002, -0.001], [0.002, 0.025, 0.003], [-0.001, 0.003, 0.011]])
PAYLOAD = DevicePayload(MASS_KG, COM_M, INERTIA_KG_M2, G)


def _rot(axis, angle: float) -> np.ndarray:
    """Rotation by ``angle`` about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


R_TILT = _rot([0.3, -0.5, 0.8], 0.7)


@pytest.mark.parametrize("point", [None, np.array([0.0, 0.0, 0.2])])
def test_static_contact_reads_the_force_and_its_moment(point):
    """Device at rest, tilted, a known contact force F at a known point Q of
    the device: the sensor carries F and the weight (statics), and the
    compensated reading is F with the moment (Q - P) x F about the point P."""
    q_body = np.array([0.01, 0.015, 0.2])  # where the contact acts (device frame, m)
    f_contact = np.array([12.0, -7.0, -250.0])  # N, world
    q, r = R_TILT @ q_body, R_TILT @ COM_M
    # Equilibrium about the origin: sensor + contact + weight = 0.
    f_sensor = -(f_contact + MASS_KG * G)
    t_sensor = -(np.cross(q, f_contact) + np.cross(r, MASS_KG * G))
    zero = np.zeros(3)
    wrench = payload_compensated_wrench(
        PAYLOAD, R_TILT, zero, zero, zero, R_TILT.T @ t_sensor, R_TILT.T @ f_sensor, point
    )
    p = zero if point is None else R_TILT @ point
    np.testing.assert_allclose(wrench[3:], f_contact, rtol=0, atol=1e-12)
    np.testing.assert_allclose(wrench[:3], np.cross(q - p, f_contact), rtol=0, atol=1e-12)


def test_free_falling_spinning_device_reads_zero():
    """No contact, no sensor load: the device falls freely (its centre of mass
    accelerates at g) while spinning steadily about a principal axis through
    the centre of mass, so its origin accelerates at g - w x (w x r): the
    compensated reading is zero."""
    axes = np.linalg.eigh(INERTIA_KG_M2)[1]
    omega = R_TILT @ axes[:, 0] * 3.0  # rad/s, world
    r = R_TILT @ COM_M
    a_origin = G - np.cross(omega, np.cross(omega, r))
    zero = np.zeros(3)
    wrench = payload_compensated_wrench(PAYLOAD, R_TILT, omega, zero, a_origin, zero, zero)
    np.testing.assert_allclose(wrench, 0.0, rtol=0, atol=1e-13)
    # The same spin without the fall: the sensor must hold the weight; a
    # sensor reading nothing means a contact lifts the device by -m g.
    a_origin = -np.cross(omega, np.cross(omega, r))
    wrench = payload_compensated_wrench(PAYLOAD, R_TILT, omega, zero, a_origin, zero, zero)
    np.testing.assert_allclose(wrench[3:], -MASS_KG * G, rtol=0, atol=1e-12)


def test_arbitrary_motion_without_contact_reads_zero():
    """The device driven (by the sensor alone) through an accelerating,
    tumbling motion ``R(t) = Rz(a(t)) Rx(b(t))``, origin on a cubic: the
    sensor's reading is the rate of the device's momenta, taken here by
    central differences (linear momentum of the centre of mass, angular
    momentum ``I_W w`` about it) minus the weight; the compensated reading,
    from the analytic w, dw and a_o, is zero to the differences' accuracy."""
    t0, h = 0.3, 1e-4

    def alpha(t):
        return 0.4 + 2.0 * t + 3.0 * t * t, 2.0 + 6.0 * t, 6.0

    def beta(t):
        return -0.2 + 1.5 * t - 4.0 * t**3, 1.5 - 12.0 * t * t, -24.0 * t

    def rotation(t):
        return _rot([0, 0, 1], alpha(t)[0]) @ _rot([1, 0, 0], beta(t)[0])

    def angular_velocity(t):
        x = _rot([0, 0, 1], alpha(t)[0])[:, 0]  # Rz(a) x: the second axis in W
        return alpha(t)[1] * np.array([0.0, 0.0, 1.0]) + beta(t)[1] * x

    def origin(t):
        return np.array([0.1 * t**3, -0.5 * t * t, 0.2 * t + 0.3 * t**3])

    def com(t):
        return origin(t) + rotation(t) @ COM_M

    def spin_momentum(t):
        R = rotation(t)
        return R @ INERTIA_KG_M2 @ R.T @ angular_velocity(t)

    # The sensor's reading, from the momenta's rates (no contact).
    a_com = (com(t0 + h) - 2.0 * com(t0) + com(t0 - h)) / (h * h)
    dH = (spin_momentum(t0 + h) - spin_momentum(t0 - h)) / (2.0 * h)
    f_sensor = MASS_KG * (a_com - G)
    r = rotation(t0) @ COM_M
    t_sensor = dH + np.cross(r, f_sensor)  # about the origin
    # The analytic motion the law is given.
    a, b = alpha(t0), beta(t0)
    x = _rot([0, 0, 1], a[0])[:, 0]
    z = np.array([0.0, 0.0, 1.0])
    w = angular_velocity(t0)
    dw = a[2] * z + b[2] * x + b[1] * a[1] * np.cross(z, x)
    a_origin = np.array([0.6 * t0, -1.0, 1.8 * t0])
    R = rotation(t0)
    wrench = payload_compensated_wrench(
        PAYLOAD, R, w, dw, a_origin, R.T @ t_sensor, R.T @ f_sensor, np.array([0.0, 0.0, 0.2])
    )
    # The inertial terms are newtons and a tenth of a N m, far above the tolerance.
    assert np.linalg.norm(f_sensor + MASS_KG * G) > 2.0
    assert np.linalg.norm(dH) > 0.1
    np.testing.assert_allclose(wrench, 0.0, rtol=0, atol=1e-6)


def test_device_payload_is_the_plant_s_rod():
    """The platform's device: its mass, the centre of mass halfway along the
    rod, the rod's central inertia m L^2 / 12 across it, and gravity -g z."""
    params = StewartParams()
    handles = add_stewart_plant(DiagramBuilder(), params, 1e5)
    payload = device_payload(handles)
    g = params.geometry
    assert payload.mass_kg == g.device_mass_kg
    np.testing.assert_allclose(payload.com_m, [0.0, 0.0, g.device_length_m / 2])
    transverse = g.device_mass_kg * g.device_length_m**2 / 12.0
    np.testing.assert_allclose(np.diag(payload.inertia_kg_m2)[:2], transverse, rtol=1e-12)
    np.testing.assert_allclose(payload.gravity_m_per_s2, [0.0, 0.0, -params.gravity_m_per_s2])
