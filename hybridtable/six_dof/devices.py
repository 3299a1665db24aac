"""The docking devices' parameters: which pair (a pad ring on a flat plate, or
a probe in a drogue), their sizes, and the law of their compliant contact
(:class:`DockingContactParams`). :mod:`~hybridtable.six_dof.contact` builds
and evaluates the contact they describe.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridtable._validation import check_choice, check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.limits import check_plausible
from hybridtable.systems.contact_law import ContactLawParams

__all__ = [
    "GEOMETRIES",
    "DEVICE_FIELDS",
    "PAD_LAW_FIELDS",
    "CONE_HALF_ANGLE_RANGE_RAD",
    "DockingContactParams",
]

#: The docking devices: a pad ring on a flat plate, or a probe in a drogue.
GEOMETRIES: tuple[str, ...] = ("plate", "cone")

#: The pads' normal law beyond Drake's point contact (the 1-D contact law's
#: terms, :class:`~hybridtable.systems.contact_law.ContactLawParams`, shared by
#: the pads): a power law, a viscous damper, a series compliance, a friction
#: force along the normal. At their defaults the law is Drake's.
PAD_LAW_FIELDS: tuple[str, ...] = (
    "contact_exponent",
    "reference_press_m",
    "contact_damping_n_s_per_m",
    "series_compliance_m_per_n",
    "normal_friction_force_n",
    "normal_friction_velocity_m_per_s",
)

#: The fields of each geometry's own devices (the other's are not used).
DEVICE_FIELDS: dict[str, tuple[str, ...]] = {
    "plate": ("pad_count", "ring_radius_m", "pad_radius_m", *PAD_LAW_FIELDS),
    "cone": (
        "cone_half_angle_rad",
        "mouth_radius_m",
        "throat_radius_m",
        "socket_depth_m",
        "probe_radius_m",
    ),
}

#: The cone's half angle (its wall from the axis) may lie in this range (rad):
#: 5 to 75 deg.
CONE_HALF_ANGLE_RANGE_RAD = (math.radians(5.0), math.radians(75.0))


@dataclass(frozen=True)
class DockingContactParams:
    """The docking devices and their compliant contact.

    ``geometry = "plate"`` (Drake's point contact): the active device (on the
    table) is a ring of ``pad_count`` spherical pads of radius
    ``pad_radius_m`` on a circle of ``ring_radius_m``, their tops in the
    port's face plane; the passive device is a flat plate.

    ``geometry = "cone"`` (Drake's hydroelastic contact): the active device
    is a spherical probe head of radius ``probe_radius_m``, its tip at the
    port origin; the passive device a drogue: a cone of half angle
    ``cone_half_angle_rad`` from its mouth (radius ``mouth_radius_m``, in
    the target's face plane) to its throat (``throat_radius_m``), then a
    socket ``socket_depth_m`` deep (:mod:`~hybridtable.six_dof.drogue`). The
    pad fields are not used, nor the cone's by a plate.

    Parameters
    ----------
    contact_stiffness_n_per_m : float
        Plate: total normal stiffness k with every pad touching, > 0 (each
        pad ``k / pad_count``). Cone: the probe's tangent stiffness at a
        press of a tenth of its radius (its force grows as the press squared:
        :func:`~hybridtable.six_dof.drogue.probe_modulus_pa`).
    contact_dissipation_s_per_m : float
        Hunt–Crossley dissipation d, ``f = f_elastic (1 + d dx/dt)``, >= 0.
    friction_coefficient : float
        Coulomb friction mu of the devices, >= 0 (Drake's regularized friction).
    pad_count : int
        Number of pads, >= 3.
    ring_radius_m, pad_radius_m : float
        Ring and pad radii, > 0, ``pad_radius_m < ring_radius_m``.
    geometry : {"plate", "cone"}
    cone_half_angle_rad : float
        The drogue's wall from the axis (rad), 5 to 75 deg.
    mouth_radius_m, throat_radius_m, probe_radius_m : float
        ``probe_radius_m < throat_radius_m < mouth_radius_m``, > 0.
    socket_depth_m : float
        Depth of the socket past the throat, > ``probe_radius_m`` (a head
        whose centre has passed the throat fits in it).
    contact_exponent, reference_press_m, contact_damping_n_s_per_m, series_compliance_m_per_n, normal_friction_force_n, normal_friction_velocity_m_per_s : float
        Plate only: the pads' normal law beyond Drake's (:attr:`pad_law`,
        each pad's force the 1-D contact law's,
        :class:`~hybridtable.systems.contact_law.ContactLawParams`): the
        exponent ``n`` (1) of a power-law spring whose secant stiffness at the
        press ``reference_press_m`` (m, > 0) is ``contact_stiffness_n_per_m``;
        a viscous damping ``c`` (N s/m, 0); a compliance ``s`` (m/N, 0) of the
        structure behind the pads; a friction force ``F`` (N, 0) against each
        pad's penetration rate, its sign smoothed over
        ``normal_friction_velocity_m_per_s`` (m/s, > 0). Totals over the ring:
        each pad takes ``c / pad_count``, ``F / pad_count`` and ``s pad_count``.
        At the defaults (:attr:`drake_law`) the pads are Drake's point contact.
    """

    contact_stiffness_n_per_m: float
    contact_dissipation_s_per_m: float = 0.0
    friction_coefficient: float = 0.0
    pad_count: int = 8
    ring_radius_m: float = 0.3
    pad_radius_m: float = 0.01
    geometry: str = "plate"
    cone_half_angle_rad: float = math.radians(30.0)
    mouth_radius_m: float = 0.3
    throat_radius_m: float = 0.08
    socket_depth_m: float = 0.15
    probe_radius_m: float = 0.05
    contact_exponent: float = 1.0
    reference_press_m: float = 1e-3
    contact_damping_n_s_per_m: float = 0.0
    series_compliance_m_per_n: float = 0.0
    normal_friction_force_n: float = 0.0
    normal_friction_velocity_m_per_s: float = 1e-3

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
        s(self, "geometry", check_choice("geometry", self.geometry, GEOMETRIES))
        for name in ("mouth_radius_m", "throat_radius_m", "socket_depth_m", "probe_radius_m"):
            s(self, name, check_positive(name, getattr(self, name)))
        alpha = check_positive("cone_half_angle_rad", self.cone_half_angle_rad)
        lo, hi = CONE_HALF_ANGLE_RANGE_RAD
        if not lo <= alpha <= hi:
            raise ParameterError(
                f"cone_half_angle_rad must be in [{lo:.4g}, {hi:.4g}] rad (5 to 75 deg; "
                f"got {alpha:g})"
            )
        s(self, "cone_half_angle_rad", alpha)
        r, rt, rm = self.probe_radius_m, self.throat_radius_m, self.mouth_radius_m
        if not r < rt < rm:
            raise ParameterError(
                f"probe_radius_m {r:g} < throat_radius_m {rt:g} < mouth_radius_m {rm:g} must "
                "hold: the probe head passes the throat, the cone narrows to it"
            )
        if self.socket_depth_m <= r:
            raise ParameterError(
                f"socket_depth_m {self.socket_depth_m:g} must be > probe_radius_m {r:g}: a head "
                "whose centre has passed the throat fits in the socket"
            )
        for name in ("contact_exponent", "reference_press_m", "normal_friction_velocity_m_per_s"):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in (
            "contact_damping_n_s_per_m",
            "series_compliance_m_per_n",
            "normal_friction_force_n",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        if self.is_cone and not self.drake_law:
            raise ParameterError(
                f'{self.pad_law_terms[0]} is a term of the pads\' law (geometry = "plate"); the probe in '
                "the drogue is Drake's hydroelastic contact, which has none"
            )

    @property
    def pad_law_terms(self) -> list[str]:
        """The fields of :data:`PAD_LAW_FIELDS` whose term acts: an exponent
        other than 1, a damping, a series compliance, a friction force."""
        return [
            name
            for name, on in (
                ("contact_exponent", self.contact_exponent != 1.0),
                ("contact_damping_n_s_per_m", self.contact_damping_n_s_per_m > 0.0),
                ("series_compliance_m_per_n", self.series_compliance_m_per_n > 0.0),
                ("normal_friction_force_n", self.normal_friction_force_n > 0.0),
            )
            if on
        ]

    @property
    def drake_law(self) -> bool:
        """The pads' law is Drake's point contact (no term of
        :attr:`pad_law_terms`: a linear spring with Hunt–Crossley dissipation)."""
        return not self.pad_law_terms

    @property
    def pad_law(self) -> ContactLawParams:
        """Each pad's normal law, the 1-D contact law's
        (:func:`~hybridtable.systems.contact_law.contact_law_force`) with the
        ring's totals shared by the ``pad_count`` pads: on the axis, every pad
        pressed alike, the ring's normal force is the 1-D law of the totals."""
        n = self.pad_count
        return ContactLawParams(
            stiffness_n_per_m=self.contact_stiffness_n_per_m / n,
            exponent=self.contact_exponent,
            reference_deflection_m=self.reference_press_m,
            damping_n_s_per_m=self.contact_damping_n_s_per_m / n,
            hunt_crossley_s_per_m=self.contact_dissipation_s_per_m,
            friction_force_n=self.normal_friction_force_n / n,
            friction_velocity_m_per_s=self.normal_friction_velocity_m_per_s,
            series_compliance_m_per_n=self.series_compliance_m_per_n * n,
        )

    @property
    def is_cone(self) -> bool:
        """The probe and drogue (hydroelastic), not the pads and plate."""
        return self.geometry == "cone"

    @property
    def moment_arm_m(self) -> float:
        """A lever arm of the contact's moments about the port (m): the pads'
        ring radius, or the probe's radius."""
        return self.probe_radius_m if self.is_cone else self.ring_radius_m

    @property
    def pad_centres_m(self) -> np.ndarray:
        """Pad centres in the port frame, (pad_count, 3) (m)."""
        a = 2.0 * np.pi * np.arange(self.pad_count) / self.pad_count
        r = self.ring_radius_m
        return np.column_stack(
            [r * np.cos(a), r * np.sin(a), np.full(self.pad_count, -self.pad_radius_m)]
        )

    @property
    def probe_centre_m(self) -> np.ndarray:
        """The probe head's centre in the port frame (m)."""
        return np.array([0.0, 0.0, -self.probe_radius_m])
