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
  Hunt–Crossley dissipation from the run's contact parameters; the plant uses
  the ``"lagged"`` discrete contact approximation (``"sap"`` ignores
  Hunt–Crossley dissipation and adds its own).

The legs are driven by a digital PD servo (see :mod:`hybridtable.stewart.backend`)
through the plant's actuation input, not by the plant's implicit PD
controllers (with the ball constraints, SAP failed to converge with them in
drake 1.51); the servo then is a sampled PD loop, whose response
:mod:`hybridtable.stewart.identify` measures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

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
from hybridtable.stewart.geometry import StewartGeometry

__all__ = [
    "StewartParams",
    "heave_mass_kg",
    "heave_servo_gains",
    "StewartPlant",
    "add_stewart_plant",
    "hunt_crossley_cor",
    "hunt_crossley_dissipation",
    "reference_matrices",
]


@dataclass(frozen=True)
class StewartParams:
    """Parameters of the Stewart-platform table back-end, SI units.

    The legs are driven by a digital PD servo at the plant's time step. Two
    ways to give the table its response (see ``docs/stewart.md``):

    - with a reference model (default): the command passes through a
      discrete second-order model (``reference_response_hz``,
      ``reference_damping_ratio``) whose position and velocity stiff legs
      track; the table stays stiff under the contact force;
    - without (``reference_response_hz=None``): the leg gains alone shape the
      response (tune them with :func:`hybridtable.stewart.identify.tune_leg_gains`);
      the table is then as compliant as its response is slow.

    Parameters
    ----------
    geometry : StewartGeometry
    leg_stiffness_n_per_m, leg_damping_n_s_per_m : float or None
        PD gains Kp (> 0) and Kd (>= 0) of each leg's servo; ``None``: from
        ``servo_bandwidth_hz`` and ``servo_damping_ratio`` for the plate's
        heave mass (:func:`heave_servo_gains`).
    servo_bandwidth_hz : float or None
        Heave natural frequency of the servo loop that sets default gains;
        ``None``: ``0.08 / time_step_s`` (80 Hz at 1 ms). The explicit servo
        is stable up to about ``servo_bandwidth_hz * time_step_s = 0.1``.
    servo_damping_ratio : float
        Damping ratio of that servo loop.
    time_step_s : float
        Time step of the discrete plant and the servo's sample period, > 0.
    gravity_m_per_s2 : float
        Gravity along -z (the docking axis is +z), >= 0. The servo adds the
        static leg forces that hold the platform at home, and the sensor
        reading is compensated for the device's weight and inertia.
    friction_coefficient : float
        Coulomb friction of the contact pair, >= 0.
    sensor_resolution_n : float
        Resolution of the F/T sensor's force reading, > 0: the reading is
        rounded to a multiple of it, so the round-off of the reaction wrench
        (~1e-14 N) reads as an exact zero when the devices are apart.
    reference_response_hz : float or None
        Natural frequency of the reference model, > 0 and below the Nyquist
        rate, or ``None`` for none.
    reference_damping_ratio : float
        Damping ratio of the reference model, >= 0.
    """

    geometry: StewartGeometry = field(default_factory=StewartGeometry)
    leg_stiffness_n_per_m: float | None = None
    leg_damping_n_s_per_m: float | None = None
    servo_bandwidth_hz: float | None = None
    servo_damping_ratio: float = 0.7
    time_step_s: float = 1e-3
    gravity_m_per_s2: float = 9.81
    friction_coefficient: float = 0.3
    sensor_resolution_n: float = 1e-6
    reference_response_hz: float | None = 25.0
    reference_damping_ratio: float = 0.8

    def __post_init__(self) -> None:
        s = object.__setattr__
        if not isinstance(self.geometry, StewartGeometry):
            raise ParameterError(f"geometry must be a StewartGeometry (got {self.geometry!r})")
        for name in ("time_step_s", "sensor_resolution_n"):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in (
            "servo_damping_ratio",
            "gravity_m_per_s2",
            "friction_coefficient",
            "reference_damping_ratio",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.leg_stiffness_n_per_m is not None:
            s(
                self,
                "leg_stiffness_n_per_m",
                check_positive("leg_stiffness_n_per_m", self.leg_stiffness_n_per_m),
            )
        if self.leg_damping_n_s_per_m is not None:
            s(
                self,
                "leg_damping_n_s_per_m",
                check_nonnegative("leg_damping_n_s_per_m", self.leg_damping_n_s_per_m),
            )
        if self.servo_bandwidth_hz is not None:
            f_s = check_positive("servo_bandwidth_hz", self.servo_bandwidth_hz)
            s(self, "servo_bandwidth_hz", f_s)
            if self.leg_stiffness_n_per_m is None and f_s * self.time_step_s > 0.1:
                raise ParameterError(
                    f"servo_bandwidth_hz {f_s:g} is too fast for time_step_s "
                    f"{self.time_step_s:g} (need servo_bandwidth_hz * time_step_s <= 0.1)"
                )
        if self.reference_response_hz is not None:
            f = check_positive("reference_response_hz", self.reference_response_hz)
            if f * self.time_step_s >= 0.5:
                raise ParameterError(
                    "reference_response_hz must be below the Nyquist rate "
                    f"{0.5 / self.time_step_s:g} Hz (got {f!r})"
                )
            s(self, "reference_response_hz", f)

    @property
    def effective_servo_bandwidth_hz(self) -> float:
        """``servo_bandwidth_hz``, or its default ``0.08 / time_step_s``."""
        if self.servo_bandwidth_hz is None:
            return 0.08 / self.time_step_s
        return self.servo_bandwidth_hz

    def servo_gains(self) -> tuple[float, float]:
        """The legs' (Kp, Kd): the given ones, or from the servo bandwidth."""
        kp, kd = heave_servo_gains(
            self.geometry, self.effective_servo_bandwidth_hz, self.servo_damping_ratio
        )
        if self.leg_stiffness_n_per_m is not None:
            kp = self.leg_stiffness_n_per_m
        if self.leg_damping_n_s_per_m is not None:
            kd = self.leg_damping_n_s_per_m
        return kp, kd

    def with_gains(self, stiffness_n_per_m: float, damping_n_s_per_m: float) -> StewartParams:
        """A copy with other leg servo gains."""
        return replace(
            self, leg_stiffness_n_per_m=stiffness_n_per_m, leg_damping_n_s_per_m=damping_n_s_per_m
        )

    def with_reference(self, response_hz: float | None, damping_ratio: float) -> StewartParams:
        """A copy with another reference model (``None``: none)."""
        return replace(
            self, reference_response_hz=response_hz, reference_damping_ratio=damping_ratio
        )


def heave_mass_kg(geometry: StewartGeometry) -> float:
    """Rough mass moving with the plate in heave: plate, device, pistons and a
    third of each cylinder."""
    g = geometry
    return g.plate_mass_kg + g.device_mass_kg + 6.0 * (g.piston_mass_kg + g.cylinder_mass_kg / 3)


def heave_servo_gains(
    geometry: StewartGeometry, bandwidth_hz: float, damping_ratio: float
) -> tuple[float, float]:
    """Leg gains (Kp, Kd) giving the plate's heave (rigid-body estimate) the
    natural frequency ``bandwidth_hz`` and damping ratio ``damping_ratio``:
    the heave stiffness is ``Kp sum(u_z^2)`` with ``u`` the leg directions."""
    w = 2.0 * math.pi * check_positive("bandwidth_hz", bandwidth_hz)
    z = check_nonnegative("damping_ratio", damping_ratio)
    uz = geometry.home_leg_directions[:, 2]
    scale = heave_mass_kg(geometry) / float(np.sum(uz * uz))
    return scale * w * w, 2.0 * z * w * scale


def reference_matrices(
    params: StewartParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Discrete (A, B, C, D) of the servo's reference model, exact for a
    command held over each time step: state and output ``[p_r, v_r]``, input
    ``[p_des, v_des]`` (``v_des`` unused)."""
    from scipy.linalg import expm

    if params.reference_response_hz is None:
        raise ParameterError("these StewartParams have no reference model")
    w = 2.0 * math.pi * params.reference_response_hz
    z = params.reference_damping_ratio
    M = np.zeros((3, 3))
    M[:2, :2] = [[0.0, 1.0], [-w * w, -2.0 * z * w]]
    M[1, 2] = w * w
    E = expm(M * params.time_step_s)
    B = np.zeros((2, 2))
    B[:, 0] = E[:2, 2]
    return E[:2, :2], B, np.eye(2), np.zeros((2, 2))


# -- Hunt–Crossley dissipation from a viscous damping --------------------------
@lru_cache(maxsize=256)
def hunt_crossley_cor(dissipation_times_velocity: float) -> float:
    """CoR of a mass hitting a linear Hunt–Crossley contact
    ``f = k x (1 + d dx/dt)`` at speed v; it depends on ``d v`` only."""
    from scipy.integrate import solve_ivp

    beta = check_nonnegative("dissipation_times_velocity", dissipation_times_velocity)
    if beta == 0.0:
        return 1.0

    # Dimensionless: x = (v / w) xi, t = tau / w; xi'' = -xi (1 + beta xi').
    def rhs(_, y):
        return [y[1], -y[0] * (1.0 + beta * y[1]) if y[0] > 0.0 else 0.0]

    def out(_, y):
        return y[0]

    out.terminal = True
    out.direction = -1.0
    sol = solve_ivp(
        rhs, (0.0, 50.0), [0.0, 1.0], events=out, rtol=1e-10, atol=1e-12, first_step=1e-6
    )
    if not sol.t_events[0].size:
        return 0.0
    return float(-sol.y_events[0][0][1])


def hunt_crossley_dissipation(
    stiffness_n_per_m: float,
    damping_n_s_per_m: float,
    mass_kg: float,
    velocity_m_per_s: float,
) -> float:
    """Hunt–Crossley dissipation d (s/m) whose impact of ``mass_kg`` at
    ``velocity_m_per_s`` has the CoR of the viscous contact ``k x + c v``.

    Point contact in Drake has no viscous damping; this maps the loop's
    ``contact_damping_n_s_per_m`` to the dissipation with the same energy
    loss in the run's first impact. Zero damping gives zero dissipation.
    """
    k = check_positive("stiffness_n_per_m", stiffness_n_per_m)
    c = check_nonnegative("damping_n_s_per_m", damping_n_s_per_m)
    m = check_positive("mass_kg", mass_kg)
    v = check_positive("velocity_m_per_s", velocity_m_per_s)
    if c == 0.0:
        return 0.0
    zeta = c / (2.0 * math.sqrt(k * m))
    if zeta >= 1.0:
        raise ParameterError(
            f"contact damping ratio {zeta:.3f} >= 1 has no Hunt–Crossley equivalent "
            "(the viscous contact does not rebound)"
        )
    target = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta))
    from scipy.optimize import brentq

    # hunt_crossley_cor decreases from 1 (beta = 0) towards 0.
    hi = 1.0
    while hunt_crossley_cor(hi) > target:
        hi *= 2.0
        if hi > 1e6:
            raise ParameterError(f"no Hunt–Crossley dissipation reaches CoR {target:.4f}")
    beta = brentq(lambda b: hunt_crossley_cor(b) - target, 0.0, hi, xtol=1e-12)
    return beta / v


# -- the plant -----------------------------------------------------------------
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

    def _leg_coordinates(self, offset_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Leg lengths (6,) and universal-joint angles (6, 2) at an axis offset."""
        g = self.geometry
        legs = g.leg_vectors(g.axis_pose(offset_m))
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
        :func:`hunt_crossley_dissipation`.
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

    tip = Sphere(g.device_tip_radius_m)
    X_tip = RigidTransform(g.device_tip_center_m)
    plant.RegisterCollisionGeometry(device, X_tip, tip, "tip", contact_props())
    plant.RegisterVisualGeometry(device, X_tip, tip, "tip", blue)
    face_z = g.home_height_m + g.device_length_m
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
