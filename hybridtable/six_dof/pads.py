"""The pad ring against the flat plate: the docking devices of Drake's point contact.

The active device is a ring of spherical pads, the passive one a flat plate
whose face is the plane ``z = 0`` of the target frame W
(:class:`~hybridtable.six_dof.devices.DockingContactParams`). Each pad touches
the plate as a point pair: Drake's compliant point contact with Hunt-Crossley
dissipation and regularized Coulomb friction. :func:`register_pads` adds both
devices to a plant. :func:`pad_stiffness` is the closed form of the contact's
6x6 stiffness and damping at a pose: the touching pads from the geometry
(:func:`_pad_contacts`, Drake's point pairs in closed form) and their
derivatives (:func:`_pad_jacobians`), one compiled call.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction

from hybridtable.laws.compiled import compiled_kernel
from hybridtable.laws.contact import hunt_crossley_force
from hybridtable.six_dof.pose import rotation_exp, rotation_jacobian, skew
from hybridtable.systems.contact_law import ContactLawParams, contact_law_force

__all__ = [
    "STICTION_TOLERANCE_M_PER_S",
    "register_pads",
    "pad_stiffness",
    "pad_geometry",
    "pad_wrench",
    "wrench_of",
    "pad_law",
    "pad_law_contacts",
    "pad_law_stiffness",
]


#: Drake's stiction tolerance of a continuous plant (m/s), stated on the plant:
#: below it the friction coefficient rises as a smooth step from 0.
STICTION_TOLERANCE_M_PER_S = 1e-4
#: Drake's point contact has no friction below this slip speed (m/s).
_NONZERO_SLIP_M_PER_S = 1e-14


def _pad_jacobians(U, F, X, N, J, qd, FN, KX, KV, mu, r, w_q, w_qd) -> None:
    """Add to ``w_q = dw/dq`` and ``w_qd = dw/dqd`` (6x6) the touching pads' terms
    (see :meth:`DockingContact.stiffness`): row ``i`` of ``U``, ``F``, ``X``, ``N``
    is a pad's contact point from the port origin, its force on the device, its
    depth and the face's normal toward the device; ``FN[i]`` its normal force,
    ``KX[i]`` and ``KV[i]`` that force's derivatives by the depth and by the
    penetration rate (the pad law's). ``J`` is the rotation vector's Jacobian;
    ``mu``, ``r`` the friction coefficient and the pads' radius. Plain loops:
    numba compiles the function, and it runs as Python where numba is missing."""
    du = np.zeros((3, 6))
    vc_q = np.zeros((3, 6))
    vc_qd = np.zeros((3, 6))
    f_q = np.zeros((3, 6))
    f_qd = np.zeros((3, 6))
    turn = np.zeros((3, 3))
    dx = np.zeros(6)
    fn_q = np.zeros(6)
    fn_qd = np.zeros(6)
    for i in range(U.shape[0]):
        u0, u1, u2 = U[i, 0], U[i, 1], U[i, 2]
        n0, n1, n2 = N[i, 0], N[i, 1], N[i, 2]
        x = X[i]
        lift = r - 0.5 * x
        b0, b1, b2 = u0 + lift * n0, u1 + lift * n1, u2 + lift * n2  # the pad's centre
        for c in range(3):  # turn = -[b]x J: d(centre - p)/dtheta
            turn[0, c] = b2 * J[1, c] - b1 * J[2, c]
            turn[1, c] = b0 * J[2, c] - b2 * J[0, c]
            turn[2, c] = b1 * J[0, c] - b0 * J[1, c]
        dx[0], dx[1], dx[2] = -n0, -n1, -n2  # d depth / dq
        for c in range(3):
            dx[3 + c] = -(n0 * turn[0, c] + n1 * turn[1, c] + n2 * turn[2, c])
        for j in range(6):  # d(C - p)/dq
            du[0, j] = 0.5 * n0 * dx[j]
            du[1, j] = 0.5 * n1 * dx[j]
            du[2, j] = 0.5 * n2 * dx[j]
        for a in range(3):
            for c in range(3):
                du[a, 3 + c] += turn[a, c]
        w0, w1, w2 = qd[3], qd[4], qd[5]
        vc0 = qd[0] + w1 * u2 - w2 * u1  # the device's point at C
        vc1 = qd[1] + w2 * u0 - w0 * u2
        vc2 = qd[2] + w0 * u1 - w1 * u0
        for j in range(6):  # d v_C/dq = [omega]x du; d v_C/dqd = [I, -[u]x]
            vc_q[0, j] = w1 * du[2, j] - w2 * du[1, j]
            vc_q[1, j] = w2 * du[0, j] - w0 * du[2, j]
            vc_q[2, j] = w0 * du[1, j] - w1 * du[0, j]
        for a in range(3):
            for j in range(3):
                vc_qd[a, j] = 1.0 if a == j else 0.0
        vc_qd[0, 3], vc_qd[0, 4], vc_qd[0, 5] = 0.0, u2, -u1
        vc_qd[1, 3], vc_qd[1, 4], vc_qd[1, 5] = -u2, 0.0, u0
        vc_qd[2, 3], vc_qd[2, 4], vc_qd[2, 5] = u1, -u0, 0.0
        n_vc = n0 * vc0 + n1 * vc1 + n2 * vc2  # minus the penetration rate
        fn = FN[i]
        for j in range(6):  # the penetration rate's derivatives are -n . d v_C
            fn_q[j] = KX[i] * dx[j] - KV[i] * (n0 * vc_q[0, j] + n1 * vc_q[1, j] + n2 * vc_q[2, j])
            fn_qd[j] = -KV[i] * (n0 * vc_qd[0, j] + n1 * vc_qd[1, j] + n2 * vc_qd[2, j])
            f_q[0, j], f_q[1, j], f_q[2, j] = n0 * fn_q[j], n1 * fn_q[j], n2 * fn_q[j]
            f_qd[0, j], f_qd[1, j], f_qd[2, j] = n0 * fn_qd[j], n1 * fn_qd[j], n2 * fn_qd[j]
        s0, s1, s2 = vc0 - n_vc * n0, vc1 - n_vc * n1, vc2 - n_vc * n2  # the slip
        s = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        if mu > 0.0 and s > _NONZERO_SLIP_M_PER_S:
            mu_s, dmu = _regularized_friction(mu, s)
            t = (s0 / s, s1 / s, s2 / s)
            nn = (n0, n1, n2)
            # d(mu(s) t)/d v_C = H (I - n n'), H = mu(s)/s (I - t t') + mu'(s) t t'
            H = np.zeros((3, 3))
            for a in range(3):
                for c in range(3):
                    e = 1.0 if a == c else 0.0
                    H[a, c] = (mu_s / s) * (e - t[a] * t[c]) + dmu * t[a] * t[c]
            P = np.zeros((3, 3))
            for a in range(3):
                hn = H[a, 0] * nn[0] + H[a, 1] * nn[1] + H[a, 2] * nn[2]
                for c in range(3):
                    P[a, c] = H[a, c] - hn * nn[c]
            for a in range(3):
                for j in range(6):
                    f_q[a, j] -= mu_s * t[a] * fn_q[j] + fn * (
                        P[a, 0] * vc_q[0, j] + P[a, 1] * vc_q[1, j] + P[a, 2] * vc_q[2, j]
                    )
                    f_qd[a, j] -= mu_s * t[a] * fn_qd[j] + fn * (
                        P[a, 0] * vc_qd[0, j] + P[a, 1] * vc_qd[1, j] + P[a, 2] * vc_qd[2, j]
                    )
        f0, f1, f2 = F[i, 0], F[i, 1], F[i, 2]
        for j in range(6):  # moment u x f: [u]x df - [f]x du (the geometric term)
            w_q[0, j] += u1 * f_q[2, j] - u2 * f_q[1, j] - (f1 * du[2, j] - f2 * du[1, j])
            w_q[1, j] += u2 * f_q[0, j] - u0 * f_q[2, j] - (f2 * du[0, j] - f0 * du[2, j])
            w_q[2, j] += u0 * f_q[1, j] - u1 * f_q[0, j] - (f0 * du[1, j] - f1 * du[0, j])
            w_qd[0, j] += u1 * f_qd[2, j] - u2 * f_qd[1, j]
            w_qd[1, j] += u2 * f_qd[0, j] - u0 * f_qd[2, j]
            w_qd[2, j] += u0 * f_qd[1, j] - u1 * f_qd[0, j]
            for a in range(3):
                w_q[3 + a, j] += f_q[a, j]
                w_qd[3 + a, j] += f_qd[a, j]


def _regularized_friction(mu, s):
    """Drake's regularized Coulomb friction at the slip speed ``s > 0``: ``mu
    step5(s / v_s)`` below the stiction tolerance ``v_s``, ``mu`` above
    (``step5(z) = z^3 (10 - 15 z + 6 z^2)``), and its derivative by ``s``."""
    z = s / STICTION_TOLERANCE_M_PER_S
    if z < 1.0:
        return (
            mu * z * z * z * (10.0 + z * (6.0 * z - 15.0)),
            mu * 30.0 * z * z * (1.0 - z) * (1.0 - z) / STICTION_TOLERANCE_M_PER_S,
        )
    return mu, 0.0


def _pad_geometry(p, R, qd, centres, r):
    """The pads pressing the plate's face ``z = 0`` with the device at ``p``,
    ``R`` (W) moving at ``qd = [v; omega]``: ``(U, X, V)``, rows for those pads
    only: the contact point from the port origin, the depth, the device's
    velocity at the contact point. Each pad (centre ``c = p + R c_P``, radius
    ``r``) presses by ``x = r + c_z``; the contact point is half-way into the
    press, ``C = c - (r - x/2) n`` with ``n = -z`` the face's normal toward the
    device (Drake's point pair)."""
    m = centres.shape[0]
    U = np.zeros((m, 3))
    X = np.zeros(m)
    V = np.zeros((m, 3))
    count = 0
    for i in range(m):
        c0 = p[0] + R[0, 0] * centres[i, 0] + R[0, 1] * centres[i, 1] + R[0, 2] * centres[i, 2]
        c1 = p[1] + R[1, 0] * centres[i, 0] + R[1, 1] * centres[i, 1] + R[1, 2] * centres[i, 2]
        c2 = p[2] + R[2, 0] * centres[i, 0] + R[2, 1] * centres[i, 1] + R[2, 2] * centres[i, 2]
        x = r + c2
        if not x > 0.0:
            continue
        u0, u1, u2 = c0 - p[0], c1 - p[1], c2 + (r - 0.5 * x) - p[2]
        w0, w1, w2 = qd[3], qd[4], qd[5]
        U[count, 0], U[count, 1], U[count, 2] = u0, u1, u2
        X[count] = x
        V[count, 0] = qd[0] + w1 * u2 - w2 * u1
        V[count, 1] = qd[1] + w2 * u0 - w0 * u2
        V[count, 2] = qd[2] + w0 * u1 - w1 * u0
        count += 1
    return U[:count], X[:count], V[:count]


def _pad_forces(U, X, V, FN, mu):
    """``(U, F, X, N)`` of :func:`_pad_contacts` from the pressing pads'
    geometry (:func:`_pad_geometry`) and their normal forces ``FN``: the pads
    whose normal force is positive, each pushing the device with ``f_n (n -
    mu(s) t)``, ``s t`` the slip of the device's point along the face
    (:func:`_regularized_friction`); and ``keep``, those pads' rows."""
    m = X.shape[0]
    F = np.zeros((m, 3))
    N = np.zeros((m, 3))
    keep = np.zeros(m, dtype=np.int64)
    count = 0
    for i in range(m):
        fn = FN[i]
        if not fn > 0.0:
            continue
        f0, f1, f2 = 0.0, 0.0, -fn
        s0, s1 = V[i, 0], V[i, 1]  # the slip along the face
        s = math.sqrt(s0 * s0 + s1 * s1)
        if mu > 0.0 and s > _NONZERO_SLIP_M_PER_S:
            mu_s = _regularized_friction(mu, s)[0]
            f0 -= mu_s * fn * s0 / s
            f1 -= mu_s * fn * s1 / s
        F[count, 0], F[count, 1], F[count, 2] = f0, f1, f2
        N[count, 2] = -1.0
        keep[count] = i
        count += 1
    keep = keep[:count]
    return U[keep], F[:count], X[keep], N[:count], keep


def _drake_law(X, V, k, d):
    """Drake's point contact of each pressing pad: its normal force ``k x (1 +
    d xdot)`` (``xdot = -n . v_C``: the Hunt–Crossley law,
    :func:`~hybridtable.laws.contact.hunt_crossley_force`, on the spring ``k
    x``), and its derivatives by ``x`` and ``xdot``: ``(FN, KX, KV)``."""
    m = X.shape[0]
    FN = np.zeros(m)
    KX = np.zeros(m)
    KV = np.zeros(m)
    for i in range(m):
        FN[i], KX[i], KV[i] = hunt_crossley_force(k * X[i], k, d, V[i, 2])
    return FN, KX, KV


def _pad_contacts(p, R, qd, centres, r, k, d, mu):
    """The touching pads of the device at ``p``, ``R`` (W) moving at ``qd =
    [v; omega]``: ``(U, F, X, N)`` as :func:`_pad_jacobians` takes them, rows
    for the touching pads only. Each pad (centre ``c = p + R c_P``, radius
    ``r``) presses the plate's face ``z = 0`` by ``x = r + c_z``; the contact
    point is half-way into the press, ``C = c - (r - x/2) n`` with ``n = -z``
    the face's normal toward the device; the force on the device is Drake's
    point contact, ``f_n (n - mu(s) t)`` with ``f_n = k x (1 - d n . v_C)``,
    ``v_C`` the device's velocity at ``C``, ``s t`` its slip along the face
    and ``mu(s)`` Drake's regularized Coulomb friction. A pad whose
    Hunt–Crossley force is not positive (separating faster than ``1 / d``)
    is no contact, as Drake reports no pair for it. Drake's sphere-box
    query of the pads against the plate's box gives the same numbers
    (tested); this is that contact without the query."""
    U, X, V = _pad_geometry(p, R, qd, centres, r)
    FN = _drake_law(X, V, k, d)[0]
    U, F, X, N, _ = _pad_forces(U, X, V, FN, mu)
    return U, F, X, N


def _pad_stiffness(q, qd, centres, r, k, d, mu):
    """``(K, C)`` of the pads at the port pose ``q = [p; theta]`` moving at ``qd``
    (:meth:`~hybridtable.six_dof.contact.DockingContact.stiffness`) with
    Drake's law: :func:`_pad_geometry`, :func:`_drake_law`,
    :func:`_pad_forces`, then :func:`_pad_jacobians`, one compiled call."""
    theta = q[3:6]
    U, X, V = _pad_geometry(q[0:3], rotation_exp(theta), qd, centres, r)
    FN, KX, KV = _drake_law(X, V, k, d)
    U, F, X, N, keep = _pad_forces(U, X, V, FN, mu)
    w_q = np.zeros((6, 6))
    w_qd = np.zeros((6, 6))
    J = rotation_jacobian(theta)
    _pad_jacobians(U, F, X, N, J, qd, FN[keep], KX[keep], KV[keep], mu, r, w_q, w_qd)
    return -w_q, -w_qd


def _wrench_of(U, F):
    """``[moment about the port origin; force]`` (6) of the point forces
    ``F[i]`` at ``U[i]`` from the port origin."""
    w = np.zeros(6)
    for i in range(U.shape[0]):
        u0, u1, u2 = U[i, 0], U[i, 1], U[i, 2]
        f0, f1, f2 = F[i, 0], F[i, 1], F[i, 2]
        w[0] += u1 * f2 - u2 * f1
        w[1] += u2 * f0 - u0 * f2
        w[2] += u0 * f1 - u1 * f0
        w[3] += f0
        w[4] += f1
        w[5] += f2
    return w


def _pad_wrench(q, qd, centres, r, k, d, mu):
    """The pads' wrench on the device at the port pose ``q = [p; theta]``
    moving at ``qd`` with Drake's law (:func:`_pad_contacts`, Drake's point
    pairs in closed form), and the touching pads' ``(U, F)``, one compiled call."""
    U, F, _, _ = _pad_contacts(q[0:3], rotation_exp(q[3:6]), qd, centres, r, k, d, mu)
    return _wrench_of(U, F), U, F


_HELPERS = (
    hunt_crossley_force,
    skew,
    rotation_exp,
    rotation_jacobian,
    _regularized_friction,
    _pad_geometry,
    _pad_forces,
    _drake_law,
    _pad_jacobians,
    _pad_contacts,
    _wrench_of,
)


def pad_stiffness():
    """:func:`_pad_stiffness`, compiled by numba if it is importable."""
    return compiled_kernel(_pad_stiffness, _HELPERS)


def pad_wrench():
    """:func:`_pad_wrench`, compiled by numba if it is importable."""
    return compiled_kernel(_pad_wrench, _HELPERS)


def wrench_of():
    """:func:`_wrench_of`, compiled by numba if it is importable."""
    return compiled_kernel(_wrench_of, _HELPERS)


def pad_geometry():
    """:func:`_pad_geometry`, compiled by numba if it is importable."""
    return compiled_kernel(_pad_geometry, _HELPERS)


def pad_law(
    law: ContactLawParams, X: np.ndarray, V: np.ndarray, derivatives: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The normal force of each pressing pad by the 1-D contact law ``law``
    (:func:`~hybridtable.systems.contact_law.contact_law_force`, one pad's
    law) at its depth ``X[i]`` and penetration rate ``-n . V[i]`` (``n = -z``):
    ``(FN, KX, KV)``, the derivatives by the depth and the rate exact
    (``AutoDiffXd``) when ``derivatives``, else zero."""
    m = X.shape[0]
    FN, KX, KV = np.zeros(m), np.zeros(m), np.zeros(m)
    for i in range(m):
        x, rate = float(X[i]), float(V[i, 2])
        if not derivatives:
            FN[i] = float(contact_law_force(law, x, rate)[0])
            continue
        f = contact_law_force(
            law, AutoDiffXd(x, np.array([1.0, 0.0])), AutoDiffXd(rate, np.array([0.0, 1.0]))
        )[0]
        FN[i] = f.value()
        grad = f.derivatives()
        if grad.size:
            KX[i], KV[i] = grad
    return FN, KX, KV


def pad_law_contacts(
    q: np.ndarray, qd: np.ndarray, centres: np.ndarray, r: float, law: ContactLawParams, mu: float
):
    """The pads' point pairs with the device at ``q = [p; theta]`` moving at
    ``qd`` by the 1-D contact law ``law`` per pad (:func:`pad_law`), the
    friction across the face Drake's: ``(U, F, X, N)`` as :func:`_pad_contacts`
    returns them."""
    U, X, V = pad_geometry()(q[0:3], rotation_exp(q[3:6]), qd, centres, r)
    FN = pad_law(law, X, V)[0]
    U, F, X, N, _ = _pad_forces(U, X, V, FN, mu)
    return U, F, X, N


def pad_law_stiffness(
    q: np.ndarray, qd: np.ndarray, centres: np.ndarray, r: float, law: ContactLawParams, mu: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(K, C)`` of :func:`_pad_stiffness` with the 1-D contact law ``law`` per
    pad (:func:`pad_law`, its derivatives exact)."""
    theta = q[3:6]
    U, X, V = pad_geometry()(q[0:3], rotation_exp(theta), qd, centres, r)
    FN, KX, KV = pad_law(law, X, V, derivatives=True)
    U, F, X, N, keep = _pad_forces(U, X, V, FN, mu)
    w_q = np.zeros((6, 6))
    w_qd = np.zeros((6, 6))
    _pad_jacobians(
        U, F, X, N, rotation_jacobian(theta), qd, FN[keep], KX[keep], KV[keep], mu, r, w_q, w_qd
    )
    return -w_q, -w_qd


#: Half the side of the passive plate's collision box (m): large enough that
#: its face stays the nearest face of every pad over any reachable pose.
_PLATE_HALF_SIDE_M = 5.0


def register_pads(plant, device_body, X_device_port, target_body, X_target_face, params) -> list:
    """Register the pads on ``device_body`` and the plate on ``target_body``
    (arguments as :func:`~hybridtable.six_dof.contact.register_docking_devices`;
    each pad pair's stiffness is ``k / pad_count``, each geometry gets twice
    that, since point-contact stiffnesses combine in series).

    Returns
    -------
    list of GeometryId
        The pads' collision geometries.
    """
    k_pair = params.contact_stiffness_n_per_m / params.pad_count
    mu = params.friction_coefficient

    def material() -> ProximityProperties:
        props = ProximityProperties()
        AddContactMaterial(
            dissipation=params.contact_dissipation_s_per_m,
            point_stiffness=2.0 * k_pair,
            friction=CoulombFriction(mu, mu),
            properties=props,
        )
        return props

    pads = []
    blue = np.array([0.2, 0.4, 0.8, 1.0])
    for i, centre in enumerate(params.pad_centres_m):
        X = X_device_port @ RigidTransform(centre)
        sphere = Sphere(params.pad_radius_m)
        pads.append(plant.RegisterCollisionGeometry(device_body, X, sphere, f"pad_{i}", material()))
        plant.RegisterVisualGeometry(device_body, X, sphere, f"pad_{i}", blue)
    h = _PLATE_HALF_SIDE_M
    X_plate = X_target_face @ RigidTransform([0.0, 0.0, h])
    plant.RegisterCollisionGeometry(
        target_body, X_plate, Box(2 * h, 2 * h, 2 * h), "plate", material()
    )
    side = 2.6 * params.ring_radius_m
    plant.RegisterVisualGeometry(
        target_body,
        X_target_face @ RigidTransform([0.0, 0.0, 0.02]),
        Box(side, side, 0.04),
        "plate",
        np.array([0.8, 0.5, 0.2, 0.8]),
    )
    return pads
