"""The Stewart platform, its contact devices and F/T sensor as a Drake MultibodyPlant.

Model (see ``docs/stewart.md``):

- the base is the world; each of the six legs is a cylinder on a universal
  joint at the base and a piston on an actuated prismatic joint (its position
  is the leg length), tied to the free-floating top plate by a ball
  constraint (SAP);
- the active contact device (a rod with a spherical tip) is welded to the
  plate; the reaction wrench of that weld is the 6-axis F/T sensor;
- the passive contact device (a stiff frame, a box) is fixed above the plate
  so that the devices touch exactly when the plate is at its home pose;
- compliant point contact between the tip and the frame, stiffness and
  Hunt–Crossley dissipation from the run's contact parameters
  (:mod:`hybridtable.stewart.hunt_crossley`); the plant uses
  the ``"lagged"`` discrete contact approximation (``"sap"`` ignores
  Hunt–Crossley dissipation and adds its own).

The parameters are :class:`~hybridtable.stewart.params.StewartParams`. The legs
are driven by a digital PD servo (see :mod:`hybridtable.stewart.backend`)
through the plant's actuation input, not by the plant's implicit PD
controllers (with the ball constraints, SAP failed to converge with them in
drake 1.51); the servo then is a sampled PD loop, whose response
:mod:`hybridtable.stewart.identify` measures.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from pydrake.geometry import (
    AddContactMaterial,
    Box,
    Cylinder,
    ProximityProperties,
    SceneGraph,
    Sphere,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    MultibodyPlant,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import (
    FixedOffsetFrame,
    JacobianWrtVariable,
    PrismaticJoint,
    RigidBody,
    RotationalInertia,
    SpatialInertia,
    UniversalJoint,
    WeldJoint,
)
from pydrake.systems.framework import DiagramBuilder

from hybridtable._validation import check_finite, check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.stewart.geometry import StewartGeometry, rpy_from_rotation
from hybridtable.stewart.params import StewartParams

__all__ = [
    "StewartPlant",
    "add_stewart_plant",
]


def _rod_inertia(mass: float, length: float, com_z: float) -> SpatialInertia:
    transverse = mass * length**2 / 12.0
    axial = max(transverse * 1e-3, 1e-6)
    return SpatialInertia.MakeFromCentralInertia(
        mass, np.array([0.0, 0.0, com_z]), RotationalInertia(transverse, transverse, axial)
    )


def _frame_along(z_axis: np.ndarray) -> RotationMatrix:
    """A rotation whose z axis is ``z_axis`` (x horizontal)."""
    z = z_axis / np.linalg.norm(z_axis)
    ref = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(ref, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return RotationMatrix(np.column_stack([x, y, z]))


@dataclass
class StewartPlant:
    """Handles to the platform in a MultibodyPlant (from :func:`add_stewart_plant`)."""

    params: StewartParams
    plant: MultibodyPlant
    scene_graph: SceneGraph
    plate: RigidBody
    device: RigidBody
    sensor_weld: WeldJoint
    universal_joints: list[UniversalJoint]
    leg_joints: list[PrismaticJoint]
    #: Height of the passive device's contact face (world z, m).
    contact_face_height_m: float
    #: Index of each leg's length in the plant's positions / velocities.
    leg_position_indices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    leg_velocity_indices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    #: Start of the plate's [quaternion, position] / [w, v] in q / v.
    plate_position_start: int = 0
    plate_velocity_start: int = 0
    #: Leg forces that hold the platform at home against gravity (N).
    gravity_feedforward_n: np.ndarray = field(default_factory=lambda: np.zeros(6))
    #: Orientation (in the world) of each universal joint's fixed frame; its
    #: z axis is the leg's home direction.
    base_joint_rotations: list[np.ndarray] = field(default_factory=list)

    @property
    def geometry(self) -> StewartGeometry:
        return self.params.geometry

    def set_axis_state(self, plant_context, offset_m: float, velocity_m_per_s: float) -> None:
        """Put the platform at ``offset_m`` from home along the docking axis
        (z), moving at ``velocity_m_per_s`` along it: plate pose and twist,
        leg lengths and joint angles, all consistent with the constraints.

        Raises
        ------
        WorkspaceError
            If the pose leaves the workspace.
        """
        g = self.geometry
        pose = g.axis_pose(offset_m)
        g.inverse_kinematics(pose)  # raises outside the workspace
        q_legs, u_angles = self._leg_coordinates(offset_m)
        eps = 1e-6
        q_p, u_p = self._leg_coordinates(offset_m + eps)
        q_m, u_m = self._leg_coordinates(offset_m - eps)
        v = check_finite("velocity_m_per_s", velocity_m_per_s)
        qdot_legs = (q_p - q_m) / (2 * eps) * v
        udot = (u_p - u_m) / (2 * eps) * v
        plant = self.plant
        plant.SetFreeBodyPose(plant_context, self.plate, RigidTransform(pose[:3]))
        from pydrake.multibody.math import SpatialVelocity

        plant.SetFreeBodySpatialVelocity(
            plant_context, self.plate, SpatialVelocity(np.zeros(3), np.array([0.0, 0.0, v]))
        )
        for i in range(6):
            self.leg_joints[i].set_translation(plant_context, q_legs[i])
            self.leg_joints[i].set_translation_rate(plant_context, qdot_legs[i])
            self.universal_joints[i].set_angles(plant_context, u_angles[i])
            self.universal_joints[i].set_angular_rates(plant_context, udot[i])

    def set_drawn_pose(
        self, plant_context, position_m: np.ndarray, rotation: RotationMatrix
    ) -> None:
        """Put the platform at rest with the plate at ``position_m`` (world, m)
        and ``rotation``: leg lengths and joint angles from the inverse
        kinematics of that pose, without the workspace check (for drawing a
        magnified pose, see :mod:`hybridtable.stewart.view`)."""
        pose = np.concatenate([position_m, rpy_from_rotation(rotation.matrix())])
        lengths, angles = self._leg_coordinates_at(pose)
        self.plant.SetFreeBodyPose(
            plant_context, self.plate, RigidTransform(rotation, np.asarray(position_m))
        )
        for i in range(6):
            self.leg_joints[i].set_translation(plant_context, lengths[i])
            self.universal_joints[i].set_angles(plant_context, angles[i])

    def _leg_coordinates(self, offset_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Leg lengths (6,) and universal-joint angles (6, 2) at an axis offset."""
        return self._leg_coordinates_at(self.geometry.axis_pose(offset_m))

    def _leg_coordinates_at(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Leg lengths (6,) and universal-joint angles (6, 2) at a 6-D pose."""
        legs = self.geometry.leg_vectors(pose)
        lengths = np.linalg.norm(legs, axis=1)
        angles = np.zeros((6, 2))
        for i in range(6):
            # Leg direction in the universal joint's fixed frame F; the child's
            # z axis is Rx(q0) Ry(q1) z = [sin q1, -sin q0 cos q1, cos q0 cos q1].
            d = self.base_joint_rotations[i].T @ (legs[i] / lengths[i])
            angles[i] = [math.atan2(-d[1], d[2]), math.asin(max(-1.0, min(1.0, d[0])))]
        return lengths, angles


def add_stewart_plant(
    builder: DiagramBuilder,
    params: StewartParams,
    contact_stiffness_n_per_m: float,
    contact_dissipation_s_per_m: float = 0.0,
    register_devices: Callable[[MultibodyPlant, RigidBody, RigidBody], object] | None = None,
) -> StewartPlant:
    """Add the platform's MultibodyPlant and SceneGraph to ``builder``.

    Parameters
    ----------
    builder : DiagramBuilder
    params : StewartParams
    contact_stiffness_n_per_m : float
        Stiffness k of the contact between the devices; each geometry gets
        2 k (point-contact stiffnesses combine in series).
    contact_dissipation_s_per_m : float
        Hunt–Crossley dissipation d of both geometries (combined: d); see
        :func:`~hybridtable.stewart.hunt_crossley.hunt_crossley_dissipation`.
    register_devices : callable, optional
        ``register_devices(plant, device_body, world_body)`` registers other
        contact devices (collision and visual geometry) on the device welded
        to the plate and on the world, in place of the spherical tip and the
        block (e.g. the 6-DoF docking devices); the contact stiffness and
        dissipation arguments then play no part. The passive device's face
        belongs at ``contact_face_height_m`` (``home_height_m +
        device_length_m``) for the devices to touch at the home pose.
    """
    k = check_positive("contact_stiffness_n_per_m", contact_stiffness_n_per_m)
    d = check_nonnegative("contact_dissipation_s_per_m", contact_dissipation_s_per_m)
    g = params.geometry
    config = MultibodyPlantConfig(
        time_step=params.time_step_s,
        discrete_contact_approximation="lagged",
        contact_model="point",
        use_sampled_output_ports=False,
    )
    plant, scene_graph = AddMultibodyPlant(config, builder)
    plant.set_name("stewart_plant")
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, -params.gravity_m_per_s2])
    legs = plant.AddModelInstance("legs")
    platform = plant.AddModelInstance("platform")
    world = plant.world_body()

    # Top plate and the contact device on its F/T sensor.
    Ip = g.plate_inertia_kg_m2
    plate = plant.AddRigidBody(
        "plate",
        platform,
        SpatialInertia.MakeFromCentralInertia(g.plate_mass_kg, np.zeros(3), RotationalInertia(*Ip)),
    )
    device = plant.AddRigidBody(
        "device", platform, _rod_inertia(g.device_mass_kg, g.device_length_m, g.device_length_m / 2)
    )
    weld = plant.AddJoint(
        WeldJoint("ft_sensor", plate.body_frame(), device.body_frame(), RigidTransform())
    )
    plant.SetDefaultFloatingBaseBodyPose(plate, RigidTransform(g.home_pose[:3]))

    grey = np.array([0.6, 0.6, 0.62, 1.0])
    steel = np.array([0.75, 0.75, 0.8, 1.0])
    blue = np.array([0.2, 0.4, 0.8, 1.0])
    plate_radius = 1.15 * g.top_radius_m
    plant.RegisterVisualGeometry(
        plate, RigidTransform([0, 0, -0.02]), Cylinder(plate_radius, 0.04), "plate", grey
    )
    plant.RegisterVisualGeometry(
        device,
        RigidTransform(g.device_tip_center_m / 2),
        Cylinder(0.4 * g.device_tip_radius_m, g.device_tip_center_m[2]),
        "rod",
        steel,
    )
    plant.RegisterVisualGeometry(
        plant.world_body(),
        RigidTransform([0, 0, -0.02]),
        Cylinder(1.15 * g.base_radius_m, 0.04),
        "base",
        grey,
    )

    def contact_props() -> ProximityProperties:
        props = ProximityProperties()
        AddContactMaterial(
            dissipation=d,
            point_stiffness=2.0 * k,
            friction=CoulombFriction(params.friction_coefficient, params.friction_coefficient),
            properties=props,
        )
        return props

    face_z = g.home_height_m + g.device_length_m
    if register_devices is not None:
        register_devices(plant, device, world)
    else:
        tip = Sphere(g.device_tip_radius_m)
        X_tip = RigidTransform(g.device_tip_center_m)
        plant.RegisterCollisionGeometry(device, X_tip, tip, "tip", contact_props())
        plant.RegisterVisualGeometry(device, X_tip, tip, "tip", blue)
        # A block large enough that its contact face stays the nearest face of
        # the tip's centre over the whole workspace (point contact takes the
        # nearest face): penetration = tip top - face for any reachable pose.
        depth = 2.0 * (g.leg_max_length_m + g.device_length_m)
        frame = Box(depth, depth, depth)
        X_frame = RigidTransform([0.0, 0.0, face_z + depth / 2])
        plant.RegisterCollisionGeometry(world, X_frame, frame, "passive_device", contact_props())
        plant.RegisterVisualGeometry(
            world,
            RigidTransform([0.0, 0.0, face_z + 0.05]),
            Box(0.4, 0.4, 0.1),
            "passive_device",
            np.array([0.8, 0.5, 0.2, 0.8]),
        )

    # Legs: universal joint at the base, actuated prismatic joint, ball
    # constraint to the plate.
    base, top = g.base_points_m, g.top_points_m
    directions = g.home_leg_directions
    lengths0 = g.inverse_kinematics(g.home_pose)
    ujoints, pjoints, base_frames = [], [], []
    for i in range(6):
        R_F = _frame_along(directions[i])
        base_frames.append(R_F.matrix())
        cylinder = plant.AddRigidBody(
            f"cylinder_{i}",
            legs,
            _rod_inertia(g.cylinder_mass_kg, g.cylinder_length_m, g.cylinder_length_m / 2),
        )
        piston = plant.AddRigidBody(
            f"piston_{i}",
            legs,
            _rod_inertia(g.piston_mass_kg, g.piston_length_m, -g.piston_length_m / 2),
        )
        F = plant.AddFrame(
            FixedOffsetFrame(f"base_joint_{i}", plant.world_frame(), RigidTransform(R_F, base[i]))
        )
        uj = plant.AddJoint(UniversalJoint(f"universal_{i}", F, cylinder.body_frame()))
        pj = plant.AddJoint(
            PrismaticJoint(
                f"leg_{i}",
                cylinder.body_frame(),
                piston.body_frame(),
                [0.0, 0.0, 1.0],
                g.leg_min_length_m,
                g.leg_max_length_m,
            )
        )
        pj.set_default_translation(lengths0[i])
        plant.AddJointActuator(f"leg_{i}", pj)
        plant.AddBallConstraint(piston, np.zeros(3), plate, top[i])
        plant.RegisterVisualGeometry(
            cylinder,
            RigidTransform([0, 0, g.cylinder_length_m / 2]),
            Cylinder(0.03, g.cylinder_length_m),
            f"cylinder_{i}",
            grey,
        )
        plant.RegisterVisualGeometry(
            piston,
            RigidTransform([0, 0, -g.piston_length_m / 2]),
            Cylinder(0.018, g.piston_length_m),
            f"piston_{i}",
            steel,
        )
        ujoints.append(uj)
        pjoints.append(pj)
    plant.Finalize()

    handles = StewartPlant(
        params=params,
        plant=plant,
        scene_graph=scene_graph,
        plate=plate,
        device=device,
        sensor_weld=weld,
        universal_joints=ujoints,
        leg_joints=pjoints,
        contact_face_height_m=face_z,
        leg_position_indices=np.array([j.position_start() for j in pjoints]),
        leg_velocity_indices=np.array([j.velocity_start() for j in pjoints]),
        plate_position_start=plate.floating_positions_start(),
        plate_velocity_start=plate.floating_velocities_start_in_v(),
        base_joint_rotations=base_frames,
    )
    handles.gravity_feedforward_n = _static_leg_forces(handles)
    return handles


def _static_leg_forces(handles: StewartPlant) -> np.ndarray:
    """Leg forces holding the platform still at home against gravity.

    Solves the statics ``0 = tau_g + B u + J^T lambda`` of the tree (24
    velocities) with the 18 ball-constraint rows J for the 6 actuator forces
    u and the constraint forces lambda.
    """
    plant = handles.plant
    context = plant.CreateDefaultContext()
    tau_g = plant.CalcGravityGeneralizedForces(context)
    if not np.any(tau_g):
        return np.zeros(6)
    B = plant.MakeActuationMatrix()
    rows = []
    top = handles.geometry.top_points_m
    world = plant.world_frame()
    for i, joint in enumerate(handles.leg_joints):
        piston_frame = joint.child_body().body_frame()
        J_piston = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, piston_frame, np.zeros(3), world, world
        )
        J_plate = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, handles.plate.body_frame(), top[i], world, world
        )
        rows.append(J_piston - J_plate)
    J = np.vstack(rows)
    A = np.hstack([B, J.T])
    solution, *_ = np.linalg.lstsq(A, -tau_g, rcond=None)
    residual = np.linalg.norm(A @ solution + tau_g)
    if residual > 1e-6 * max(1.0, np.linalg.norm(tau_g)):
        raise ParameterError(f"the home pose is not statically determinate (residual {residual:g})")
    # Actuator order: B's columns follow actuator indices, which follow the legs.
    return solution[: B.shape[1]]
