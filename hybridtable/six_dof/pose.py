"""Rotations of the 6-DoF loop: rotation vectors, their exponential and logarithm.

A device pose is ``q = [p; theta]`` (m, rad): the position of the docking
port in the target frame W and the rotation vector ``theta`` of its
orientation, ``R = exp([theta]x)`` (Rodrigues: :func:`rotation_exp` and
:func:`skew` are :mod:`hybridtable.stewart.geometry`'s, which the Stewart
platform's kinematics use too). The table and the MDC work in these
coordinates; rotation-vector differences are taken component-wise.
"""

from __future__ import annotations

import math

import numpy as np

from hybridtable.stewart.geometry import rotation_exp, skew

__all__ = [
    "skew",
    "rotation_exp",
    "rotation_jacobian",
    "rotation_log",
    "pose_coordinates",
    "quaternions_of_rotation_vectors",
    "quaternion_product",
    "rotation_vectors_of_quaternions",
]


def rotation_jacobian(theta: np.ndarray) -> np.ndarray:
    """The left Jacobian ``J`` of ``exp`` at ``theta``: ``exp([theta + d]x) =
    exp([J d]x) exp([theta]x)`` to first order, so a point ``b = R a`` of the
    body moves by ``d b = -[b]x J d``."""
    t2 = float(theta[0] ** 2 + theta[1] ** 2 + theta[2] ** 2)
    K = skew(theta)
    if t2 < 1e-12:
        return np.eye(3) + 0.5 * K + (1.0 / 6.0) * (K @ K)
    t = math.sqrt(t2)
    return np.eye(3) + ((1.0 - math.cos(t)) / t2) * K + ((t - math.sin(t)) / (t2 * t)) * (K @ K)


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vector of ``R`` (angle in [0, pi)), inverse of :func:`rotation_exp`."""
    c = max(-1.0, min(1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    angle = math.acos(c)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-6:
        return 0.5 * v
    return angle / (2.0 * math.sin(angle)) * v


def pose_coordinates(position_m: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """``q = [p; theta]`` (6) of a position and a rotation matrix."""
    return np.concatenate([np.asarray(position_m, dtype=float), rotation_log(rotation)])


def quaternions_of_rotation_vectors(theta: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)`` (N, 4; Hamilton) of rotation vectors
    (N, 3; rad, angle below pi), so ``w >= 0``:
    ``(cos(a/2), sin(a/2) theta / a)`` with ``a = |theta|``."""
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    a = np.linalg.norm(theta, axis=1)
    # sin(a/2)/a, its series below 1e-4 rad (exact to double precision there)
    ratio = np.where(a < 1e-4, 0.5 - a * a / 48.0, np.sin(0.5 * a) / np.where(a > 0, a, 1.0))
    return np.column_stack([np.cos(0.5 * a), ratio[:, None] * theta])


def rotation_vectors_of_quaternions(quaternion: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3; rad) of unit quaternions ``(w, x, y, z)`` (N, 4),
    either sign: ``2 atan2(|v|, w) v / |v|``, with ``q`` turned to ``w >= 0``
    first so the angle is below pi (inverse of
    :func:`quaternions_of_rotation_vectors`)."""
    q = np.atleast_2d(np.asarray(quaternion, dtype=float))
    q = q * np.where(q[:, :1] < 0.0, -1.0, 1.0)
    w, v = q[:, 0], q[:, 1:]
    s = np.linalg.norm(v, axis=1)
    # 2 atan2(s, w) / s, its series below 1e-8 (w ~ 1 there)
    ratio = np.where(
        s < 1e-8, 2.0 / np.where(w > 0, w, 1.0), 2.0 * np.arctan2(s, w) / np.where(s > 0, s, 1.0)
    )
    return ratio[:, None] * v


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton products ``a b`` of quaternions ``(w, x, y, z)`` (N, 4)."""
    aw, av = a[:, :1], a[:, 1:]
    bw, bv = b[:, :1], b[:, 1:]
    w = aw * bw - np.sum(av * bv, axis=1, keepdims=True)
    v = aw * bv + bw * av + np.cross(av, bv)
    return np.hstack([w, v])
