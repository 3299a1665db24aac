"""The docking devices and their compliant contact, computed by Drake.

Two pairs of devices (:class:`DockingContactParams`, ``geometry``):

- ``"plate"``: a ring of spherical pads against a flat plate whose face is the
  plane ``z = 0`` of the target frame W, in Drake's compliant point contact
  (:mod:`~hybridtable.six_dof.pads`), or with the 1-D contact law per pad
  where the scenario states terms Drake's has not;
- ``"cone"``: a probe head entering a conical drogue, in Drake's hydroelastic
  contact (:mod:`~hybridtable.six_dof.drogue`), so that an offset or a tilt
  acts through the drogue's walls.

:func:`register_docking_devices` adds either pair to any MultibodyPlant (the
Stewart plant uses it too); :class:`DockingContact` holds a small plant of the
two devices alone (the device a free body, the target welded to the world)
and evaluates the contact wrench at a pose and twist: the drogue's through
the plant's contact results, the pads' by their point pairs in closed form
(Drake's query to round-off, tested against it: the plant's contact results
are the tests' oracle, and what the Stewart platform's plant computes;
Hunt–Crossley dissipation
and regularized Coulomb friction in both), and its 6x6 stiffness and damping
in closed form;
:class:`DockingContactSystem` is that as a Drake system of the loop.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.geometry import HydroelasticContactRepresentation
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import RigidBody, SpatialInertia
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem

from hybridtable.errors import ParameterError
from hybridtable.six_dof import drogue
from hybridtable.six_dof.devices import DockingContactParams
from hybridtable.six_dof.pads import (
    STICTION_TOLERANCE_M_PER_S,
    pad_law_contacts,
    pad_law_stiffness,
    pad_stiffness,
    pad_wrench,
    register_pads,
    wrench_of,
)
from hybridtable.six_dof.pose import rotation_exp, rotation_jacobian
from hybridtable.stewart.geometry import cross

__all__ = [
    "register_docking_devices",
    "DockingContact",
    "DockingContactSystem",
    "STICTION_TOLERANCE_M_PER_S",
    "peak_press_m",
    "port_start_z_m",
]


def register_docking_devices(
    plant,
    device_body: RigidBody,
    X_device_port: RigidTransform,
    target_body: RigidBody,
    X_target_face: RigidTransform,
    params: DockingContactParams,
) -> list:
    """Register the active device on ``device_body`` and the passive one on
    ``target_body`` (:func:`~hybridtable.six_dof.pads.register_pads` or
    :func:`~hybridtable.six_dof.drogue.register_drogue_devices`).

    Parameters
    ----------
    plant : MultibodyPlant
        Not yet finalized, registered with a SceneGraph.
    device_body : RigidBody
    X_device_port : RigidTransform
        The port frame P in the device body's frame.
    target_body : RigidBody
    X_target_face : RigidTransform
        The target frame W (the plate's face or the drogue's mouth at its
        z = 0, the target at z > 0) in the target body's frame.
    params : DockingContactParams

    Returns
    -------
    list of GeometryId
        The active device's collision geometries.
    """
    register = drogue.register_drogue_devices if params.is_cone else register_pads
    return register(plant, device_body, X_device_port, target_body, X_target_face, params)


def peak_press_m(params: DockingContactParams, mass_kg: float, speed_m_per_s: float) -> float:
    """How far a body of ``mass_kg`` arriving head-on at ``speed_m_per_s``
    presses the contact before it stops, without dissipation (m): pads
    ``v sqrt(m / k)``; the probe on a flat floor, where its work
    :func:`~hybridtable.six_dof.drogue.probe_energy_j` equals ``m v^2 / 2``
    (bisection), at most its radius."""
    if not params.is_cone:
        omega = (
            2.0
            * math.pi
            * (math.sqrt(params.contact_stiffness_n_per_m / mass_kg) / (2.0 * math.pi))
        )
        return speed_m_per_s / omega
    energy = 0.5 * mass_kg * speed_m_per_s**2
    lo, hi = 0.0, params.probe_radius_m
    if float(drogue.probe_energy_j(params, hi)) <= energy:
        return hi
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if float(drogue.probe_energy_j(params, mid)) < energy:
            lo = mid
        else:
            hi = mid
    return hi


def port_start_z_m(
    params: DockingContactParams, R0: np.ndarray, across_m: np.ndarray, gap_m: float
) -> float:
    """The port origin's z at t = 0 (m, W) with the port turned by ``R0``
    and ``across_m`` (x, y) off the axis: the active device ``gap_m`` before
    it would first touch the target, moving along +z (the pads: the plate;
    the probe: whichever of the drogue's rim, cone, socket or floor it
    meets, :func:`~hybridtable.six_dof.drogue.first_touch_gap_m`).

    Raises
    ------
    ParameterError
        If the probe, flying along the axis, would never touch the drogue.
    """
    if not params.is_cone:
        lowest = float(np.max((params.pad_centres_m @ R0.T)[:, 2])) + params.pad_radius_m
        return -gap_m - lowest
    z_ref = -2.0 * params.probe_radius_m  # the head wholly before the mouth's plane
    port = np.array([across_m[0], across_m[1], z_ref])
    travel = drogue.first_touch_gap_m(params, port + R0 @ params.probe_centre_m)
    if not math.isfinite(travel):
        miss = math.hypot(across_m[0], across_m[1])
        raise ParameterError(
            f"lateral_miss_m puts the probe {miss:g} m off the axis: it passes outside the "
            f"drogue's rim (radius {2.0 * params.mouth_radius_m:g} m) and never touches it"
        )
    return z_ref + travel - gap_m


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
        self._geometries = register_docking_devices(
            plant,
            self._device,
            RigidTransform(),
            plant.world_body(),
            RigidTransform(),
            params,
        )
        plant.set_stiction_tolerance(STICTION_TOLERANCE_M_PER_S)
        # A tetrahedron's slice of the drogue's surface is one polygon, not a
        # fan of triangles: a third of the faces to integrate and to linearize.
        plant.set_contact_surface_representation(HydroelasticContactRepresentation.kPolygon)
        plant.Finalize()
        self._plant = plant
        self._diagram = builder.Build()
        self._context = self._diagram.CreateDefaultContext()
        self._plant_context = plant.GetMyMutableContextFromRoot(self._context)
        self._results = plant.get_contact_results_output_port()
        if not params.is_cone:
            self._pad_centres = np.ascontiguousarray(params.pad_centres_m)
            self._pad_stiffness = pad_stiffness()
            self._pad_wrench = pad_wrench()
            self._wrench_of = wrench_of()
            #: The pads' own law where it is not Drake's (None: Drake's, in closed form).
            self._pad_law = None if params.drake_law else params.pad_law

    def _evaluate(self, q: np.ndarray, qd: np.ndarray | None):
        """The port origin and Drake's contact results with the device at
        ``q`` moving at ``qd`` (None: at rest)."""
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
        return p, self._results.Eval(ctx)

    def _pads(self, q: np.ndarray, qd: np.ndarray):
        """The pads' wrench at ``q`` moving at ``qd`` and the touching pads'
        ``(U, F)`` (contact point from the port origin, force on the device):
        Drake's point pairs in closed form, one compiled call
        (:func:`~hybridtable.six_dof.pads.pad_wrench`: Drake's query to
        round-off, tested, at a fraction of its cost), or where the pads' law
        is not Drake's (:attr:`DockingContactParams.drake_law`), the same
        point pairs with the 1-D contact law per pad
        (:func:`~hybridtable.six_dof.pads.pad_law_contacts`)."""
        c = self.params
        if self._pad_law is None:
            k_pad = c.contact_stiffness_n_per_m / c.pad_count
            return self._pad_wrench(
                q,
                qd,
                self._pad_centres,
                c.pad_radius_m,
                k_pad,
                c.contact_dissipation_s_per_m,
                c.friction_coefficient,
            )
        U, F, _, _ = pad_law_contacts(
            q, qd, self._pad_centres, c.pad_radius_m, self._pad_law, c.friction_coefficient
        )
        return self._wrench_of(U, F), U, F

    def _surfaces(self, q: np.ndarray, qd: np.ndarray | None):
        """The probe's hydroelastic contacts at ``q`` moving at ``qd``:
        ``(port origin p, [(the surface's centroid, force on the device, its
        moment about the centroid, HydroelasticContactInfo), ...])``. A probe
        further from the drogue's smooth surface than its facets sag is apart
        from the faceted one too, and Drake's query (up to 1 ms inside the
        drogue) is skipped."""
        c = self.params
        centre = np.asarray(q[:3], dtype=float) + rotation_exp(q[3:]) @ c.probe_centre_m
        if drogue.wall_depth_m(c, centre) < -drogue.facet_sag_m(c):
            return np.asarray(q[:3], dtype=float), []  # apart: no query
        p, results = self._evaluate(q, qd)
        out = []
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            F = info.F_Ac_W()  # on the body of the surface's geometry M, at its centroid
            sign = 1.0 if info.contact_surface().id_M() == self._geometries[0] else -1.0
            out.append(
                (
                    info.contact_surface().centroid(),
                    sign * F.translational(),
                    sign * F.rotational(),
                    info,
                )
            )
        return p, out

    def wrench(
        self, q: np.ndarray, qd: np.ndarray | None = None, points: list | None = None
    ) -> np.ndarray:
        """The contact wrench on the device ``[moment; force]`` (6: N m, N) at
        the port origin, in W, with the device at ``q = [p; theta]`` moving at
        ``qd = [v; omega]`` (default at rest). ``points``, when given, gets
        ``(contact point, force on the device)`` of every touching pad or
        contact surface (its centroid) (W, m, N)."""
        if not self.params.is_cone:
            q = np.asarray(q, dtype=float)
            w, U, F = self._pads(q, np.zeros(6) if qd is None else np.asarray(qd, dtype=float))
            if points is not None:
                points += [(q[:3] + U[i], np.array(F[i])) for i in range(U.shape[0])]
            return w
        force = np.zeros(3)
        moment = np.zeros(3)
        p, surfaces = self._surfaces(q, qd)
        touches = [(c, f) for c, f, _, _ in surfaces]
        for _, _, m, _ in surfaces:
            moment += m
        for c, f in touches:
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
        :meth:`wrench`), in closed form: for the probe from one evaluation of
        Drake's contact, for the pads from their geometry alone (one compiled
        call, :func:`~hybridtable.six_dof.pads.pad_stiffness`: a sphere over
        the plate's flat face is Drake's point pair in closed form, the same
        numbers to round-off, tested; without Drake's query, at 1/15 of its cost).

        **Pads** (:func:`~hybridtable.six_dof.pads.pad_stiffness`). Each
        touching pad is a sphere of radius ``r`` pressed ``x`` into the
        plate's face (normal ``n`` out of the plate), with Drake's point-contact
        law: normal force ``k x (1 + d xdot)``, ``k`` the pad pair's stiffness,
        ``d`` the dissipation, ``xdot = -n . v_C`` the penetration rate of the
        device's point at the contact point ``C`` (half-way between the two
        surfaces: ``C = c - (r - x/2) n`` with ``c`` the pad's centre), and the
        regularized Coulomb friction ``-mu(s) f_n t`` against the slip ``s t``
        (Drake's Stribeck curve). Moving the pose by ``dq = [dp;
        dtheta]`` moves the centre by ``dp - [c - p]x J dtheta`` (``J`` the
        rotation vector's Jacobian, :func:`~hybridtable.six_dof.pose.rotation_jacobian`),
        the depth by ``-n`` times that, and the lever arm ``C - p`` with
        both: its change times the force is the geometric term of the moment.
        The target's face is flat (its normal does not turn with the contact
        point); a pad's derivative is taken where it touches (a pad that
        starts or stops touching at ``q`` is a kink of ``w``).

        **Probe** (:func:`~hybridtable.six_dof.drogue.hydroelastic_jacobians`).
        The contact surface lies on the rigid drogue; each face of it (area
        ``A``, centroid ``x``, normal ``n`` toward the probe) carries the
        probe's pressure ``P (1 - d n . v_x)``, ``v_x`` the device's velocity
        at ``x``. Moving the probe changes the pressure at the face's fixed
        point by ``-g . (its displacement)``, ``g`` the pressure field's
        gradient there (the surface's edge, where the pressure is 0, moves
        without changing the integral); the lever arm ``x - p`` shortens as
        the port moves. Without friction (the compensator's contact model
        has none): friction with a slip raises ParameterError.
        """
        q = np.asarray(q, dtype=float)
        moving = qd is not None and bool(np.any(np.asarray(qd) != 0.0))
        qd = np.zeros(6) if qd is None else np.asarray(qd, dtype=float)
        w_q = np.zeros((6, 6))  # dw/dq
        w_qd = np.zeros((6, 6))  # dw/dqd
        c = self.params
        if c.is_cone:
            J = rotation_jacobian(q[3:])
            if moving and c.friction_coefficient > 0.0:
                raise ParameterError(
                    "the probe's closed-form stiffness has no friction: linearize a moving "
                    "probe with friction_coefficient = 0 (as the compensator's model is)"
                )
            p, surfaces = self._surfaces(q, qd)
            for _, _, _, info in surfaces:
                A, X, N, P, G = drogue.face_data(info, self._geometries[0])
                drogue.hydroelastic_jacobians()(
                    A, X, N, P, G, p, J, qd, c.contact_dissipation_s_per_m, w_q, w_qd
                )
            return -w_q, -w_qd
        if self._pad_law is not None:
            return pad_law_stiffness(
                q, qd, self._pad_centres, c.pad_radius_m, self._pad_law, c.friction_coefficient
            )
        return self._pad_stiffness(
            q,
            qd,
            self._pad_centres,
            c.pad_radius_m,
            c.contact_stiffness_n_per_m / c.pad_count,
            c.contact_dissipation_s_per_m,
            c.friction_coefficient,
        )


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
