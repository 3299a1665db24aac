"""The docking devices' compliant contact, computed by Drake's point contact.

The active device is a ring of spherical pads (:class:`DockingContactParams`),
the passive one a flat plate whose face is the plane ``z = 0`` of the target
frame W. :func:`register_docking_devices` adds both to any MultibodyPlant (the
Stewart plant uses it too); :class:`DockingContact` holds a small plant of the
two devices alone (the device a free body, the plate welded to the world) and
evaluates the contact wrench at a pose and twist through the plant's contact
results (Drake's compliant point contact with Hunt–Crossley dissipation and
regularized Coulomb friction); :class:`DockingContactSystem` is that as a
Drake system of the loop.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import RigidBody, SpatialInertia
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.laws.compiled import compiled_available, njit_cached
from hybridtable.limits import check_plausible
from hybridtable.six_dof.pose import rotation_exp, rotation_jacobian
from hybridtable.stewart.geometry import cross

__all__ = [
    "DockingContactParams",
    "register_docking_devices",
    "DockingContact",
    "DockingContactSystem",
    "STICTION_TOLERANCE_M_PER_S",
]


@dataclass(frozen=True)
class DockingContactParams:
    """The docking devices and their compliant contact (Drake point contact).

    The active device (on the table) is a ring of ``pad_count`` spherical
    pads of radius ``pad_radius_m`` on a circle of ``ring_radius_m``, their
    tops in the port's face plane; the passive device is a flat plate.

    Parameters
    ----------
    contact_stiffness_n_per_m : float
        Total normal stiffness k of the contact with every pad touching, > 0
        (each pad ``k / pad_count``).
    contact_dissipation_s_per_m : float
        Hunt–Crossley dissipation d of each pad, ``f = k_i x (1 + d dx/dt)``, >= 0.
    friction_coefficient : float
        Coulomb friction mu of the pads on the plate, >= 0 (Drake's
        regularized friction).
    pad_count : int
        Number of pads, >= 3.
    ring_radius_m, pad_radius_m : float
        Ring and pad radii, > 0, ``pad_radius_m < ring_radius_m``.
    """

    contact_stiffness_n_per_m: float
    contact_dissipation_s_per_m: float = 0.0
    friction_coefficient: float = 0.0
    pad_count: int = 8
    ring_radius_m: float = 0.3
    pad_radius_m: float = 0.01

    def __post_init__(self) -> None:
        s = object.__setattr__
        k = check_positive("contact_stiffness_n_per_m", self.contact_stiffness_n_per_m)
        s(self, "contact_stiffness_n_per_m", check_plausible("contact_stiffness_n_per_m", k))
        for name in ("contact_dissipation_s_per_m", "friction_coefficient"):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        if isinstance(self.pad_count, bool) or int(self.pad_count) != self.pad_count:
            raise ParameterError(f"pad_count must be a whole number (got {self.pad_count!r})")
        if not 3 <= int(self.pad_count) <= 64:
            raise ParameterError(f"pad_count must be in [3, 64] (got {self.pad_count!r})")
        s(self, "pad_count", int(self.pad_count))
        for name in ("ring_radius_m", "pad_radius_m"):
            s(self, name, check_positive(name, getattr(self, name)))
        if self.pad_radius_m >= self.ring_radius_m:
            raise ParameterError(
                f"pad_radius_m {self.pad_radius_m:g} must be < ring_radius_m {self.ring_radius_m:g}"
            )

    @property
    def pad_centres_m(self) -> np.ndarray:
        """Pad centres in the port frame, (pad_count, 3) (m)."""
        a = 2.0 * np.pi * np.arange(self.pad_count) / self.pad_count
        r = self.ring_radius_m
        return np.column_stack(
            [r * np.cos(a), r * np.sin(a), np.full(self.pad_count, -self.pad_radius_m)]
        )


#: Drake's stiction tolerance of a continuous plant (m/s), stated on the plant:
#: below it the friction coefficient rises as a smooth step from 0.
STICTION_TOLERANCE_M_PER_S = 1e-4
#: Drake's point contact has no friction below this slip speed (m/s).
_NONZERO_SLIP_M_PER_S = 1e-14


def _pad_jacobians(U, F, X, N, J, qd, k, d, mu, r, w_q, w_qd) -> None:
    """Add to ``w_q = dw/dq`` and ``w_qd = dw/dqd`` (6x6) the touching pads' terms
    (see :meth:`DockingContact.stiffness`): row ``i`` of ``U``, ``F``, ``X``, ``N``
    is a pad's contact point from the port origin, its force on the device, its
    depth and the face's normal toward the device. ``J`` is the rotation
    vector's Jacobian; ``k``, ``d``, ``mu``, ``r`` the pad pair's stiffness,
    dissipation, friction coefficient and the pads' radius. Plain loops: numba
    compiles the function, and it runs as Python where numba is missing."""
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
        fn = k * x * (1.0 - d * n_vc)
        for j in range(6):
            fn_q[j] = k * (1.0 - d * n_vc) * dx[j] - k * x * d * (
                n0 * vc_q[0, j] + n1 * vc_q[1, j] + n2 * vc_q[2, j]
            )
            fn_qd[j] = -k * x * d * (n0 * vc_qd[0, j] + n1 * vc_qd[1, j] + n2 * vc_qd[2, j])
            f_q[0, j], f_q[1, j], f_q[2, j] = n0 * fn_q[j], n1 * fn_q[j], n2 * fn_q[j]
            f_qd[0, j], f_qd[1, j], f_qd[2, j] = n0 * fn_qd[j], n1 * fn_qd[j], n2 * fn_qd[j]
        s0, s1, s2 = vc0 - n_vc * n0, vc1 - n_vc * n1, vc2 - n_vc * n2  # the slip
        s = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        if mu > 0.0 and s > _NONZERO_SLIP_M_PER_S:
            # Drake's regularized Coulomb friction: mu step5(s / v_s) below the
            # stiction tolerance v_s, mu above; step5(z) = z^3 (10 - 15 z + 6 z^2).
            z = s / STICTION_TOLERANCE_M_PER_S
            mu_s, dmu = mu, 0.0
            if z < 1.0:
                mu_s = mu * z * z * z * (10.0 + z * (6.0 * z - 15.0))
                dmu = mu * 30.0 * z * z * (1.0 - z) * (1.0 - z) / STICTION_TOLERANCE_M_PER_S
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


@functools.cache
def _jacobian_kernel():
    """:func:`_pad_jacobians`, compiled by numba if it is importable."""
    return njit_cached(_pad_jacobians) if compiled_available() else _pad_jacobians


#: Half the side of the passive plate's collision box (m): large enough that
#: its face stays the nearest face of every pad over any reachable pose.
_PLATE_HALF_SIDE_M = 5.0


def register_docking_devices(
    plant,
    device_body: RigidBody,
    X_device_port: RigidTransform,
    target_body: RigidBody,
    X_target_face: RigidTransform,
    params: DockingContactParams,
    pad_stiffness_scale: float = 1.0,
) -> list:
    """Register the pads on ``device_body`` and the plate on ``target_body``.

    Parameters
    ----------
    plant : MultibodyPlant
        Not yet finalized, registered with a SceneGraph.
    device_body : RigidBody
    X_device_port : RigidTransform
        The port frame P in the device body's frame.
    target_body : RigidBody
    X_target_face : RigidTransform
        The target frame W (plate face at its z = 0, plate at z > 0) in the
        target body's frame.
    params : DockingContactParams
    pad_stiffness_scale : float
        Multiplies every point stiffness (1: the pad pair's combined
        stiffness is ``k / pad_count``; each geometry gets twice that, since
        point-contact stiffnesses combine in series).

    Returns
    -------
    list of GeometryId
        The pads' collision geometries.
    """
    k_pair = params.contact_stiffness_n_per_m / params.pad_count * pad_stiffness_scale
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


class DockingContact:
    """Drake's contact of the two docking devices, evaluated at a device pose.

    Parameters
    ----------
    params : DockingContactParams
    """

    def __init__(self, params: DockingContactParams) -> None:
        self.params = params
        builder = DiagramBuilder()
        plant, _ = AddMultibodyPlantSceneGraph(builder, 0.0)
        # The device's inertia plays no part: its motion is prescribed.
        self._device = plant.AddRigidBody("device", SpatialInertia.SolidSphereWithMass(1.0, 0.1))
        register_docking_devices(
            plant,
            self._device,
            RigidTransform(),
            plant.world_body(),
            RigidTransform(),
            params,
        )
        plant.set_stiction_tolerance(STICTION_TOLERANCE_M_PER_S)
        plant.Finalize()
        self._plant = plant
        self._diagram = builder.Build()
        self._context = self._diagram.CreateDefaultContext()
        self._plant_context = plant.GetMyMutableContextFromRoot(self._context)
        self._results = plant.get_contact_results_output_port()
        self._device_index = self._device.index()

    def _contacts(self, q: np.ndarray, qd: np.ndarray | None):
        """Drake's point pairs of the pads with the device at ``q`` moving at
        ``qd``: ``(port origin p, [(contact point, force on the device, the
        pair's depth, normal out of the plate toward the device), ...])``."""
        p = np.asarray(q[:3], dtype=float)
        R = rotation_exp(q[3:])
        plant, ctx = self._plant, self._plant_context
        plant.SetFreeBodyPose(ctx, self._device, RigidTransform(RotationMatrix(R), p))
        if qd is None:
            plant.SetFreeBodySpatialVelocity(ctx, self._device, SpatialVelocity(np.zeros(6)))
        else:
            plant.SetFreeBodySpatialVelocity(
                ctx, self._device, SpatialVelocity(np.asarray(qd[3:]), np.asarray(qd[:3]))
            )
        results = self._results.Eval(ctx)
        pairs = []
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            f = info.contact_force()  # on body B, at the contact point
            pair = info.point_pair()
            normal = pair.nhat_BA_W  # out of B into A
            if info.bodyA_index() == self._device_index:
                f = -f
            else:
                normal = -normal
            pairs.append((info.contact_point(), f, pair.depth, normal))
        return p, pairs

    def wrench(
        self, q: np.ndarray, qd: np.ndarray | None = None, points: list | None = None
    ) -> np.ndarray:
        """The contact wrench on the device ``[moment; force]`` (6: N m, N) at
        the port origin, in W, with the device at ``q = [p; theta]`` moving at
        ``qd = [v; omega]`` (default at rest). ``points``, when given, gets
        ``(contact point, force on the device)`` of every touching pad (W, m, N)."""
        p, pairs = self._contacts(q, qd)
        force = np.zeros(3)
        moment = np.zeros(3)
        for c, f, _, _ in pairs:
            force += f
            moment += cross(c - p, f)
            if points is not None:
                points.append((np.array(c), np.array(f)))
        return np.concatenate([moment, force])

    def stiffness(
        self, q: np.ndarray, qd: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The contact linearized at ``q`` moving at ``qd`` (default at rest):
        ``K = -dw/dq`` and ``C = -dw/dqd`` (6x6 each, ``w`` the wrench of
        :meth:`wrench`), in closed form from one evaluation of Drake's contact.

        Each touching pad is a sphere of radius ``r`` pressed ``x`` into the
        plate's face (normal ``n`` out of the plate), with Drake's point-contact
        law: normal force ``k x (1 + d xdot)``, ``k`` the pad pair's stiffness,
        ``d`` the dissipation, ``xdot = -n . v_C`` the penetration rate of the
        device's point at the contact point ``C`` (half-way between the two
        surfaces: ``C = c - (r - x/2) n`` with ``c`` the pad's centre), and the
        regularized Coulomb friction ``-mu(s) f_n t`` against the slip ``s t``
        (Drake's Stribeck curve, see :func:`_pad_jacobians`). Moving the pose by ``dq = [dp;
        dtheta]`` moves the centre by ``dp - [c - p]x J dtheta`` (``J`` the
        rotation vector's Jacobian, :func:`~hybridtable.six_dof.pose.rotation_jacobian`),
        the depth by ``-n`` times that, and the lever arm ``C - p`` with
        both: its change times the force is the geometric term of the moment.
        The target's face is flat (its normal does not turn with the contact
        point); a pad's derivative is taken where it touches (a pad that
        starts or stops touching at ``q`` is a kink of ``w``)."""
        q = np.asarray(q, dtype=float)
        qd = np.zeros(6) if qd is None else np.asarray(qd, dtype=float)
        p, pairs = self._contacts(q, qd)
        w_q = np.zeros((6, 6))  # dw/dq
        w_qd = np.zeros((6, 6))  # dw/dqd
        if pairs:
            c = self.params
            _jacobian_kernel()(
                np.array([c for c, _, _, _ in pairs]) - p,
                np.array([f for _, f, _, _ in pairs]),
                np.array([x for _, _, x, _ in pairs]),
                np.array([n for _, _, _, n in pairs]),
                rotation_jacobian(q[3:]),
                qd,
                c.contact_stiffness_n_per_m / c.pad_count,
                c.contact_dissipation_s_per_m,
                c.friction_coefficient,
                c.pad_radius_m,
                w_q,
                w_qd,
            )
        return -w_q, -w_qd


class DockingContactSystem(LeafSystem):
    """The contact of the docking devices as a system of the loop.

    Ports
    -----
    Input ``table_state`` (12: m, rad, m/s, rad/s)
        ``[q; qd]`` of the active device: port position and rotation vector
        in W, velocity and angular velocity.
    Output ``contact_wrench`` (6: N m, N)
        The wrench of the passive device on the active one, ``[moment about
        the port origin; force]`` in W.
    """

    def __init__(self, params: DockingContactParams) -> None:
        LeafSystem.__init__(self)
        self.contact = DockingContact(params)
        self._state = self.DeclareVectorInputPort("table_state", 12)
        self.DeclareVectorOutputPort("contact_wrench", BasicVector(6), self._calc)

    def _calc(self, context, output) -> None:
        x = self._state.Eval(context)
        output.SetFromVector(self.contact.wrench(x[:6], x[6:]))
