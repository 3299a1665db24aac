"""The Stewart platform's kinematics under the docking port: port pose <-> plate pose, legs.

Frames (:mod:`hybridtable.six_dof.stewart_backend`). The Stewart world has its
origin at the centre of the base joint circle and ``z`` up, the docking axis.
The target frame W of the loop has the same axes and its origin on the passive
plate's face, at ``home_height_m + device_length_m`` above the base. The port
frame P is fixed on the device, ``device_length_m`` above the plate frame
along the plate normal, with the plate's axes. So with the port at ``q = [p;
theta]`` (W; ``R = exp([theta]x)``) the plate frame is at ``o_W + p - R [0, 0,
device_length_m]`` in the world.

The arithmetic runs at every tick of the 6-DoF Stewart loop, so it is written
once as plain functions on arrays (:func:`_plate_of_port`, :func:`_legs`,
:func:`_port_of_plate`) that numba compiles
(:func:`~hybridtable.laws.compiled.compiled_kernel`); :class:`PoseKinematics`
calls them, and words its refusals in Python.
"""

from __future__ import annotations

import math

import numpy as np

from hybridtable.errors import DivergenceError, WorkspaceError
from hybridtable.laws.compiled import compiled_kernel
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.stewart.geometry import StewartGeometry, cross, rotation_from_quaternion, skew

__all__ = ["MAX_CONDITION_NUMBER", "PoseKinematics"]

#: Largest condition number of the leg Jacobian a commanded pose may have [1]:
#: beyond it the pose is refused as (near) a singularity of the platform.
MAX_CONDITION_NUMBER = 1e6


def _fmt(v) -> str:
    return "[" + ", ".join(f"{float(x):.6g}" for x in v) + "]"


def _plate_of_port(
    q: np.ndarray, world_origin_m: np.ndarray, port_in_plate_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The plate's position (world, m) and rotation of a port pose ``q`` (W)."""
    R = rotation_exp(q[3:6])
    return world_origin_m + q[0:3] - R @ port_in_plate_m, R


def _plate_twist_of_port(R: np.ndarray, qd: np.ndarray, port_in_plate_m: np.ndarray) -> np.ndarray:
    """``[v; omega]`` of the plate origin from the port's ``qd = [v_P; omega]``."""
    omega = qd[3:6]
    return np.concatenate((qd[0:3] - cross(omega, R @ port_in_plate_m), omega))


def _legs(
    q: np.ndarray,
    qd: np.ndarray,
    world_origin_m: np.ndarray,
    port_in_plate_m: np.ndarray,
    top: np.ndarray,
    base: np.ndarray,
):
    """``(lengths (6), rates (6), J (6x6), plate position (3), leg vectors (6x3),
    unit legs (6x3))`` of the port at ``q`` moving at ``qd`` (W): ``J`` is the
    leg Jacobian, ``rates = J [v; omega]`` of the plate origin."""
    position, R = _plate_of_port(q, world_origin_m, port_in_plate_m)
    arm = top @ R.T
    legs = position + arm - base
    lengths = np.sqrt(legs[:, 0] * legs[:, 0] + legs[:, 1] * legs[:, 1] + legs[:, 2] * legs[:, 2])
    u = legs / lengths.reshape(6, 1)
    J = np.empty((6, 6))
    J[:, 0:3] = u
    J[:, 3] = arm[:, 1] * u[:, 2] - arm[:, 2] * u[:, 1]
    J[:, 4] = arm[:, 2] * u[:, 0] - arm[:, 0] * u[:, 2]
    J[:, 5] = arm[:, 0] * u[:, 1] - arm[:, 1] * u[:, 0]
    return lengths, J @ _plate_twist_of_port(R, qd, port_in_plate_m), J, position, legs, u


def _inside(
    position: np.ndarray,
    lengths: np.ndarray,
    u: np.ndarray,
    J: np.ndarray,
    shortest_m: float,
    longest_m: float,
    home_directions: np.ndarray,
    min_cosine: float,
    max_condition_number: float,
) -> bool:
    """Whether the legs are inside the workspace (plate above the base, every
    stroke, every universal joint) and the leg Jacobian is conditioned
    better than ``max_condition_number``. Near a limit, :meth:`PoseKinematics._check`
    decides and words the refusal."""
    cosines = u[:, 0] * home_directions[:, 0] + u[:, 1] * home_directions[:, 1]
    cosines = cosines + u[:, 2] * home_directions[:, 2]
    if not (
        position[2] > 0.0
        and lengths.min() > shortest_m
        and lengths.max() < longest_m
        and cosines.min() > min_cosine
    ):
        return False
    # |J|_F |J^-1|_F bounds the condition number from above (at most 6x it):
    # below the limit, the pose is certainly conditioned well enough; only
    # near it does the SVD (10x the cost) decide.
    if _frobenius(J) * _inverse_frobenius(J) <= max_condition_number:
        return True
    s = np.linalg.svd(J)[1]
    return s[5] > 0.0 and s[0] / s[5] <= max_condition_number


def _frobenius(A: np.ndarray) -> float:
    """The Frobenius norm of a square matrix."""
    total = 0.0
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            total += A[i, j] * A[i, j]
    return math.sqrt(total)


def _inverse_frobenius(A: np.ndarray) -> float:
    """The Frobenius norm of ``A``'s inverse (Gauss-Jordan with partial
    pivoting); infinite for a singular ``A``."""
    n = A.shape[0]
    M = np.zeros((n, 2 * n))
    for i in range(n):
        for j in range(n):
            M[i, j] = A[i, j]
        M[i, n + i] = 1.0
    for c in range(n):
        pivot = c
        for r in range(c + 1, n):
            if abs(M[r, c]) > abs(M[pivot, c]):
                pivot = r
        if M[pivot, c] == 0.0:
            return math.inf
        if pivot != c:
            for j in range(2 * n):
                M[c, j], M[pivot, j] = M[pivot, j], M[c, j]
        scale = 1.0 / M[c, c]
        for j in range(2 * n):
            M[c, j] *= scale
        for r in range(n):
            if r != c and M[r, c] != 0.0:
                factor = M[r, c]
                for j in range(2 * n):
                    M[r, j] -= factor * M[c, j]
    total = 0.0
    for i in range(n):
        for j in range(n, 2 * n):
            total += M[i, j] * M[i, j]
    return math.sqrt(total)


def _commanded_legs(
    x: np.ndarray,
    world_origin_m: np.ndarray,
    port_in_plate_m: np.ndarray,
    top: np.ndarray,
    base: np.ndarray,
    shortest_m: float,
    longest_m: float,
    home_directions: np.ndarray,
    min_cosine: float,
    max_condition_number: float,
):
    """``([lengths; rates] (12), inside)`` of a commanded port state ``x = [q; qd]``."""
    lengths, rates, J, position, _, u = _legs(
        x[0:6], x[6:12], world_origin_m, port_in_plate_m, top, base
    )
    inside = _inside(
        position,
        lengths,
        u,
        J,
        shortest_m,
        longest_m,
        home_directions,
        min_cosine,
        max_condition_number,
    )
    return np.concatenate((lengths, rates)), inside


def _port_of_plate(
    position_m: np.ndarray,
    R: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    world_origin_m: np.ndarray,
    port_in_plate_m: np.ndarray,
) -> np.ndarray:
    """The port's ``[q; qd]`` (12, W) of the plate's pose and twist (world)."""
    arm = R @ port_in_plate_m
    return np.concatenate(
        (position_m + arm - world_origin_m, rotation_log(R), v + cross(w, arm), w)
    )


def _port_of_plant_state(
    x: np.ndarray,
    quaternion_start: int,
    velocity_start: int,
    world_origin_m: np.ndarray,
    port_in_plate_m: np.ndarray,
) -> np.ndarray:
    """The port's ``[q; qd]`` (12, W) of the Stewart plant's state ``x``: the
    plate's quaternion and position at ``quaternion_start``, its angular and
    translational velocity at ``velocity_start``."""
    i, j = quaternion_start, velocity_start
    R = rotation_from_quaternion(x[i : i + 4])
    return _port_of_plate(
        x[i + 4 : i + 7], R, x[j + 3 : j + 6], x[j : j + 3], world_origin_m, port_in_plate_m
    )


#: The plain functions the kernels call.
_HELPERS = (
    cross,
    skew,
    rotation_exp,
    rotation_log,
    rotation_from_quaternion,
    _plate_of_port,
    _plate_twist_of_port,
    _legs,
    _frobenius,
    _inverse_frobenius,
    _inside,
    _port_of_plate,
)


class PoseKinematics:
    """The port's pose in W <-> the plate's pose in the Stewart world, and the
    legs' inverse kinematics of a port pose.

    Parameters
    ----------
    geometry : StewartGeometry
    max_condition_number : float
        Refuse poses whose leg Jacobian is worse conditioned than this.
    """

    def __init__(
        self, geometry: StewartGeometry, max_condition_number: float = MAX_CONDITION_NUMBER
    ) -> None:
        self.geometry = geometry
        #: The origin of W in the Stewart world (m).
        self.world_origin_m = np.array(
            [0.0, 0.0, geometry.home_height_m + geometry.device_length_m]
        )
        #: The port's origin in the plate frame (m).
        self.port_in_plate_m = np.array([0.0, 0.0, geometry.device_length_m])
        self.max_condition_number = float(max_condition_number)
        self._top = np.ascontiguousarray(geometry.top_points_m, dtype=float)
        self._base = np.ascontiguousarray(geometry.base_points_m, dtype=float)
        self._stroke = (geometry.leg_min_length_m, geometry.leg_max_length_m)
        self._home_directions = np.ascontiguousarray(geometry.home_leg_directions, dtype=float)
        # A margin below the joint limit's cosine: closer, the geometry decides.
        self._min_cosine = math.cos(geometry.max_joint_angle_rad) + 1e-9
        self._legs = compiled_kernel(_legs, _HELPERS)
        self._commanded = compiled_kernel(_commanded_legs, _HELPERS)
        self._port = compiled_kernel(_port_of_plate, _HELPERS)
        self._port_of_plant = compiled_kernel(_port_of_plant_state, _HELPERS)

    # -- frames ---------------------------------------------------------
    def plate_of_port(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The plate's position (world, m) and rotation of a port pose ``q`` (W)."""
        return _plate_of_port(np.asarray(q, dtype=float), self.world_origin_m, self.port_in_plate_m)

    def plate_twist_of_port(self, R: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``[v; omega]`` of the plate origin from the port's ``qd = [v_P; omega]``."""
        return _plate_twist_of_port(
            np.asarray(R, dtype=float), np.asarray(qd, dtype=float), self.port_in_plate_m
        )

    def port_state(
        self, position_m: np.ndarray, R: np.ndarray, v: np.ndarray, w: np.ndarray
    ) -> np.ndarray:
        """The port's ``[q; qd]`` (12, W) of the plate's pose and twist (world)."""
        return self._port(
            np.asarray(position_m, dtype=float),
            np.ascontiguousarray(R, dtype=float),
            np.asarray(v, dtype=float),
            np.asarray(w, dtype=float),
            self.world_origin_m,
            self.port_in_plate_m,
        )

    def port_state_of_plant(
        self, x: np.ndarray, quaternion_start: int, velocity_start: int
    ) -> np.ndarray:
        """The port's ``[q; qd]`` (12, W) of the Stewart plant's state ``x``
        (the plate's quaternion and position at ``quaternion_start``, its
        angular and translational velocity at ``velocity_start``)."""
        return self._port_of_plant(
            x, quaternion_start, velocity_start, self.world_origin_m, self.port_in_plate_m
        )

    # -- kinematics -----------------------------------------------------
    def leg_lengths(self, q: np.ndarray, check: bool = True) -> np.ndarray:
        """The six leg lengths (m) with the port at ``q`` (W).

        Raises
        ------
        WorkspaceError
            With ``check``, if the pose leaves the workspace (a leg's stroke,
            a universal joint's limit, the base plane) or is near a singularity.
        """
        return self.inverse_kinematics(q, None, check)[0]

    def inverse_kinematics(
        self, q: np.ndarray, qd: np.ndarray | None = None, check: bool = True
    ) -> tuple[np.ndarray, np.ndarray]:
        """Leg lengths (6, m) and rates (6, m/s) of the port's pose ``q`` and
        twist ``qd`` (W; rates zero without ``qd``).

        Raises
        ------
        WorkspaceError
            With ``check`` (see :meth:`leg_lengths`), in one line naming the
            pose and the leg.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (6,):
            raise WorkspaceError(f"a port pose is 6 numbers [x, y, z, rx, ry, rz] (got {q})")
        if not np.all(np.isfinite(q)):
            raise DivergenceError(
                f"the 6-DoF loop diverged: the commanded port pose {_fmt(q)} is not finite"
            )
        twist = np.zeros(6) if qd is None else np.asarray(qd, dtype=float)
        lengths, rates, J, position, legs, u = self._legs(
            q, twist, self.world_origin_m, self.port_in_plate_m, self._top, self._base
        )
        if check:
            self._check(q, position, lengths, legs, u, J)
        return lengths, (np.zeros(6) if qd is None else rates)

    def commanded_legs(self, x: np.ndarray) -> np.ndarray:
        """``[lengths; rates]`` (12: m, m/s) of a commanded port state ``x =
        [q; qd]`` (12, W), checked as :meth:`inverse_kinematics` checks (the
        checks compiled; a refusal worded by :meth:`inverse_kinematics`).

        Raises
        ------
        WorkspaceError, DivergenceError
            As :meth:`inverse_kinematics`.
        """
        try:
            legs, inside = self._commanded(
                x,
                self.world_origin_m,
                self.port_in_plate_m,
                self._top,
                self._base,
                self._stroke[0] + 1e-12,
                self._stroke[1] - 1e-12,
                self._home_directions,
                self._min_cosine,
                self.max_condition_number,
            )
        except ValueError:  # as plain Python, math.sin of an infinite rotation
            legs, inside = x, False
        if inside:
            return legs
        lengths, rates = self.inverse_kinematics(x[:6], x[6:])  # raises, in words
        return np.concatenate([lengths, rates])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """The leg Jacobian (6x6) at the port pose ``q``: ``dL/dt = J [v; omega]``
        with the plate origin's velocity and the angular velocity (world)."""
        q = np.asarray(q, dtype=float)
        return self._legs(
            q, np.zeros(6), self.world_origin_m, self.port_in_plate_m, self._top, self._base
        )[2]

    def _where(self, q: np.ndarray, position: np.ndarray) -> str:
        return (
            f"port at {_fmt(q[:3])} m, rotation vector {_fmt(q[3:])} rad "
            f"(plate at {_fmt(position)} m above the base centre)"
        )

    def _check(self, q, position, lengths, legs, u, J) -> None:
        g = self.geometry
        # The geometry's checks (stroke, universal-joint angle), vectorized;
        # near a limit its own check decides (and words the leg's message).
        inside = (
            position[2] > 0.0
            and lengths.min() > self._stroke[0] + 1e-12
            and lengths.max() < self._stroke[1] - 1e-12
            and np.einsum("ij,ij->i", u, self._home_directions).min() > self._min_cosine
        )
        if not inside:
            try:
                if position[2] <= 0.0:
                    raise WorkspaceError(
                        f"the plate must be above the base (z = {position[2]:g} m)"
                    )
                g.check_legs(lengths, legs)
            except WorkspaceError as err:
                raise WorkspaceError(
                    f"the commanded {self._where(q, position)} is outside the Stewart "
                    f"platform's workspace: {err}"
                ) from None
        s = np.linalg.svd(J, compute_uv=False)
        cond = math.inf if s[-1] <= 0.0 else s[0] / s[-1]
        if not cond <= self.max_condition_number:
            left = np.linalg.svd(J)[0][:, -1]
            leg = int(np.argmax(np.abs(left)))
            raise WorkspaceError(
                f"the commanded {self._where(q, position)} is near a singularity of the Stewart "
                f"platform: the leg Jacobian's condition number is {cond:.3g} (limit "
                f"{self.max_condition_number:.3g}), leg {leg} the most involved"
            )
