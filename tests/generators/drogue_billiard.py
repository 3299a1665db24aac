"""Drogue billiard: an independent hand calculation of a probe entering a conical drogue.

Written from the physics alone (nothing here imports ``hybridtable``). The drogue is a
rigid surface of revolution about z; its meridian profile (rho, z) is the polyline
rim ``(2Rm, 0) -> (Rm, 0)``, cone ``-> (Rt, D)`` with ``D = (Rm - Rt) / tan(alpha)``,
socket wall ``-> (Rt, D + L)`` and floor ``-> (0, D + L)``; the hollow is on the axis /
-z side. A sphere (radius r) translates from ``(miss, -2r)`` with velocity ``(0, v)``;
contacts are frictionless and elastic (specular), so the motion is a 2-D billiard of
the centre in the (x, z) plane inside the configuration region: every profile segment
offset by r toward the hollow, plus arcs of radius r about the convex corners (mouth
edge ``(Rm, 0)``, throat edge ``(Rt, D)``); the concave floor corner is where the
offset socket wall and floor meet. Everything is mirrored (x -> -x) for x < 0; the
floor is one segment across the axis. The free end of the rim at 2Rm has no arc.

Event-driven: find the first boundary hit from the hollow side, reflect about its
normal (for an arc: corner -> hit point), repeat; stop when nothing can be hit again
(the probe left), or after :data:`MAX_TOUCHES` touches.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "MAX_TOUCHES",
    "Drogue",
    "Prediction",
    "Touch",
    "predict",
    "wall_force_direction",
]

MAX_TOUCHES = 200
_EPS = 1e-12


@dataclass(frozen=True)
class Drogue:
    alpha_rad: float
    mouth_radius_m: float
    throat_radius_m: float
    socket_depth_m: float
    probe_radius_m: float

    def __post_init__(self) -> None:
        r, rt, rm = self.probe_radius_m, self.throat_radius_m, self.mouth_radius_m
        if not (0.0 < self.alpha_rad < math.pi / 2):
            raise ValueError("alpha must be in (0, pi/2)")
        if not (0.0 < r < rt < rm) or not self.socket_depth_m > r:
            raise ValueError("need 0 < r < Rt < Rm and L > r")

    @property
    def throat_depth_m(self) -> float:
        return (self.mouth_radius_m - self.throat_radius_m) / math.tan(self.alpha_rad)


@dataclass
class Touch:
    boundary: str
    x_m: float
    z_m: float
    velocity_after: tuple[float, float]


@dataclass
class Prediction:
    touches: list[Touch] = field(default_factory=list)
    captured: bool = False
    exit_velocity: tuple[float, float] | None = None
    closest_call_m: float = math.inf


@dataclass(frozen=True)
class _Boundary:
    name: str
    kind: str  # "seg" (a = start, b = end, n = normal toward the hollow) or "arc"
    a: np.ndarray  # seg: start point; arc: centre
    b: np.ndarray  # seg: end point; arc: the wedge's first edge direction
    n: np.ndarray  # seg: unit normal toward the hollow; arc: the wedge's second edge


def _cross(u: np.ndarray, w: np.ndarray) -> float:
    return float(u[0] * w[1] - u[1] * w[0])


def _boundaries(d: Drogue) -> list[_Boundary]:
    a, r, rm, rt = d.alpha_rad, d.probe_radius_m, d.mouth_radius_m, d.throat_radius_m
    zt, zf = d.throat_depth_m, d.throat_depth_m + d.socket_depth_m
    v = np.array
    n_rim, n_cone, n_wall = v([0.0, -1.0]), v([-math.cos(a), -math.sin(a)]), v([-1.0, 0.0])
    mouth, throat = v([rm, 0.0]), v([rt, zt])
    right = [
        _Boundary("rim", "seg", v([2 * rm, -r]), v([rm, -r]), n_rim),
        _Boundary("mouth_edge", "arc", mouth, n_cone, n_rim),
        _Boundary("cone", "seg", mouth + r * n_cone, throat + r * n_cone, n_cone),
        _Boundary("throat_edge", "arc", throat, n_wall, n_cone),
        _Boundary("socket_wall", "seg", v([rt - r, zt]), v([rt - r, zf - r]), n_wall),
    ]
    flip = v([-1.0, 1.0])
    left = [_Boundary(b.name, b.kind, b.a * flip, b.b * flip, b.n * flip) for b in right]
    floor = _Boundary("floor", "seg", v([rt - r, zf - r]), v([r - rt, zf - r]), n_rim)
    return [*right, *left, floor]


def _in_wedge(b: _Boundary, u: np.ndarray, tol: float = 1e-9) -> bool:
    s = math.copysign(1.0, _cross(b.b, b.n))
    return (
        s * _cross(b.b, u) >= -tol and s * _cross(u, b.n) >= -tol and float(u @ (b.b + b.n)) > 0.0
    )


def _hit(b: _Boundary, p: np.ndarray, vel: np.ndarray, r: float) -> tuple[float, np.ndarray]:
    """(time, normal) of the first hit of ``b`` from the hollow side, (inf, _) if none."""
    none = (math.inf, b.n)
    if b.kind == "seg":
        vn = float(vel @ b.n)
        if vn >= 0.0:
            return none
        t = float((p - b.a) @ b.n) / -vn
        if t <= _EPS:
            return none
        q, e = p + t * vel, b.b - b.a
        s = float((q - b.a) @ e) / float(e @ e)
        return (t, b.n) if -1e-9 <= s <= 1 + 1e-9 else none
    w = p - b.a
    aa, bb, cc = float(vel @ vel), float(vel @ w), float(w @ w) - r * r
    disc = bb * bb - aa * cc
    if bb >= 0.0 or disc < 0.0:
        return none
    t = (-bb - math.sqrt(disc)) / aa
    if t <= _EPS:
        return none
    u = (p + t * vel - b.a) / r
    u = u / np.linalg.norm(u)
    return (t, u) if _in_wedge(b, u) else none


def _point_seg(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    e = b - a
    s = min(max(float((q - a) @ e) / max(float(e @ e), 1e-300), 0.0), 1.0)
    return float(np.linalg.norm(q - (a + s * e)))


def _seg_seg(p0: np.ndarray, p1: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    d1, d2 = p1 - p0, b - a
    den = _cross(d1, d2)
    if abs(den) > 1e-300:
        s, t = _cross(a - p0, d2) / den, _cross(a - p0, d1) / den
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
            return 0.0
    return min(
        _point_seg(p0, a, b), _point_seg(p1, a, b), _point_seg(a, p0, p1), _point_seg(b, p0, p1)
    )


def _seg_arc(p0: np.ndarray, p1: np.ndarray, b: _Boundary, r: float) -> float:
    c = b.a
    best = min(_point_seg(c + r * b.b, p0, p1), _point_seg(c + r * b.n, p0, p1))
    e = p1 - p0
    s_foot = float((c - p0) @ e) / max(float(e @ e), 1e-300)
    cands = [0.0, 1.0] + ([s_foot] if 0.0 < s_foot < 1.0 else [])
    ww, we, ee = float((p0 - c) @ (p0 - c)), float((p0 - c) @ e), float(e @ e)
    disc = we * we - ee * (ww - r * r)
    if disc >= 0.0 and ee > 0.0:  # crossings of the circle
        cands += [
            s for s in ((-we - math.sqrt(disc)) / ee, (-we + math.sqrt(disc)) / ee) if 0 <= s <= 1
        ]
    for s in cands:
        w = p0 + s * e - c
        dist = float(np.linalg.norm(w))
        if dist > 0.0 and _in_wedge(b, w / dist, tol=0.0):
            best = min(best, abs(dist - r))
    return best


def _clearance(p0: np.ndarray, p1: np.ndarray, b: _Boundary, r: float) -> float:
    return _seg_seg(p0, p1, b.a, b.b) if b.kind == "seg" else _seg_arc(p0, p1, b, r)


def predict(drogue: Drogue, miss_m: float, speed_m_per_s: float) -> Prediction:
    """The billiard of the probe's centre from ``(miss, -2r)`` with velocity ``(0, v)``."""
    if not speed_m_per_s > 0.0:
        raise ValueError("speed must be > 0")
    r, bounds = drogue.probe_radius_m, _boundaries(drogue)
    far = 10.0 * (2 * drogue.mouth_radius_m + drogue.throat_depth_m + drogue.socket_depth_m)
    p, vel = np.array([float(miss_m), -2.0 * r]), np.array([0.0, float(speed_m_per_s)])
    out, last, z_max = Prediction(), -1, float(p[1])
    while True:
        if vel[1] < 0.0 and p[1] < -r:
            hit_t, hit_i, hit_n = math.inf, -1, vel
        else:
            hits = [(*_hit(b, p, vel, r), i) for i, b in enumerate(bounds)]
            hit_t, hit_n, hit_i = min(hits, key=lambda h: h[0])
        if math.isinf(hit_t):  # a final leg: nothing can be hit again
            q = p + far * vel / np.linalg.norm(vel)
        else:
            q = p + hit_t * vel
        z_max = max(z_max, float(q[1]))
        for i, b in enumerate(bounds):
            if i not in (last, hit_i):
                out.closest_call_m = min(out.closest_call_m, _clearance(p, q, b, r))
        if math.isinf(hit_t):
            out.exit_velocity = (float(vel[0]), float(vel[1]))
            break
        p, last = q, hit_i
        vel = vel - 2.0 * float(vel @ hit_n) * hit_n
        out.touches.append(
            Touch(bounds[hit_i].name, float(p[0]), float(p[1]), (float(vel[0]), float(vel[1])))
        )
        if len(out.touches) >= MAX_TOUCHES:
            break
    out.captured = z_max > drogue.throat_depth_m
    return out


def wall_force_direction(drogue: Drogue, rho_m: float) -> tuple[float, float]:
    """The unit direction (radial, axial) of the frictionless contact force on a probe pressed
    into the cone wall at radius rho (between Rt and Rm): the wall's normal toward the hollow,
    (-cos alpha, -sin alpha)."""
    tol = 1e-9 * drogue.mouth_radius_m
    if not (drogue.throat_radius_m - tol <= rho_m <= drogue.mouth_radius_m + tol):
        raise ValueError("rho must lie on the cone wall, between Rt and Rm")
    return (-math.cos(drogue.alpha_rad), -math.sin(drogue.alpha_rad))


if __name__ == "__main__":
    misses = (0.0, 0.02, 0.06, 0.1, 0.15, 0.2, 0.25, 0.32, 0.4)
    for deg in (20, 30, 40):
        dr = Drogue(math.radians(deg), 0.3, 0.08, 0.15, 0.05)
        print(f"alpha = {deg} deg, D = {dr.throat_depth_m:.4f} m")
        for m in misses:
            pr = predict(dr, m, 0.1)
            slow = predict(dr, m, 1.0)  # the speed only scales time
            same = [t.boundary for t in slow.touches] == [t.boundary for t in pr.touches]
            names = " ".join(t.boundary for t in pr.touches)
            ev = (
                "None"
                if pr.exit_velocity is None
                else "({:+.4f}, {:+.4f})".format(*pr.exit_velocity)
            )
            print(
                f"  miss {m:4.2f}: captured={pr.captured!s:5} touches={len(pr.touches):3d} "
                f"closest={pr.closest_call_m * 1e3:7.2f} mm exit={ev} speed-invariant={same} [{names}]"
            )
