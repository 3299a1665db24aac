"""The spacecraft model as a rigid body in 6 DoF, integrated by the rig computer.

State (discrete, updated every tick h): position ``p`` and velocity ``v`` of
the centre of mass in the target frame W, the attitude ``R`` (body to W) and
the body-frame angular velocity ``omega_b``. At each tick the compensated
wrench ``[moment about the port origin; force]`` (W) is applied at the port:

- ``v <- v + h f / m``, ``p <- p + h v`` (semi-implicit Euler, the 1-D
  spacecraft's step: on axis the two are the same numbers);
- ``omega_b <- omega_b + h I^-1 (R^T tau - omega_b x I omega_b)``, with
  ``tau`` the moment about the centre of mass, ``R <- R exp([h omega_b]x)``.

Its output is the docking port's pose and twist: the table's command.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import LeafSystem

from hybridtable.laws.compiled import compiled_kernel
from hybridtable.six_dof.params import RigidBodyParams
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.stewart.geometry import cross, skew

__all__ = ["RigidSpacecraft", "BODY_STATE_SIZE", "port_state", "kinetic_energy_j"]

#: ``[p (3), v (3), R row-major (9), omega_b (3)]``.
BODY_STATE_SIZE = 18


def _port_state(x: np.ndarray, port_position_m: np.ndarray) -> np.ndarray:
    """:func:`port_state` on arrays (compiled by numba in the loop)."""
    p, v = x[0:3], x[3:6]
    R = np.ascontiguousarray(x[6:15]).reshape(3, 3)
    omega = R @ x[15:18]
    arm = R @ port_position_m
    return np.concatenate((p + arm, rotation_log(R), v + cross(omega, arm), omega))


def _step(
    x: np.ndarray,
    wrench: np.ndarray,
    h: float,
    mass: float,
    inertia: np.ndarray,
    inertia_inv: np.ndarray,
    port_position_m: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The body state one tick on (see the module) and its port's state (one
    call a tick, compiled by numba in the loop)."""
    p, v = x[0:3], x[3:6]
    R = np.ascontiguousarray(x[6:15]).reshape(3, 3)
    wb = x[15:18]
    f = wrench[3:6]
    tau = wrench[0:3] + cross(R @ port_position_m, f)  # about the centre of mass
    v_new = v + (h / mass) * f
    p_new = p + h * v_new
    Iw = inertia @ wb
    wb_new = wb + h * (inertia_inv @ (R.T @ tau - cross(wb, Iw)))
    R_new = _nearest_rotation(R @ rotation_exp(h * wb_new))
    new = np.concatenate((p_new, v_new, R_new.ravel(), wb_new))
    return new, _port_state(new, port_position_m)


def _nearest_rotation(M: np.ndarray) -> np.ndarray:
    """The rotation nearest a matrix ``M`` that is one to round-off: its polar
    factor, by one Newton step ``(M + M^-T) / 2`` (quadratic: from an error
    of 1e-16, exact to round-off; the SVD's ``U V^T`` costs 10x as much).
    Keeps the attitude a rotation against round-off."""
    a, b, c = M[:, 0], M[:, 1], M[:, 2]
    bc, ca, ab = cross(b, c), cross(c, a), cross(a, b)
    det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]
    out = np.empty((3, 3))
    for i in range(3):
        out[i, 0] = 0.5 * (M[i, 0] + bc[i] / det)
        out[i, 1] = 0.5 * (M[i, 1] + ca[i] / det)
        out[i, 2] = 0.5 * (M[i, 2] + ab[i] / det)
    return out


#: The plain functions the kernels call.
_HELPERS = (cross, skew, rotation_exp, rotation_log, _nearest_rotation, _port_state)


def port_state(body: RigidBodyParams, x: np.ndarray) -> np.ndarray:
    """The port's ``[p_P; theta; v_P; omega]`` (12) of a body state ``x`` (18)."""
    return _port_state(np.asarray(x, dtype=float), body.port_position_m)


def kinetic_energy_j(body: RigidBodyParams, x: np.ndarray) -> float:
    """Translational plus rotational kinetic energy of a body state (J)."""
    w = x[15:18]
    return 0.5 * body.mass_kg * float(x[3:6] @ x[3:6]) + 0.5 * float(w @ body.inertia @ w)


class RigidSpacecraft(LeafSystem):
    """The spacecraft model (see the module docstring).

    Ports
    -----
    Input ``compensated_wrench`` (6: N m, N)
        ``[moment about the port origin; force]`` in W, applied at the port.
    Output ``commanded_state`` (12: m, rad, m/s, rad/s)
        The port's pose ``[p_P; theta]`` and twist ``[v_P; omega]`` in W.
    Output ``body_state`` (18: m, m/s, 1, rad/s)
        ``[p, v, R row-major, omega_b]`` of the centre of mass.

    Parameters
    ----------
    params : RigidBodyParams
    period_s : float
        The rig computer's tick h.
    """

    def __init__(self, params: RigidBodyParams, period_s: float) -> None:
        LeafSystem.__init__(self)
        self.params = params
        self._h = float(period_s)
        self._m = params.mass_kg
        self._I = params.inertia
        self._I_inv = np.linalg.inv(self._I)
        self._arm = np.ascontiguousarray(params.port_position_m, dtype=float)
        self._step = compiled_kernel(_step, _HELPERS)
        self._wrench = self.DeclareVectorInputPort("compensated_wrench", 6)
        x0 = np.zeros(BODY_STATE_SIZE)
        x0[6:15] = np.eye(3).ravel()
        # Two groups, the body's state and its port's (a function of it, kept
        # beside it so both outputs are the state: no Python per evaluation).
        self._x = self.DeclareDiscreteState(x0)
        self._port = self.DeclareDiscreteState(port_state(params, x0))
        self.DeclarePeriodicDiscreteUpdateEvent(self._h, 0.0, self._update)
        self.DeclareStateOutputPort("commanded_state", self._port)
        self.DeclareStateOutputPort("body_state", self._x)

    def initial_state(
        self,
        port_position_m: np.ndarray,
        rotation: np.ndarray,
        velocity_m_per_s: np.ndarray,
        angular_velocity_rad_per_s: np.ndarray | None = None,
    ) -> np.ndarray:
        """The body state (18) with the port at ``port_position_m`` (W), the
        attitude ``rotation`` and the centre of mass moving at
        ``velocity_m_per_s``, turning at ``angular_velocity_rad_per_s`` (body
        frame; default not at all)."""
        R = np.asarray(rotation, dtype=float)
        x = np.zeros(BODY_STATE_SIZE)
        x[0:3] = np.asarray(port_position_m) - R @ self._arm
        x[3:6] = velocity_m_per_s
        x[6:15] = R.ravel()
        if angular_velocity_rad_per_s is not None:
            x[15:18] = angular_velocity_rad_per_s
        return x

    def set_state(self, context, body_state: np.ndarray) -> None:
        """Write a body state (18) and its port's into this system's context."""
        x = np.asarray(body_state, dtype=float)
        context.SetDiscreteState(0, x)
        context.SetDiscreteState(1, port_state(self.params, x))

    def _update(self, context, discrete_state) -> None:
        x, port = self._step(
            context.get_discrete_state(0).value(),
            self._wrench.Eval(context),
            self._h,
            self._m,
            self._I,
            self._I_inv,
            self._arm,
        )
        discrete_state.get_mutable_vector(0).SetFromVector(x)
        discrete_state.get_mutable_vector(1).SetFromVector(port)
