"""Geometry and kinematics of a 3-3 Stewart platform (the paper's lower motion table).

Frames: the base frame B is the world frame, its origin at the centre of the
base joint circle, ``z`` up. The top-plate frame T has its origin at the centre
of the top joint circle, ``z`` along the plate normal. A pose is the 6-vector
``[x, y, z, roll, pitch, yaw]`` (m, rad) of T in B, the rotation being
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (Drake's ``RollPitchYaw``).

Leg layout: the base joints sit in three pairs centred at 0, 120 and 240 deg,
the top joints in three pairs centred at 60, 180 and 300 deg. Leg ``2i`` joins
base angle ``120 i + a_b / 2`` to top angle ``120 i + 60 - a_t / 2``; leg
``2i + 1`` joins base angle ``120 (i + 1) - a_b / 2`` to top angle
``120 i + 60 + a_t / 2``, with the pair angles ``a_b``, ``a_t``. Both pair
angles zero give the 3-3 (octahedral) mechanism: two legs share each joint
point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridtable._validation import check_finite, check_nonnegative, check_positive
from hybridtable.errors import ParameterError, WorkspaceError

__all__ = [
    "WorkspaceError",
    "cross",
    "skew",
    "rotation_exp",
    "StewartGeometry",
    "rotation_from_rpy",
    "rpy_from_rotation",
    "rotation_from_quaternion",
]

NUM_LEGS = 6


def cross(a, b) -> np.ndarray:
    """``a x b`` of two 3-vectors, in scalar arithmetic: ``np.cross`` costs ~10 us on
    a small array (the 6-DoF contact's wrench spent 2/3 of its time there). The
    same products and differences in the same order as ``np.cross``: the same bits."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def rotation_from_rpy(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)`` of ``rpy = [roll, pitch, yaw]``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def rpy_from_rotation(R: np.ndarray) -> np.ndarray:
    """``[roll, pitch, yaw]`` of a rotation matrix (inverse of :func:`rotation_from_rpy`
    away from pitch = +-90 deg)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    roll = math.atan2(R[2, 1], R[2, 2])
    yaw = math.atan2(R[1, 0], R[0, 0])
    return np.array([roll, pitch, yaw])


def rotation_from_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion ``[w, x, y, z]`` (normalized here), as a
    MultibodyPlant's floating-body positions hold it (scalar arithmetic: this
    runs at every tick of the Stewart back-ends)."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / n, q[1] / n, q[2] / n, q[3] / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def skew(w: np.ndarray) -> np.ndarray:
    """The cross-product matrix ``[w]x`` of a 3-vector."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rotation_exp(theta: np.ndarray) -> np.ndarray:
    """``exp([theta]x)``: the rotation by ``|theta|`` rad about ``theta`` (Rodrigues)."""
    t = math.sqrt(float(theta[0] ** 2 + theta[1] ** 2 + theta[2] ** 2))
    K = skew(theta)
    if t < 1e-9:
        return np.eye(3) + K + 0.5 * (K @ K)
    return np.eye(3) + (math.sin(t) / t) * K + ((1.0 - math.cos(t)) / (t * t)) * (K @ K)


def _circle_points(radius: float, angles_deg: np.ndarray) -> np.ndarray:
    a = np.radians(angles_deg)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros_like(a)])


@dataclass(frozen=True)
class StewartGeometry:
    """Geometry, stroke and mass properties of a 3-3 Stewart platform, SI units.

    Parameters
    ----------
    base_radius_m, top_radius_m : float
        Radii of the base and top joint circles, > 0.
    base_pair_angle_rad, top_pair_angle_rad : float
        Angle between the two joints of a pair, in [0, 2 pi / 3); 0 gives the
        3-3 mechanism (the paper's table).
    home_height_m : float
        Height of the top-plate frame above the base at the home pose, > 0.
    leg_min_length_m, leg_max_length_m : float
        Stroke of the legs (joint centre to joint centre); the home pose must
        lie inside.
    max_joint_angle_rad : float
        Largest angle between a leg and its home direction that the base's
        universal joint allows, in (0, pi/2).
    plate_mass_kg : float
        Mass of the top plate with everything rigidly on it except the
        contact device (F/T sensor, adapter).
    plate_inertia_kg_m2 : tuple of 3 floats
        Principal moments of inertia of the plate about its centre of mass
        (the frame origin), about the plate's x, y, z axes.
    cylinder_mass_kg, piston_mass_kg : float
        Masses of a leg's cylinder (on the universal joint) and piston (on
        the ball joint).
    cylinder_length_m, piston_length_m : float
        Lengths of the cylinder and piston, modelled as slender rods (inertia
        ``m l^2 / 12`` about their transverse axes).
    device_mass_kg : float
        Mass of the active contact device (between the F/T sensor and the
        contact), > 0.
    device_length_m : float
        Distance from the sensor (plate frame origin) to the device's
        contact tip along the plate normal.
    device_tip_radius_m : float
        Radius of the device's spherical tip.
    """

    base_radius_m: float = 0.6
    top_radius_m: float = 0.35
    base_pair_angle_rad: float = 0.0
    top_pair_angle_rad: float = 0.0
    home_height_m: float = 0.8
    leg_min_length_m: float = 0.80
    leg_max_length_m: float = 1.15
    max_joint_angle_rad: float = math.radians(40.0)
    plate_mass_kg: float = 60.0
    plate_inertia_kg_m2: tuple[float, float, float] = (2.0, 2.0, 3.8)
    cylinder_mass_kg: float = 3.0
    piston_mass_kg: float = 1.5
    cylinder_length_m: float = 0.6
    piston_length_m: float = 0.6
    device_mass_kg: float = 1.5
    device_length_m: float = 0.2
    device_tip_radius_m: float = 0.03

    def __post_init__(self) -> None:
        s = object.__setattr__
        for name in (
            "base_radius_m",
            "top_radius_m",
            "home_height_m",
            "leg_min_length_m",
            "leg_max_length_m",
            "max_joint_angle_rad",
            "plate_mass_kg",
            "cylinder_mass_kg",
            "piston_mass_kg",
            "cylinder_length_m",
            "piston_length_m",
            "device_mass_kg",
            "device_length_m",
            "device_tip_radius_m",
        ):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in ("base_pair_angle_rad", "top_pair_angle_rad"):
            value = check_nonnegative(name, getattr(self, name))
            if value >= 2.0 * math.pi / 3.0:
                raise ParameterError(f"{name} must be < 2 pi / 3 (got {value!r})")
            s(self, name, value)
        if self.max_joint_angle_rad >= math.pi / 2:
            raise ParameterError(
                f"max_joint_angle_rad must be < pi / 2 (got {self.max_joint_angle_rad!r})"
            )
        try:
            inertia = tuple(float(v) for v in self.plate_inertia_kg_m2)
        except (TypeError, ValueError):
            raise ParameterError(
                f"plate_inertia_kg_m2 must be 3 numbers (got {self.plate_inertia_kg_m2!r})"
            ) from None
        if len(inertia) != 3:
            raise ParameterError(f"plate_inertia_kg_m2 must be 3 numbers (got {inertia!r})")
        for value in inertia:
            check_positive("plate_inertia_kg_m2", value)
        a, b, c = inertia
        if a + b < c or b + c < a or a + c < b:
            raise ParameterError(
                f"plate_inertia_kg_m2 violates the triangle inequality (got {inertia!r})"
            )
        s(self, "plate_inertia_kg_m2", inertia)
        if self.device_tip_radius_m >= self.device_length_m:
            raise ParameterError(
                f"device_tip_radius_m must be < device_length_m (got {self.device_tip_radius_m!r})"
            )
        if self.leg_min_length_m >= self.leg_max_length_m:
            raise ParameterError(
                f"leg_min_length_m must be < leg_max_length_m (got {self.leg_min_length_m!r} "
                f">= {self.leg_max_length_m!r})"
            )
        # The home pose must be reachable.
        try:
            self.inverse_kinematics(self.home_pose)
        except WorkspaceError as err:
            raise ParameterError(f"home pose outside the workspace: {err}") from None

    # -- layout -------------------------------------------------------------
    @property
    def base_points_m(self) -> np.ndarray:
        """Base joint centres of legs 0..5 in B, shape (6, 3)."""
        half = math.degrees(self.base_pair_angle_rad) / 2.0
        angles = []
        for i in range(3):
            angles += [120.0 * i + half, 120.0 * (i + 1) - half]
        return _circle_points(self.base_radius_m, np.array(angles))

    @property
    def top_points_m(self) -> np.ndarray:
        """Top joint centres of legs 0..5 in the plate frame T, shape (6, 3)."""
        half = math.degrees(self.top_pair_angle_rad) / 2.0
        angles = []
        for i in range(3):
            angles += [120.0 * i + 60.0 - half, 120.0 * i + 60.0 + half]
        return _circle_points(self.top_radius_m, np.array(angles))

    @property
    def home_pose(self) -> np.ndarray:
        """The home pose ``[0, 0, home_height_m, 0, 0, 0]``."""
        return np.array([0.0, 0.0, self.home_height_m, 0.0, 0.0, 0.0])

    @property
    def home_leg_directions(self) -> np.ndarray:
        """Unit vectors from the base joints to the top joints at home, (6, 3)."""
        legs = self.leg_vectors(self.home_pose)
        return legs / np.linalg.norm(legs, axis=1, keepdims=True)

    @property
    def device_tip_center_m(self) -> np.ndarray:
        """Centre of the device's spherical tip in the plate frame T."""
        return np.array([0.0, 0.0, self.device_length_m - self.device_tip_radius_m])

    # -- kinematics ---------------------------------------------------------
    @staticmethod
    def _split_pose(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pose = np.asarray(pose, dtype=float).reshape(-1)
        if pose.shape != (6,) or not np.all(np.isfinite(pose)):
            raise WorkspaceError(
                f"a pose is 6 finite numbers [x, y, z, roll, pitch, yaw] (got {pose})"
            )
        return pose[:3], rotation_from_rpy(pose[3:])

    def leg_vectors(self, pose: np.ndarray) -> np.ndarray:
        """Vectors from base to top joint centres in B for a pose, (6, 3)."""
        p, R = self._split_pose(pose)
        return p + self.top_points_m @ R.T - self.base_points_m

    def check_legs(self, lengths_m: np.ndarray, legs: np.ndarray | None = None) -> None:
        """Raise :class:`WorkspaceError` if a leg length leaves the stroke or
        (given the leg vectors) a leg tilts beyond ``max_joint_angle_rad``."""
        lengths = np.asarray(lengths_m, dtype=float)
        for i, length in enumerate(lengths):
            if not (self.leg_min_length_m <= length <= self.leg_max_length_m):
                raise WorkspaceError(
                    f"leg {i} length {length:.6f} m outside its stroke "
                    f"[{self.leg_min_length_m:g}, {self.leg_max_length_m:g}] m"
                )
        if legs is not None:
            cosines = np.einsum("ij,ij->i", legs / lengths[:, None], self.home_leg_directions)
            for i, c in enumerate(cosines):
                angle = math.acos(min(1.0, max(-1.0, c)))
                if angle > self.max_joint_angle_rad:
                    raise WorkspaceError(
                        f"leg {i} tilts {math.degrees(angle):.1f} deg from its home direction "
                        f"(universal-joint limit {math.degrees(self.max_joint_angle_rad):.1f} deg)"
                    )

    def inverse_kinematics(self, pose: np.ndarray, check: bool = True) -> np.ndarray:
        """Leg lengths (m, shape (6,)) of a pose.

        Raises
        ------
        WorkspaceError
            With ``check``, if a leg leaves its stroke, a universal joint its
            angle limit, or the plate its side of the base (``z <= 0``).
        """
        legs = self.leg_vectors(pose)
        lengths = np.linalg.norm(legs, axis=1)
        if check:
            if pose[2] <= 0.0:
                raise WorkspaceError(f"the plate must be above the base (z = {pose[2]:g} m)")
            self.check_legs(lengths, legs)
        return lengths

    def leg_jacobian(self, pose: np.ndarray) -> np.ndarray:
        """J (6x6) with ``dL/dt = J [v; w]``: v the plate origin's velocity and
        w the plate's angular velocity, both in B."""
        p, R = self._split_pose(pose)
        arm = self.top_points_m @ R.T
        legs = p + arm - self.base_points_m
        u = legs / np.linalg.norm(legs, axis=1, keepdims=True)
        return np.hstack([u, np.cross(arm, u)])

    def forward_kinematics(
        self,
        lengths_m: np.ndarray,
        initial_pose: np.ndarray | None = None,
        tolerance_m: float = 1e-13,
        max_iterations: int = 50,
    ) -> np.ndarray:
        """The pose with the given leg lengths, by Newton's method from
        ``initial_pose`` (default: home).

        Raises
        ------
        WorkspaceError
            If the lengths leave the stroke or Newton's method does not
            converge (no assembly near the initial pose, or a singularity).
        """
        target = np.asarray(lengths_m, dtype=float).reshape(-1)
        if target.shape != (NUM_LEGS,) or not np.all(np.isfinite(target)):
            raise WorkspaceError(f"forward kinematics needs 6 finite leg lengths (got {target})")
        self.check_legs(target)
        pose0 = self.home_pose if initial_pose is None else np.asarray(initial_pose, dtype=float)
        p, R = self._split_pose(pose0)
        p = p.copy()
        top = self.top_points_m
        base = self.base_points_m
        for _ in range(max_iterations):
            arm = top @ R.T
            legs = p + arm - base
            lengths = np.linalg.norm(legs, axis=1)
            error = lengths - target
            if np.max(np.abs(error)) < tolerance_m:
                pose = np.concatenate([p, rpy_from_rotation(R)])
                self.inverse_kinematics(pose)  # workspace check (joint angles, z > 0)
                return pose
            u = legs / lengths[:, None]
            J = np.hstack([u, np.cross(arm, u)])
            if np.linalg.cond(J) > 1e10:
                break
            step = np.linalg.solve(J, -error)
            p = p + step[:3]
            R = rotation_exp(step[3:]) @ R
        raise WorkspaceError(
            f"forward kinematics did not converge for leg lengths {np.round(target, 6)} m"
        )

    def axis_pose(self, offset_m: float, axis: np.ndarray | None = None) -> np.ndarray:
        """The home pose translated by ``offset_m`` along a unit ``axis`` of B
        (default: z, the docking axis)."""
        a = np.array([0.0, 0.0, 1.0]) if axis is None else np.asarray(axis, dtype=float)
        pose = self.home_pose.copy()
        pose[:3] += check_finite("offset_m", offset_m) * a / np.linalg.norm(a)
        return pose

    def axis_workspace(
        self, axis: np.ndarray | None = None, resolution_m: float = 1e-9
    ) -> tuple[float, float]:
        """The interval of translations from home along ``axis`` (default z)
        that stay in the workspace, by bisection from home."""

        def inside(offset: float) -> bool:
            try:
                self.inverse_kinematics(self.axis_pose(offset, axis))
            except WorkspaceError:
                return False
            return True

        span = 2.0 * (self.leg_max_length_m + self.home_height_m)
        bounds = []
        for sign in (-1.0, 1.0):
            lo, hi = 0.0, span
            # Bounded workspace: the far end is always outside.
            while hi - lo > resolution_m:
                mid = 0.5 * (lo + hi)
                if inside(sign * mid):
                    lo = mid
                else:
                    hi = mid
            bounds.append(sign * lo)
        return bounds[0], bounds[1]
