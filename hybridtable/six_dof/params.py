"""Parameters of the 6-DoF docking loop, SI units, validated on construction.

:class:`DockingLoopParams` is the 1-D loop's nested scenario
(:class:`~hybridtable._nested.NestedParams`) for the full pose: a plant (the
spacecraft's rigid body :class:`RigidBodyParams`, the docking devices and
their contact :class:`DockingContactParams`, the table :class:`DockingTable`),
a rig computer (:class:`DockingRig`: the 1-D sensor config, rate, wrench
compensator, F/T noise) and an approach (:class:`ApproachParams`). The frames
and equations are in ``docs/six_dof.md``.

Why one module: the component configs, the flat names their checks are worded
in and the tree that builds them by those names are one concept, as in
:mod:`hybridtable.loop.params`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, is_dataclass, replace
from typing import Any, ClassVar

import numpy as np

from hybridtable._nested import NestedParams, flat_properties
from hybridtable._validation import (
    check_choice,
    check_finite,
    check_nonnegative,
    check_positive,
    check_seed,
)
from hybridtable.errors import ParameterError
from hybridtable.limits import LIMITS, check_plausible
from hybridtable.loop.params import believed
from hybridtable.six_dof.contact import peak_press_m
from hybridtable.six_dof.devices import DEVICE_FIELDS, DockingContactParams
from hybridtable.six_dof.drogue import floor_depth_m
from hybridtable.systems.sensor import SensorParams, sample_taps
from hybridtable.systems.table import TableParams

__all__ = [
    "MAX_MISALIGNMENT_RAD",
    "TABLE_BACKENDS",
    "STIFFNESS_MODELS",
    "DEADBAND_READINGS",
    "RigidBodyParams",
    "DockingContactParams",
    "ApproachParams",
    "DockingTable",
    "DockingPlant",
    "WrenchCompensatorConfig",
    "FTNoiseParams",
    "DockingRig",
    "DockingLoopParams",
    "inertia_matrix",
]


TABLE_BACKENDS: tuple[str, ...] = ("model", "stewart")
#: How the MDC gets its 6x6 stiffness: linearized at the table's pose at every
#: tick of the contact, linearized once at the nominal docked pose, or given.
STIFFNESS_MODELS: tuple[str, ...] = ("linearized", "nominal", "given")

#: What the compensator's dead band reads: the measured force's norm, or its
#: component along the docking axis (the compression, ``-fz``: the 1-D reading).
DEADBAND_READINGS: tuple[str, ...] = ("force_norm", "axial_force")


def inertia_matrix(name: str, value) -> np.ndarray:
    """A physical inertia tensor (3x3, kg m^2) from 3 principal moments or a
    3x3 matrix: symmetric, positive definite, and its principal moments obey
    the triangle inequality (``I1 + I2 >= I3``) of any real body.

    Raises
    ------
    ParameterError
        Naming ``name`` and what is unphysical.
    """
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be 3 numbers or a 3x3 matrix (got {value!r})") from None
    if a.shape == (3,):
        a = np.diag(a)
    if a.shape != (3, 3):
        raise ParameterError(f"{name} must be 3 numbers or a 3x3 matrix (got shape {a.shape})")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be finite (got {a.tolist()})")
    scale = float(np.max(np.abs(a)))
    if scale == 0.0 or np.max(np.abs(a - a.T)) > 1e-9 * scale:
        raise ParameterError(f"{name} must be a symmetric, non-zero matrix (got {a.tolist()})")
    moments = np.linalg.eigvalsh(0.5 * (a + a.T))
    if moments[0] <= 0.0:
        raise ParameterError(
            f"{name} is unphysical: its principal moments {np.round(moments, 6).tolist()} kg m^2 "
            "must all be > 0"
        )
    i1, i2, i3 = moments
    if i1 + i2 < i3 * (1.0 - 1e-9):
        raise ParameterError(
            f"{name} is unphysical: principal moments {np.round(moments, 6).tolist()} kg m^2 "
            "violate the triangle inequality I1 + I2 >= I3 that every real body obeys"
        )
    return 0.5 * (a + a.T)


def _pair(name: str, value) -> tuple[float, float]:
    try:
        items = [float(v) for v in value]
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be 2 numbers (got {value!r})") from None
    if len(items) != 2:
        raise ParameterError(f"{name} must be 2 numbers (got {value!r})")
    return (check_finite(name, items[0]), check_finite(name, items[1]))


@dataclass(frozen=True)
class RigidBodyParams:
    """The spacecraft model as a rigid body.

    Parameters
    ----------
    mass_kg : float
        Mass m, > 0.
    inertia_kg_m2 : 3 numbers or 3x3
        Inertia tensor about the centre of mass in the body frame (3 numbers:
        the principal moments about the body axes); symmetric, positive
        definite, principal moments obeying the triangle inequality.
    port_distance_m : float
        Distance from the centre of mass to the docking port's face along the
        body z axis (the docking axis), > 0.
    lateral_offset_m : 2 numbers
        ``[x, y]`` of the port's axis from the centre of mass in the body
        frame: the contact force's line passes this far from the centre of mass.
    """

    mass_kg: float
    inertia_kg_m2: tuple = (1000.0, 1000.0, 1000.0)
    port_distance_m: float = 1.5
    lateral_offset_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(
            self,
            "mass_kg",
            check_plausible("spacecraft_mass_kg", check_positive("mass_kg", self.mass_kg)),
        )
        s(
            self,
            "inertia_kg_m2",
            tuple(map(tuple, inertia_matrix("inertia_kg_m2", self.inertia_kg_m2).tolist())),
        )
        s(self, "port_distance_m", check_positive("port_distance_m", self.port_distance_m))
        s(self, "lateral_offset_m", _pair("lateral_offset_m", self.lateral_offset_m))
        if math.hypot(*self.lateral_offset_m) > 10.0 * self.port_distance_m:
            raise ParameterError(
                f"lateral_offset_m {self.lateral_offset_m} is more than 10 port distances "
                f"({self.port_distance_m:g} m) from the centre of mass"
            )

    @property
    def inertia(self) -> np.ndarray:
        """The inertia tensor (3x3, kg m^2, body frame)."""
        return np.array(self.inertia_kg_m2)

    @property
    def port_position_m(self) -> np.ndarray:
        """The port's origin in the body frame, ``[x_off, y_off, port_distance]`` (m)."""
        return np.array([*self.lateral_offset_m, self.port_distance_m])


#: The largest roll or pitch misalignment of an approach (rad).
MAX_MISALIGNMENT_RAD = 0.5
#: The largest angular rate of an approach (rad/s): a spacecraft tumbling
#: faster than a turn in six seconds is no docking.
MAX_ANGULAR_RATE_RAD_PER_S = 1.0


@dataclass(frozen=True)
class ApproachParams:
    """How the spacecraft comes in.

    Parameters
    ----------
    initial_velocity_m_per_s : float
        Approach speed along the docking axis (+z), > 0.
    initial_gap_m : float
        Gap between the first pad to touch and the plate at t = 0, >= 0.
    misalignment_rad : 2 numbers
        ``[roll, pitch]`` of the spacecraft's attitude from the docking axis
        (rad), each within +-0.5 rad.
    angular_rate_rad_per_s : 3 numbers
        The spacecraft's angular velocity at t = 0 in its body frame (rad/s),
        of norm at most 1 rad/s; the port then moves at the centre of mass's
        approach velocity plus ``omega x arm``.
    lateral_miss_m : 2 numbers
        ``[x, y]`` of the port origin across the docking axis at t = 0 (m, in
        the target frame W), at most 10 m: how far the approach misses the
        target's centre (a drogue guides a miss within its mouth to its
        socket; on a plate it only moves where the pads land).
    """

    initial_velocity_m_per_s: float = 0.1
    initial_gap_m: float = 0.001
    misalignment_rad: tuple[float, float] = (0.0, 0.0)
    angular_rate_rad_per_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    lateral_miss_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        s = object.__setattr__
        v = check_positive("initial_velocity_m_per_s", self.initial_velocity_m_per_s)
        s(self, "initial_velocity_m_per_s", check_plausible("initial_velocity_m_per_s", v))
        gap = check_nonnegative("initial_gap_m", self.initial_gap_m)
        s(self, "initial_gap_m", check_plausible("initial_gap_m", gap))
        pair = _pair("misalignment_rad", self.misalignment_rad)
        if max(abs(pair[0]), abs(pair[1])) > MAX_MISALIGNMENT_RAD:
            raise ParameterError(
                f"misalignment_rad must be within +-{MAX_MISALIGNMENT_RAD} rad "
                f"({math.degrees(MAX_MISALIGNMENT_RAD):.3g} deg) per axis (got {pair})"
            )
        s(self, "misalignment_rad", pair)
        rate = self.angular_rate_rad_per_s
        try:
            w = tuple(check_finite("angular_rate_rad_per_s", float(x)) for x in rate)
        except (TypeError, ValueError):
            raise ParameterError(
                f"angular_rate_rad_per_s must be 3 numbers (got {rate!r})"
            ) from None
        if len(w) != 3 or math.hypot(*w) > MAX_ANGULAR_RATE_RAD_PER_S:
            raise ParameterError(
                f"angular_rate_rad_per_s must be 3 numbers of norm <= "
                f"{MAX_ANGULAR_RATE_RAD_PER_S:g} rad/s (got {rate!r})"
            )
        s(self, "angular_rate_rad_per_s", w)
        miss = _pair("lateral_miss_m", self.lateral_miss_m)
        if math.hypot(*miss) > 10.0:
            raise ParameterError(f"lateral_miss_m must be within 10 m of the axis (got {miss})")
        s(self, "lateral_miss_m", miss)


@dataclass(frozen=True)
class DockingTable:
    """The table that carries the active device.

    Parameters
    ----------
    backend : {"model", "stewart"}
        ``"model"``: the table model, each pose coordinate the 1-D loop's
        second-order table (``response``); ``"stewart"``: the Stewart
        platform's MultibodyPlant.
    response : TableParams
        The 1-D table's config (``table_response_hz``, ``math.inf``: the ideal
        table; ``table_damping_ratio``). On the Stewart table it is its legs'
        reference model's (left at inf: taken from it).
    stewart : StewartParams or None
        The platform for ``backend="stewart"`` (None: its defaults).
    """

    backend: str = "model"
    response: TableParams = TableParams(math.inf, 0.8)
    stewart: object | None = None

    def __post_init__(self) -> None:
        check_choice("table", self.backend, TABLE_BACKENDS)
        if not isinstance(self.response, TableParams):
            raise ParameterError("response must be a TableParams")
        f = self.response.response_frequency_hz
        if math.isfinite(f):
            check_plausible("table_response_hz", f)
        if self.backend != "stewart":
            return
        from hybridtable.stewart.params import StewartParams

        stewart = self.stewart if self.stewart is not None else StewartParams()
        if not isinstance(stewart, StewartParams):
            raise ParameterError("stewart must be a StewartParams")
        object.__setattr__(self, "stewart", stewart)
        # One response for one table: the legs' reference model's.
        ref = stewart.reference_response_hz
        ref_hz = math.inf if ref is None else ref
        zeta = self.response.damping_ratio
        if math.isinf(f):
            object.__setattr__(
                self, "response", TableParams(ref_hz, stewart.reference_damping_ratio)
            )
        elif ref is None or not (
            math.isclose(f, ref_hz, rel_tol=1e-9)
            and math.isclose(zeta, stewart.reference_damping_ratio, abs_tol=1e-12)
        ):
            raise ParameterError(
                f"table_response_hz {f:g} Hz / table_damping_ratio {zeta:g} must be the "
                f"Stewart table's reference model ({ref_hz:g} Hz / "
                f"{stewart.reference_damping_ratio:g}): give it once"
            )


@dataclass(frozen=True)
class DockingPlant:
    """What is physically there: the spacecraft model's rigid body, the
    docking devices and their contact, the table."""

    spacecraft: RigidBodyParams
    contact: DockingContactParams
    table: DockingTable = DockingTable()

    def __post_init__(self) -> None:
        for name, kind in (("spacecraft", RigidBodyParams), ("contact", DockingContactParams)):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError(f"{name} must be a {kind.__name__}")
        if self.table.backend == "stewart" and not self.contact.drake_law:
            raise ParameterError(
                f"{self.contact.pad_law_terms[0]}: the Stewart platform's MultibodyPlant computes Drake's point "
                'contact, which has no such term; the table model ([table] backend = "model") '
                "carries the pads' own law"
            )


@dataclass(frozen=True)
class WrenchCompensatorConfig:
    """The wrench compensator the rig computer runs, and what it believes.

    Parameters
    ----------
    name : str
        A registered wrench compensator (``compensator``: ``"none"``,
        ``"SDC"``, ``"MDC"``, ``"SDMDC"`` or a plug-in).
    lead_time_s : float or None
        SDC lead; None: the sensor delay (:func:`~hybridtable.loop.params.believed`).
    stiffness_model : {"linearized", "nominal", "given"}
        The MDC's 6x6 stiffness (and damping): Drake's contact, without
        friction, linearized at the table's pose at every tick of the contact
        (zero where the table has left the contact); linearized once at the
        nominal docked pose (aligned, on axis, every pad pressed by half the
        undamped peak penetration ``v0 / omega``: on axis the 1-D MDC's
        constant ``k``); or ``stiffness_matrix``.
    stiffness_matrix : 6x6 or None
        ``K`` (``compensator_stiffness_matrix``) for ``stiffness_model="given"``,
        rows/columns ``[x, y, z, rx, ry, rz]`` with the moment rows first in
        the wrench: ``-dw/dq`` (N/m, N, N m/m, N m/rad).
    force_deadband_n : float
        The compensator acts while the measured force's norm (or its axial
        compression, ``deadband_reading``) exceeds it.
    deadband_reading : {"force_norm", "axial_force"}
        What the dead band reads (:data:`DEADBAND_READINGS`): ``axial_force``
        is the 1-D run format's gate, ``f_mea <= force_deadband_n``.
    clamp_nonnegative : bool
        The compensated wrench is zero while its force would pull the devices
        together along the docking axis (``fz > 0`` on the spacecraft): the 1-D
        run format's clamp ``f_comp = max(f_comp, 0)``.
    stiffness_n_per_m : float or None
        The contact stiffness (all pads together) of the compensator's contact
        model (``compensator_stiffness_n_per_m``, as in 1-D): its linearized
        and nominal ``K``, and ``sdmdc-online``'s prior; None: the contact's
        (:func:`~hybridtable.loop.params.believed`).
    """

    name: str = "none"
    lead_time_s: float | None = None
    stiffness_model: str = "linearized"
    stiffness_matrix: tuple | None = None
    force_deadband_n: float = 0.0
    stiffness_n_per_m: float | None = None
    deadband_reading: str = "force_norm"
    clamp_nonnegative: bool = False

    def __post_init__(self) -> None:
        from hybridtable.six_dof.registry import wrench_compensator_names

        s = object.__setattr__
        s(
            self,
            "name",
            check_choice("compensator", self.name, wrench_compensator_names(), any_case=True),
        )
        if self.lead_time_s is not None:
            s(self, "lead_time_s", check_nonnegative("lead_time_s", self.lead_time_s))
        check_choice("stiffness_model", self.stiffness_model, STIFFNESS_MODELS)
        if self.stiffness_matrix is not None:
            s(self, "stiffness_matrix", _stiffness_matrix(self.stiffness_matrix))
        if self.stiffness_model == "given" and self.stiffness_matrix is None:
            raise ParameterError('stiffness_model "given" needs compensator_stiffness_matrix')
        s(self, "force_deadband_n", check_nonnegative("force_deadband_n", self.force_deadband_n))
        check_choice("deadband_reading", self.deadband_reading, DEADBAND_READINGS)
        if not isinstance(self.clamp_nonnegative, bool):
            raise ParameterError(
                f"clamp_nonnegative must be true or false (got {self.clamp_nonnegative!r})"
            )
        if self.stiffness_n_per_m is not None:
            k = check_positive("compensator_stiffness_n_per_m", self.stiffness_n_per_m)
            s(self, "stiffness_n_per_m", check_plausible("compensator_stiffness_n_per_m", k))


@dataclass(frozen=True)
class FTNoiseParams:
    """White noise of what the rig computer reads, per axis, drawn at its
    ticks: the F/T sensor's wrench and the table's measured pose.

    Parameters
    ----------
    force_std_n, moment_std_n_m : float
        Standard deviations of the F/T reading (``force_noise_n``,
        ``moment_noise_n_m``), >= 0.
    seed : int
        Seed of the noise, a whole number >= 0.
    position_std_m, attitude_std_rad : float
        Standard deviations of the table's measured position and of a small
        rotation of its measured attitude about each axis (``position_noise_m``,
        ``attitude_noise_rad``), >= 0: the encoders the compensator reads.
    """

    force_std_n: float = 0.0
    moment_std_n_m: float = 0.0
    seed: int = 0
    position_std_m: float = 0.0
    attitude_std_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("force_std_n", "moment_std_n_m", "position_std_m", "attitude_std_rad"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))
        object.__setattr__(self, "seed", check_seed("seed", self.seed))

    @property
    def on_pose(self) -> bool:
        """The measured pose has noise."""
        return self.position_std_m > 0.0 or self.attitude_std_rad > 0.0


@dataclass(frozen=True)
class DockingRig:
    """The rig's computer: the wrench it reads, its rate, its compensator.

    Parameters
    ----------
    sensor : SensorParams
        The 1-D loop's sensor config: the F/T delay (``sensor_delay_s``), >= 0.
        A delay between ticks reads the two neighbouring samples interpolated,
        as the 1-D sampled rig does
        (:func:`~hybridtable.systems.sensor.sample_taps`).
    sample_rate_hz : float
        Rate of the rig computer (spacecraft model, compensator, sensor), > 0.
    compensator : WrenchCompensatorConfig
    noise : FTNoiseParams
        The F/T sensor's noise.
    duration_s : float or None
        How long it records; None: until the contact has ended.
    """

    sensor: SensorParams = SensorParams()
    sample_rate_hz: float = 1000.0
    # Built on use, not at import: a wrench compensator plug-in may import this module.
    compensator: WrenchCompensatorConfig = field(default_factory=WrenchCompensatorConfig)
    noise: FTNoiseParams = FTNoiseParams()
    duration_s: float | None = None

    def __post_init__(self) -> None:
        for name, kind in (
            ("sensor", SensorParams),
            ("compensator", WrenchCompensatorConfig),
            ("noise", FTNoiseParams),
        ):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError(f"{name} must be a {kind.__name__}")
        rate = check_positive("sample_rate_hz", self.sample_rate_hz)
        object.__setattr__(self, "sample_rate_hz", check_plausible("sample_rate_hz", rate))
        check_plausible("sensor_delay_s", self.sensor.sensor_delay_s)
        if self.duration_s is not None:
            d = check_positive("duration_s", self.duration_s)
            if d > 600.0:
                raise ParameterError(f"duration_s must be <= 600 s (got {d:g})")
            object.__setattr__(self, "duration_s", d)


@flat_properties
@dataclass(frozen=True, init=False)
class DockingLoopParams(NestedParams):
    """Every parameter of one 6-DoF docking run, SI units, one config per
    component, as the 1-D loop's :class:`~hybridtable.loop.params.HybridLoopParams`
    (the same :class:`~hybridtable._nested.NestedParams`)::

        DockingLoopParams
          plant: DockingPlant
            spacecraft: RigidBodyParams      mass, inertia, port
            contact: DockingContactParams    stiffness, dissipation, friction, pads
            table: DockingTable              backend, response (the 1-D TableParams), stewart
          rig: DockingRig
            sensor: SensorParams             sensor_delay_s (the 1-D sensor's)
            sample_rate_hz, duration_s
            compensator: WrenchCompensatorConfig
            noise: FTNoiseParams
          approach: ApproachParams           speed, gap, misalignment

    Build it nested or by flat names (:data:`FIELDS`), e.g.
    ``DockingLoopParams(spacecraft=body, contact=contact, sensor_delay_s=0.005,
    compensator="SDMDC")``; every flat name reads as a property and
    :meth:`with_` changes by flat name or by config. ``spacecraft`` and
    ``contact`` are required.
    """

    plant: DockingPlant
    rig: DockingRig = field(default_factory=DockingRig)
    approach: ApproachParams = ApproachParams()

    PARTS: ClassVar[dict[str, type]] = {
        "plant": DockingPlant,
        "rig": DockingRig,
        "approach": ApproachParams,
    }
    FIELDS: ClassVar[dict[str, tuple[str, ...]]] = {
        "spacecraft": ("plant", "spacecraft"),
        "spacecraft_mass_kg": ("plant", "spacecraft", "mass_kg"),
        "inertia_kg_m2": ("plant", "spacecraft", "inertia_kg_m2"),
        "port_distance_m": ("plant", "spacecraft", "port_distance_m"),
        "lateral_offset_m": ("plant", "spacecraft", "lateral_offset_m"),
        "contact": ("plant", "contact"),
        **{f.name: ("plant", "contact", f.name) for f in fields(DockingContactParams)},
        "initial_velocity_m_per_s": ("approach", "initial_velocity_m_per_s"),
        "initial_gap_m": ("approach", "initial_gap_m"),
        "misalignment_rad": ("approach", "misalignment_rad"),
        "angular_rate_rad_per_s": ("approach", "angular_rate_rad_per_s"),
        "lateral_miss_m": ("approach", "lateral_miss_m"),
        "sample_rate_hz": ("rig", "sample_rate_hz"),
        "sensor_delay_s": ("rig", "sensor", "sensor_delay_s"),
        "table": ("plant", "table", "backend"),
        "table_response_hz": ("plant", "table", "response", "response_frequency_hz"),
        "table_damping_ratio": ("plant", "table", "response", "damping_ratio"),
        "compensator": ("rig", "compensator", "name"),
        "lead_time_s": ("rig", "compensator", "lead_time_s"),
        "stiffness_model": ("rig", "compensator", "stiffness_model"),
        "compensator_stiffness_matrix": ("rig", "compensator", "stiffness_matrix"),
        "force_deadband_n": ("rig", "compensator", "force_deadband_n"),
        "deadband_reading": ("rig", "compensator", "deadband_reading"),
        "clamp_nonnegative": ("rig", "compensator", "clamp_nonnegative"),
        "compensator_stiffness_n_per_m": ("rig", "compensator", "stiffness_n_per_m"),
        "force_noise_n": ("rig", "noise", "force_std_n"),
        "moment_noise_n_m": ("rig", "noise", "moment_std_n_m"),
        "position_noise_m": ("rig", "noise", "position_std_m"),
        "attitude_noise_rad": ("rig", "noise", "attitude_std_rad"),
        "seed": ("rig", "noise", "seed"),
        "duration_s": ("rig", "duration_s"),
        "stewart": ("plant", "table", "stewart"),
    }
    REQUIRED: ClassVar[dict[str, str]] = {"plant": "plant= or spacecraft= and contact="}
    EXAMPLE: ClassVar[str] = "spacecraft"

    def to_dict(self) -> dict:
        """Every quantity by flat name, a config (spacecraft, contact,
        approach, stewart) as a dict of its fields (the contact's devices of
        its geometry only): the layout of ``simulate6 --json``'s ``params``."""
        out: dict = {}
        configs = [path for path in self.FIELDS.values() if len(path) == 2 and path[0] == "plant"]
        configs += [("plant", "table", "stewart"), ("approach",)]
        for name, value in self.quantities().items():
            path = self.FIELDS[name]
            if any(path[: len(c)] == c and path != c for c in configs):
                continue  # inside a config given whole (spacecraft, contact, approach)
            out[name] = asdict(value) if is_dataclass(value) else value
            if name == "contact":  # the devices of its geometry only
                for other, keys in DEVICE_FIELDS.items():
                    if other != value.geometry:
                        for key in keys:
                            del out[name][key]
                out["approach"] = asdict(self.approach)
        return out

    # -- derived --------------------------------------------------------
    @property
    def sample_period_s(self) -> float:
        """The rig computer's tick h = 1 / sample_rate_hz (s)."""
        return 1.0 / self.sample_rate_hz

    @property
    def delay_taps(self) -> tuple[int, float]:
        """The sensor delay as whole ticks ``M`` and a fraction ``alpha`` of a
        tick (:func:`~hybridtable.systems.sensor.sample_taps`)."""
        return sample_taps(self.sensor_delay_s, self.sample_period_s)

    @property
    def delay_ticks(self) -> int:
        """The ticks a reading can lag the contact: ``M``, or ``M + 1`` for a
        delay between ticks."""
        m, alpha = self.delay_taps
        return m + (1 if alpha else 0)

    @property
    def effective_lead_time_s(self) -> float:
        """The SDC lead: ``lead_time_s`` or the sensor delay."""
        return believed(self, "lead_time_s")

    @property
    def believed_contact(self) -> DockingContactParams:
        """The contact the compensator's model believes: the contact with the
        believed stiffness (``compensator_stiffness_n_per_m``) and without
        friction (Drake's regularized friction is steep near zero slip,
        ``mu f / 1e-4 m/s``, which a damping matrix would turn into lateral
        forces of tens of kN)."""
        k = believed(self, "compensator_stiffness_n_per_m", self.contact.contact_stiffness_n_per_m)
        return replace(self.contact, contact_stiffness_n_per_m=k, friction_coefficient=0.0)

    @property
    def contact_frequency_hz(self) -> float:
        """On-axis contact frequency sqrt(k / m) / 2 pi (Hz)."""
        k = self.contact.contact_stiffness_n_per_m
        return math.sqrt(k / self.spacecraft.mass_kg) / (2.0 * math.pi)

    def without_noise(self, **changes: Any) -> DockingLoopParams:
        """The same loop with ``changes`` (flat names) and no noise in it: the
        F/T sensor's and the encoders' (a model's run of a recorded one, a
        candidate run)."""
        return self.with_(
            **changes,
            force_noise_n=0.0,
            moment_noise_n_m=0.0,
            position_noise_m=0.0,
            attitude_noise_rad=0.0,
        )

    def ideal_rig(self) -> DockingLoopParams:
        """The same docking on the ideal rig: no sensor delay, the ideal table
        model, no compensation, no F/T noise (what ``simulate6`` compares a
        run with, and a campaign's ``energy_excess``)."""
        return self.with_(
            sensor_delay_s=0.0,
            table="model",
            table_response_hz=math.inf,
            compensator="none",
            force_noise_n=0.0,
            moment_noise_n_m=0.0,
            stewart=None,
        )

    @property
    def peak_press_m(self) -> float:
        """The undamped head-on peak press of the contact (m): the spacecraft's
        approach energy taken by the contact alone (:func:`~hybridtable.six_dof.contact.peak_press_m`)."""
        return peak_press_m(
            self.contact, self.spacecraft.mass_kg, self.approach.initial_velocity_m_per_s
        )

    def nominal_pose(self) -> np.ndarray:
        """The nominal docked pose ``q`` (6): aligned, on axis, pressed by half
        the undamped peak press (:attr:`peak_press_m`): every pad into the
        plate, or the probe into the socket's floor."""
        z = 0.5 * self.peak_press_m
        if self.contact.is_cone:
            z += floor_depth_m(self.contact)
        return np.array([0.0, 0.0, z, 0.0, 0.0, 0.0])


def _stiffness_matrix(value) -> tuple:
    """A finite 6x6 stiffness no stiffer than any docking contact."""
    try:
        K = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError("compensator_stiffness_matrix must be a 6x6 matrix") from None
    if K.shape != (6, 6) or not np.all(np.isfinite(K)):
        raise ParameterError(
            f"compensator_stiffness_matrix must be a finite 6x6 matrix (got shape {K.shape})"
        )
    most = LIMITS["compensator_stiffness_n_per_m"].high
    if np.any(np.abs(K) > most):
        i, j = np.unravel_index(int(np.argmax(np.abs(K))), K.shape)
        raise ParameterError(
            f"compensator_stiffness_matrix ([compensator] stiffness_matrix of a scenario) "
            f"entries must be at most {most:g} in magnitude (N/m, N m/rad; no docking "
            f"contact is stiffer); got {K[i, j]:g} at row {i}, column {j}"
        )
    return tuple(map(tuple, K.tolist()))
