"""The probe-and-drogue docking devices: a spherical probe head on the port's
axis entering a conical drogue, in contact through Drake's hydroelastic model.

Geometry (``docs/six_dof.md`` has a figure). The drogue is a surface of
revolution about the docking axis of the target frame W, its mouth in the
plane ``z = 0`` and its inside at ``z > 0``; in a meridian half-plane
``(rho, z)`` its profile is

- the **rim**, flat, from ``2 R_m`` to the mouth radius ``R_m`` at ``z = 0``;
- the **cone** wall, from ``(R_m, 0)`` to the throat ``(R_t, D)``, at
  ``cone_half_angle_rad`` ``alpha`` from the axis: ``D = (R_m - R_t) / tan alpha``;
- the **socket**, a cylinder of the throat's radius from ``D`` to ``D + L``
  and its floor at ``z = D + L``.

The probe head is a sphere of radius ``r < R_t`` on the port's axis, its tip
at the port origin (its centre at ``-r`` along the port's z axis). A head that
has passed the throat (its centre beyond ``z = D``) is **captured**: a real
drogue's latches close behind it there. The latches are not modelled: a run
goes on until the probe has left the mouth, or is held in the socket
(:func:`~hybridtable.six_dof.simulation.simulate6`).

Contact: the probe head is compliant (Drake's hydroelastic sphere, modulus
``E``), the drogue rigid (a surface of revolution of :data:`FACETS` facets
round, open: Drake's point contact takes a mesh as its convex hull, which
fills a funnel; hydroelastic contact uses the surface itself). Pressed ``x``
into a flat wall, the head pushes back with
``f(x) = pi E x^2 (1 - 2 x / (3 r))`` (the pressure ``E (1 - |y - c| / r)``
integrated over the wall's disc inside the sphere), along the wall's normal:
on the cone wall, frictionless, ``cot alpha`` across the axis per unit along
it. The rig states its contact as ``contact_stiffness_n_per_m``; for the probe
that is the tangent stiffness ``f'(x)`` at a press of a tenth of its radius,
``k = 0.18 pi E r`` (:func:`probe_modulus_pa`), so one number states how stiff
the contact is for both devices, and a compensator's belief about it scales
``E`` as it scales the pads' ``k``. Hunt-Crossley dissipation and Coulomb
friction act on the hydroelastic pressure as on the pads' point forces.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from pydrake.common import MemoryFile
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    InMemoryMesh,
    Mesh,
    ProximityProperties,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import ContactModel, CoulombFriction

from hybridtable.laws.compiled import compiled_available, njit_cached

__all__ = [
    "FACETS",
    "REFERENCE_PRESS",
    "probe_modulus_pa",
    "probe_force_n",
    "probe_energy_j",
    "profile",
    "throat_depth_m",
    "floor_depth_m",
    "drogue_mesh",
    "register_drogue_devices",
    "face_data",
    "hydroelastic_jacobians",
    "wall_depth_m",
    "facet_sag_m",
    "first_touch_gap_m",
]

#: Facets round the drogue's surface of revolution: the force of a probe
#: pressed into the cone ripples by about 0.8 % as it goes round (measured on
#: a prototype), and one evaluation of the contact costs 0.4-1.5 ms.
FACETS = 64

#: The press, as a fraction of the probe's radius, at which its tangent
#: stiffness is the rig's ``contact_stiffness_n_per_m``.
REFERENCE_PRESS = 0.1

#: Resolution of the probe's hydroelastic mesh, as a fraction of its radius.
#: Drake's tetrahedral sphere lies inside the smooth one: on a flat wall its
#: force is 28, 13 and 6 % under :func:`probe_force_n` at presses of 2, 5 and
#: 10 mm of a 50 mm head (measured; an eighth of the radius roughly halves
#: that, for three times the cost of an evaluation).
_RESOLUTION = 0.25


def probe_modulus_pa(contact) -> float:
    """The probe's hydroelastic modulus ``E`` (Pa) whose tangent stiffness at
    a press of :data:`REFERENCE_PRESS` of its radius is the contact's stiffness:
    ``f'(x) = 2 pi E x (1 - x / r)``."""
    r = contact.probe_radius_m
    x = REFERENCE_PRESS * r
    return contact.contact_stiffness_n_per_m / (2.0 * math.pi * x * (1.0 - x / r))


def probe_force_n(contact, press_m) -> np.ndarray:
    """``f(x) = pi E x^2 (1 - 2 x / (3 r))`` (N): the head pressed ``x`` (m)
    into a flat wall, without dissipation."""
    x = np.clip(np.asarray(press_m, dtype=float), 0.0, contact.probe_radius_m)
    r = contact.probe_radius_m
    return math.pi * probe_modulus_pa(contact) * x * x * (1.0 - 2.0 * x / (3.0 * r))


def probe_energy_j(contact, press_m) -> np.ndarray:
    """The work ``integral f`` of pressing the head ``x`` (m) into a flat wall:
    ``pi E (x^3 / 3 - x^4 / (6 r))`` (J)."""
    x = np.clip(np.asarray(press_m, dtype=float), 0.0, contact.probe_radius_m)
    r = contact.probe_radius_m
    return math.pi * probe_modulus_pa(contact) * (x**3 / 3.0 - x**4 / (6.0 * r))


def profile(contact) -> np.ndarray:
    """The drogue's meridian profile ``(rho, z)`` (m), from the rim's outer edge
    to the axis (see the module doc)."""
    rm, rt = contact.mouth_radius_m, contact.throat_radius_m
    depth = (rm - rt) / math.tan(contact.cone_half_angle_rad)
    floor = depth + contact.socket_depth_m
    return np.array([(2.0 * rm, 0.0), (rm, 0.0), (rt, depth), (rt, floor), (0.0, floor)])


def throat_depth_m(contact) -> float:
    """``D``: the throat's plane (m along +z from the mouth)."""
    return float(profile(contact)[2, 1])


def floor_depth_m(contact) -> float:
    """``D + socket_depth_m``: the socket's floor (m along +z from the mouth)."""
    return float(profile(contact)[-1, 1])


@functools.lru_cache(maxsize=16)
def _surface_obj(prof: tuple) -> str:
    """An OBJ text of the surface of revolution of ``prof``: :data:`FACETS`
    vertices round each profile point (one on the axis), triangles facing the
    hollow (their normals toward the probe)."""
    rows = []
    index = []
    for rho, z in prof:
        ring = []
        for j in range(1 if rho == 0.0 else FACETS):
            a = 2.0 * math.pi * j / FACETS
            rows.append(f"v {rho * math.cos(a):.12g} {rho * math.sin(a):.12g} {z:.12g}")
            ring.append(len(rows))
        index.append(ring)
    faces = []
    for lo, hi in zip(index[:-1], index[1:], strict=True):
        for j in range(FACETS):
            a0, a1 = lo[j % len(lo)], lo[(j + 1) % len(lo)]
            b0, b1 = hi[j % len(hi)], hi[(j + 1) % len(hi)]
            if a0 != a1:
                faces.append(f"f {a0} {b0} {a1}")
            if b0 != b1:
                faces.append(f"f {a1} {b0} {b1}")
    return "\n".join(rows + faces) + "\n"


def drogue_mesh(contact, floor: bool = True) -> Mesh:
    """The drogue's surface as a Drake mesh held in memory (without the
    socket's floor: open at the socket's bottom ring)."""
    prof = profile(contact) if floor else profile(contact)[:-1]
    text = _surface_obj(tuple(map(tuple, prof.tolist())))
    return Mesh(InMemoryMesh(mesh_file=MemoryFile(text, ".obj", "drogue")))


def register_drogue_devices(
    plant, device_body, X_device_port, target_body, X_target_face, contact
) -> list:
    """Register the probe head on ``device_body`` and the drogue on
    ``target_body`` (frames as :func:`~hybridtable.six_dof.contact.register_docking_devices`),
    and set ``plant``'s contact model to hydroelastic (point contact where a
    pair of other geometries has no hydroelastic representation).

    Returns
    -------
    list of GeometryId
        The probe head's collision geometry.
    """
    mu = contact.friction_coefficient
    d = contact.contact_dissipation_s_per_m
    r = contact.probe_radius_m
    probe = ProximityProperties()
    AddCompliantHydroelasticProperties(_RESOLUTION * r, probe_modulus_pa(contact), probe)
    AddContactMaterial(dissipation=d, friction=CoulombFriction(mu, mu), properties=probe)
    X = X_device_port @ RigidTransform([0.0, 0.0, -r])
    head = plant.RegisterCollisionGeometry(device_body, X, Sphere(r), "probe", probe)
    plant.RegisterVisualGeometry(device_body, X, Sphere(r), "probe", np.array([0.2, 0.4, 0.8, 1]))
    rigid = ProximityProperties()
    AddRigidHydroelasticProperties(0.1 * r, rigid)
    AddContactMaterial(dissipation=d, friction=CoulombFriction(mu, mu), properties=rigid)
    walls = drogue_mesh(contact, floor=False)
    plant.RegisterCollisionGeometry(target_body, X_target_face, walls, "drogue", rigid)
    # The socket's floor is a box's face: a fan of thin triangles to the axis
    # would cut a centred head into a polygon per triangle (5 ms a query).
    rt, floor = contact.throat_radius_m, floor_depth_m(contact)
    X_floor = X_target_face @ RigidTransform([0.0, 0.0, floor + 0.5 * rt])
    plant.RegisterCollisionGeometry(
        target_body, X_floor, Box(2.2 * rt, 2.2 * rt, rt), "drogue_floor", rigid
    )
    plant.RegisterVisualGeometry(
        target_body, X_target_face, drogue_mesh(contact), "drogue", np.array([0.8, 0.5, 0.2, 0.6])
    )
    plant.set_contact_model(ContactModel.kHydroelasticWithFallback)
    return [head]


def face_data(info, probe_id) -> tuple[np.ndarray, ...]:
    """The faces of one hydroelastic contact surface: their areas (m^2),
    centroids (m, W), unit normals out of the drogue toward the probe,
    pressures at the centroids (Pa) and the probe's pressure gradients there
    (Pa/m, W)."""
    s = info.contact_surface()
    probe_is_m = s.id_M() == probe_id
    field = s.tri_e_MN() if s.is_triangle() else s.poly_e_MN()
    grad = s.EvaluateGradE_M_W if probe_is_m else s.EvaluateGradE_N_W
    n = s.num_faces()
    area, centre, normal = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
    pressure, gradient = np.empty(n), np.empty((n, 3))
    sign = 1.0 if probe_is_m else -1.0  # face_normal: out of N into M
    for f in range(n):
        c = s.centroid(f)
        area[f] = s.area(f)
        centre[f] = c
        normal[f] = sign * s.face_normal(f)
        pressure[f] = field.EvaluateCartesian(f, c)
        gradient[f] = grad(f)
    return area, centre, normal, pressure, gradient


def _face_jacobians(A, X, N, P, G, p, J, qd, d, w_q, w_qd) -> None:
    """Add to ``w_q = dw/dq`` and ``w_qd = dw/dqd`` (6x6) the faces' terms of a
    hydroelastic contact without friction (see
    :meth:`~hybridtable.six_dof.contact.DockingContact.stiffness`): face ``i``
    of area ``A[i]``, centroid ``X[i]`` on the rigid drogue, normal ``N[i]``
    toward the probe, pressure ``P[i]`` and the probe's pressure gradient
    ``G[i]``; ``p`` the port origin, ``J`` the rotation vector's Jacobian,
    ``qd = [v; omega]``, ``d`` the Hunt-Crossley dissipation. Plain loops, as
    the pads' kernel."""
    w0, w1, w2 = qd[3], qd[4], qd[5]
    for i in range(A.shape[0]):
        a = A[i]
        n0, n1, n2 = N[i, 0], N[i, 1], N[i, 2]
        u0, u1, u2 = X[i, 0] - p[0], X[i, 1] - p[1], X[i, 2] - p[2]
        g0, g1, g2 = G[i, 0], G[i, 1], G[i, 2]
        # the separating speed of the device's point at the face: n . (v + omega x u)
        vn = (
            n0 * (qd[0] + w1 * u2 - w2 * u1)
            + n1 * (qd[1] + w2 * u0 - w0 * u2)
            + n2 * (qd[2] + w0 * u1 - w1 * u0)
        )
        damp = 1.0 - d * vn
        if damp <= 0.0:
            continue  # Drake's traction is clamped at zero: no pull
        pa = P[i] * a
        # the pressure at the face's fixed point as the probe moves:
        # dP/dp = -g; dP/dtheta = -(u x g)' J (a rotation about the port origin)
        ug0, ug1, ug2 = u1 * g2 - u2 * g1, u2 * g0 - u0 * g2, u0 * g1 - u1 * g0
        dP = np.zeros(6)
        dP[0], dP[1], dP[2] = -g0, -g1, -g2
        for c in range(3):
            dP[3 + c] = -(ug0 * J[0, c] + ug1 * J[1, c] + ug2 * J[2, c])
        # vn's dependence on the port position: d(omega x (x - p))/dp
        nw0, nw1, nw2 = n1 * w2 - n2 * w1, n2 * w0 - n0 * w2, n0 * w1 - n1 * w0
        dvn = np.zeros(6)
        dvn[0], dvn[1], dvn[2] = -nw0, -nw1, -nw2
        # d vn / d qd = [n; u x n]
        un0, un1, un2 = u1 * n2 - u2 * n1, u2 * n0 - u0 * n2, u0 * n1 - u1 * n0
        dvd = np.array([n0, n1, n2, un0, un1, un2])
        f = pa * damp  # the face's force along n
        f0, f1, f2 = f * n0, f * n1, f * n2
        for j in range(6):
            fq = a * (damp * dP[j] - P[i] * d * dvn[j])
            fqd = -pa * d * dvd[j]
            w_q[3, j] += n0 * fq
            w_q[4, j] += n1 * fq
            w_q[5, j] += n2 * fq
            w_qd[3, j] += n0 * fqd
            w_qd[4, j] += n1 * fqd
            w_qd[5, j] += n2 * fqd
            # moment u x f: u x df, and the lever arm u = x - p shortening as p moves
            w_q[0, j] += (u1 * n2 - u2 * n1) * fq
            w_q[1, j] += (u2 * n0 - u0 * n2) * fq
            w_q[2, j] += (u0 * n1 - u1 * n0) * fq
            w_qd[0, j] += (u1 * n2 - u2 * n1) * fqd
            w_qd[1, j] += (u2 * n0 - u0 * n2) * fqd
            w_qd[2, j] += (u0 * n1 - u1 * n0) * fqd
        # d u / d p = -I: d(u x f)/dp_j = -e_j x f
        w_q[0, 1] -= f2
        w_q[0, 2] += f1
        w_q[1, 0] += f2
        w_q[1, 2] -= f0
        w_q[2, 0] -= f1
        w_q[2, 1] += f0


@functools.cache
def hydroelastic_jacobians():
    """:func:`_face_jacobians`, compiled by numba if it is importable."""
    return njit_cached(_face_jacobians) if compiled_available() else _face_jacobians


def facet_sag_m(contact) -> float:
    """How far the faceted surface lies inside the smooth one at most (m):
    the sag of a facet of the rim's outer edge, ``2 R_m (1 - cos(pi / FACETS))``."""
    return 2.0 * contact.mouth_radius_m * (1.0 - math.cos(math.pi / FACETS)) + 1e-9


def _segment_distance(rho: float, z: float, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = float(np.clip(((rho - a[0]) * ab[0] + (z - a[1]) * ab[1]) / float(ab @ ab), 0.0, 1.0))
    return math.hypot(rho - a[0] - t * ab[0], z - a[1] - t * ab[1])


def wall_depth_m(contact, centre: np.ndarray) -> float:
    """How far the probe head with its centre at ``centre`` (W, m) is pressed
    into the drogue: its radius minus the distance from the centre to the
    profile in the centre's meridian plane (the nearest point of a surface of
    revolution lies there), on either side of the axis; <= 0 apart."""
    rho = math.hypot(centre[0], centre[1])
    prof = profile(contact)
    far = math.inf
    for side in (1.0, -1.0):  # the meridian half-plane through the centre, and its mirror
        pts = prof * np.array([side, 1.0])
        for a, b in zip(pts[:-1], pts[1:], strict=True):
            far = min(far, _segment_distance(rho, float(centre[2]), a, b))
    return contact.probe_radius_m - far


def first_touch_gap_m(contact, centre: np.ndarray) -> float:
    """How far the probe head at ``centre`` (W, m) moves along +z before it
    touches the drogue (m; ``inf``: never): the smallest ``s >= 0`` with
    :func:`wall_depth_m` at ``centre + s e_z`` reaching 0, found on a grid of a
    fifth of the radius and refined by bisection."""
    r = contact.probe_radius_m
    top = floor_depth_m(contact) + r
    step = 0.2 * r
    c = np.array(centre, dtype=float)
    s_prev = 0.0
    if wall_depth_m(contact, c) >= 0.0:
        return 0.0
    for s in np.arange(step, max(top - c[2], 0.0) + 2 * step, step):
        if wall_depth_m(contact, c + [0.0, 0.0, s]) >= 0.0:
            lo, hi = s_prev, float(s)
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if wall_depth_m(contact, c + [0.0, 0.0, mid]) >= 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        s_prev = float(s)
    return math.inf
