"""The docking devices' compliant contact, computed by Drake's point contact.

The active device is a ring of spherical pads (:class:`~hybridtable.six_dof.params.DockingContactParams`),
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

import numpy as np
from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import RigidBody, SpatialInertia
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem

from hybridtable.six_dof.params import DockingContactParams
from hybridtable.six_dof.pose import rotation_exp
from hybridtable.stewart.geometry import cross

__all__ = [
    "register_docking_devices",
    "DockingContact",
    "DockingContactSystem",
]

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
        plant.Finalize()
        self._plant = plant
        self._diagram = builder.Build()
        self._context = self._diagram.CreateDefaultContext()
        self._plant_context = plant.GetMyMutableContextFromRoot(self._context)
        self._results = plant.get_contact_results_output_port()
        self._device_index = self._device.index()

    def wrench(
        self, q: np.ndarray, qd: np.ndarray | None = None, points: list | None = None
    ) -> np.ndarray:
        """The contact wrench on the device ``[moment; force]`` (6: N m, N) at
        the port origin, in W, with the device at ``q = [p; theta]`` moving at
        ``qd = [v; omega]`` (default at rest). ``points``, when given, gets
        ``(contact point, force on the device)`` of every touching pad (W, m, N)."""
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
        force = np.zeros(3)
        moment = np.zeros(3)
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            f = info.contact_force()  # on body B, at the contact point
            if info.bodyA_index() == self._device_index:
                f = -f
            c = info.contact_point()
            force += f
            moment += cross(c - p, f)
            if points is not None:
                points.append((np.array(c), np.array(f)))
        return np.concatenate([moment, force])

    def stiffness(
        self, q: np.ndarray, qd: np.ndarray | None = None, step: float = 1e-7
    ) -> tuple[np.ndarray, np.ndarray]:
        """The contact linearized at ``q``: ``K = -dw/dq`` and ``C = -dw/dqd``
        (6x6 each) by central differences of :meth:`wrench` (steps ``step``
        m and rad; ``step`` m/s and rad/s). ``C`` is zero for an undamped,
        frictionless contact (not evaluated)."""
        q = np.asarray(q, dtype=float)
        qd0 = np.zeros(6) if qd is None else np.asarray(qd, dtype=float)
        K = np.zeros((6, 6))
        for j in range(6):
            e = np.zeros(6)
            e[j] = step
            K[:, j] = -(self.wrench(q + e, qd0) - self.wrench(q - e, qd0)) / (2.0 * step)
        C = np.zeros((6, 6))
        if self.params.contact_dissipation_s_per_m > 0.0 or self.params.friction_coefficient > 0:
            for j in range(6):
                e = np.zeros(6)
                e[j] = step
                C[:, j] = -(self.wrench(q, qd0 + e) - self.wrench(q, qd0 - e)) / (2.0 * step)
        return K, C


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
