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

__all__ = ["skew", "rotation_exp", "rotation_jacobian", "rotation_log", "pose_coordinates"]


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
