"""Drake systems of the candidate physical effects (:mod:`hybridtable.effects`).

Three back-ends with the ports of the nominal ones, so any of them drops into
the replay and the closed loop through :class:`hybridtable.rig.RigPhysics`:

- :class:`ContactLaw` (contact: in ``motion`` (3), out ``force``,
  ``force_rate``): the unilateral spring generalized with a power law, viscous
  and Hunt-Crossley damping, Coulomb friction and a series compliance;
- :class:`MeasurementChain` (sensor: in ``force``, out ``measured_force``):
  the force-measurement chain of a sampled rig, a first-order low pass, a
  fractional delay and an offset;
- :class:`ResonantTable` (table: in ``commanded_state`` (2), out ``motion``
  (3)): the second-order table followed by a lightly damped structural mode.

With their parameters at the null values they reproduce the nominal systems
exactly (tests/test_effects.py).

:func:`chain_output` puts a user's system behind one output port of a
back-end (e.g. a gain behind ``measured_force``), for effects a user registers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.math import tanh
from pydrake.systems.framework import Diagram, DiagramBuilder, LeafSystem_, System
from pydrake.systems.primitives import (
    Adder,
    ConstantVectorSource,
    DiscreteTimeDelay,
    LinearSystem,
    MatrixGain,
    Multiplexer,
    PassThrough,
    TrajectorySource,
)
from pydrake.systems.scalar_conversion import TemplateSystem
from pydrake.trajectories import PiecewisePolynomial

from hybridtable._validation import (
    ParameterError,
    check_finite,
    check_nonnegative,
    check_positive,
)
from hybridtable.table import TableParams, table_matrices

__all__ = [
    "ContactLawParams",
    "ContactLaw",
    "ContactLaw_",
    "contact_law_force",
    "MeasurementChainParams",
    "MeasurementChain",
    "first_order_hold_filter",
    "StructuralModeParams",
    "ResonantTable",
    "resonant_table_matrices",
    "ChainedOutput",
    "chain_output",
    "RecordedOffset",
]


# -- contact -------------------------------------------------------------------
@dataclass(frozen=True)
class ContactLawParams:
    """A unilateral contact law, SI units.

    In contact (penetration ``d > 0``) the force is::

        f_e = k d_ref (d_c / d_ref)^n,   d_c = d - s f_e     (elastic, series compliance s)
        f   = f_e (1 + alpha v) + c v + F tanh(v / v_F)
        f   = max(f, 0)                                       (never pulls)

    and zero apart (``d <= 0``); ``v`` is the penetration rate.

    Parameters
    ----------
    stiffness_n_per_m : float
        ``k``: the stiffness (with ``n != 1`` the secant stiffness ``f_e / d``
        at ``d = reference_deflection_m``), > 0.
    exponent : float
        ``n`` of the power law, > 0 (1: a linear spring).
    reference_deflection_m : float
        ``d_ref`` of the power law, > 0 (unused when ``n == 1``).
    damping_n_s_per_m : float
        Viscous damping ``c``, >= 0.
    hunt_crossley_s_per_m : float
        Hunt-Crossley factor ``alpha``: damping ``alpha k d`` proportional to
        the deflection, >= 0.
    friction_force_n : float
        Coulomb friction ``F`` against the deflection rate, >= 0.
    friction_velocity_m_per_s : float
        ``v_F``: the sign of ``v`` is smoothed as ``tanh(v / v_F)``, > 0.
    series_compliance_m_per_n : float
        Compliance ``s`` of a structure between the table's position sensor
        and the contact (quasi-static: it takes the elastic force), >= 0.
    """

    stiffness_n_per_m: float
    exponent: float = 1.0
    reference_deflection_m: float = 1e-3
    damping_n_s_per_m: float = 0.0
    hunt_crossley_s_per_m: float = 0.0
    friction_force_n: float = 0.0
    friction_velocity_m_per_s: float = 1e-3
    series_compliance_m_per_n: float = 0.0

    def __post_init__(self) -> None:
        s = object.__setattr__
        for name in (
            "stiffness_n_per_m",
            "exponent",
            "reference_deflection_m",
            "friction_velocity_m_per_s",
        ):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in (
            "damping_n_s_per_m",
            "hunt_crossley_s_per_m",
            "friction_force_n",
            "series_compliance_m_per_n",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))

    @property
    def is_linear_spring(self) -> bool:
        return self.exponent == 1.0


def _elastic(params: ContactLawParams, d):
    """Elastic force ``f_e`` and its slope ``d f_e / d d`` at penetration
    ``d > 0`` (float or AutoDiffXd), with the series compliance solved."""
    k, n, s = params.stiffness_n_per_m, params.exponent, params.series_compliance_m_per_n
    if params.is_linear_spring:
        slope = k / (1.0 + k * s)
        return slope * d, slope + 0.0 * d
    dr = params.reference_deflection_m

    def g(x):  # power law and its derivative, x > 0
        gx = k * dr * (x / dr) ** n
        return gx, n * gx / x

    if s == 0.0:
        return g(d)
    # Solve phi(f) = f - g(d - s f) = 0 on (0, g(d)) by safeguarded Newton in
    # float, then one Newton step in T (exact first derivatives).
    dv = float(d.value()) if isinstance(d, AutoDiffXd) else float(d)
    lo, hi = 0.0, g(dv)[0]
    f = hi / (1.0 + g(dv)[1] * s)
    for _ in range(60):
        x = dv - s * f
        if x <= 0.0:
            f = 0.5 * (lo + hi)
            continue
        gx, dg = g(x)
        phi = f - gx
        if phi > 0.0:
            hi = f
        else:
            lo = f
        step = phi / (1.0 + s * dg)
        f_new = f - step
        if not lo <= f_new <= hi:
            f_new = 0.5 * (lo + hi)
        if abs(f_new - f) <= 1e-13 * max(abs(f), 1.0):
            f = f_new
            break
        f = f_new
    gx, dg = g(d - s * f)
    f_t = f - (f - gx) / (1.0 + s * dg)
    return f_t, dg / (1.0 + s * dg)


def contact_law_force(params: ContactLawParams, p, v, a=0.0):
    """Force and force rate of the contact law at penetration ``p``, rate
    ``v`` and acceleration ``a`` (float or AutoDiffXd)."""
    if not p > 0.0:
        return 0.0 * p, 0.0 * p
    fe, dfe = _elastic(params, p)
    alpha, c = params.hunt_crossley_s_per_m, params.damping_n_s_per_m
    big_f, vf = params.friction_force_n, params.friction_velocity_m_per_s
    f = fe * (1.0 + alpha * v) + c * v
    dfdv = fe * alpha + c
    if big_f > 0.0:
        th = tanh(v / vf)
        f = f + big_f * th
        dfdv = dfdv + big_f / vf * (1.0 - th * th)
    if not f > 0.0:
        return 0.0 * f, 0.0 * f
    rate = dfe * (1.0 + alpha * v) * v + dfdv * a
    return f, rate


@TemplateSystem.define("ContactLaw_", T_list=[float, AutoDiffXd])
def ContactLaw_(T):
    class Impl(LeafSystem_[T]):
        """A unilateral contact with the law of :class:`ContactLawParams`.

        Ports
        -----
        Input ``motion`` (size 3: m, m/s, m/s^2)
            ``[p_act, v_act, a_act]`` of the table: penetration and rates.
        Output ``force`` (size 1, N)
            Contact force, compression positive, zero apart.
        Output ``force_rate`` (size 1, N/s)
            Its time derivative (zero apart).
        """

        def _construct(self, params: ContactLawParams, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self._motion = self.DeclareVectorInputPort("motion", 3)
            self.DeclareVectorOutputPort("force", 1, self._calc_force)
            self.DeclareVectorOutputPort("force_rate", 1, self._calc_force_rate)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, converter=converter)

        def _calc_force(self, context, output):
            p, v, a = self._motion.Eval(context)
            output.SetAtIndex(0, contact_law_force(self.params, p, v, a)[0])

        def _calc_force_rate(self, context, output):
            p, v, a = self._motion.Eval(context)
            output.SetAtIndex(0, contact_law_force(self.params, p, v, a)[1])

    return Impl


ContactLaw = ContactLaw_[None]


# -- force-measurement chain ---------------------------------------------------
@dataclass(frozen=True)
class MeasurementChainParams:
    """The force-measurement chain of a sampled rig, SI units.

    ``f_mea[k] = b + y(t_k - D)``, ``y`` the force through a first-order low
    pass of time constant ``tau``; a delay ``D`` between ticks is linear
    interpolation of the two neighbouring tick samples.

    Parameters
    ----------
    sample_period_s : float
        Tick period ``h`` of the rig computer, > 0.
    delay_s : float
        Total delay ``D`` of the reading, >= 0 (any value, not only whole ticks).
    time_constant_s : float
        ``tau`` of the low pass, >= 0 (0: none).
    bias_n : float
        Offset ``b`` of the reading.
    """

    sample_period_s: float
    delay_s: float = 0.0
    time_constant_s: float = 0.0
    bias_n: float = 0.0

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "sample_period_s", check_positive("sample_period_s", self.sample_period_s))
        s(self, "delay_s", check_nonnegative("delay_s", self.delay_s))
        s(self, "time_constant_s", check_nonnegative("time_constant_s", self.time_constant_s))
        s(self, "bias_n", check_finite("bias_n", self.bias_n))

    def taps(self) -> tuple[int, float]:
        """Whole ticks ``M`` and fraction ``alpha`` of the delay,
        ``D = (M + alpha) h`` (a delay within 1e-9 of a whole tick is whole)."""
        x = self.delay_s / self.sample_period_s
        m = math.floor(x + 1e-9)
        alpha = x - m
        return m, (0.0 if alpha < 1e-9 else alpha)


def first_order_hold_filter(
    time_constant_s: float, sample_period_s: float
) -> tuple[float, float, float]:
    """Exact discretization of ``1 / (tau s + 1)`` for an input linear between
    ticks: ``y[k+1] = a y[k] + b0 u[k] + b1 u[k+1]``; returns ``(a, b0, b1)``."""
    tau, h = time_constant_s, sample_period_s
    if tau <= 0.0:
        return 0.0, 0.0, 1.0
    a = math.exp(-h / tau)
    q = tau / h * (1.0 - a)  # -expm1 keeps precision for large tau
    return a, q - a, 1.0 - q


class MeasurementChain(Diagram):
    """The force-measurement chain as Drake primitives (:class:`MeasurementChainParams`).

    Ports
    -----
    Input ``force`` (size 1, N)
        Actual contact force.
    Output ``measured_force`` (size 1, N)
        The reading the rig computer gets at its ticks.

    ``force -> [low pass] -> DiscreteTimeDelay taps M, M+1 -> (1 - alpha, alpha) -> + b``.
    The low pass is a discrete ``LinearSystem`` with feedthrough (the
    first-order-hold discretization of the continuous filter: exact while the
    force is linear between ticks). The taps follow the sampled sensor's
    semantics (``DiscreteTimeDelay(h, M - 1)`` read at tick ``k`` is
    ``u(t_k - M h)``), so with ``tau = 0``, ``b = 0`` and a whole-tick delay it
    is exactly :class:`~hybridtable.sensor.ForceSensorDelay` ``"sampled"``.
    """

    def __init__(self, params: MeasurementChainParams) -> None:
        Diagram.__init__(self)
        self.params = params
        h = params.sample_period_s
        builder = DiagramBuilder()
        entry = builder.AddNamedSystem("entry", PassThrough(1))
        signal = entry.get_output_port()
        if params.time_constant_s > 0.0:
            a, b0, b1 = first_order_hold_filter(params.time_constant_s, h)
            # z[k] = y[k] - b1 u[k]:  z[k+1] = a z[k] + (a b1 + b0) u[k], y = z + b1 u.
            lowpass = builder.AddNamedSystem(
                "low_pass",
                LinearSystem([[a]], [[a * b1 + b0]], [[1.0]], [[b1]], time_period=h),
            )
            builder.Connect(signal, lowpass.get_input_port())
            signal = lowpass.get_output_port()
        m, alpha = params.taps()

        def tap(j: int):
            if j == 0:
                return signal
            delay = builder.AddNamedSystem(f"delay_{j}", DiscreteTimeDelay(h, j - 1, 1))
            builder.Connect(signal, delay.get_input_port())
            return delay.get_output_port()

        out = tap(m)
        if alpha > 0.0:
            mux = builder.AddNamedSystem("taps", Multiplexer(2))
            builder.Connect(out, mux.get_input_port(0))
            builder.Connect(tap(m + 1), mux.get_input_port(1))
            mix = builder.AddNamedSystem(
                "interpolation", MatrixGain(np.array([[1 - alpha, alpha]]))
            )
            builder.Connect(mux.get_output_port(), mix.get_input_port())
            out = mix.get_output_port()
        if params.bias_n != 0.0:
            bias = builder.AddNamedSystem("bias", ConstantVectorSource([params.bias_n]))
            adder = builder.AddNamedSystem("add_bias", Adder(2, 1))
            builder.Connect(out, adder.get_input_port(0))
            builder.Connect(bias.get_output_port(), adder.get_input_port(1))
            out = adder.get_output_port()
        builder.ExportInput(entry.get_input_port(), "force")
        builder.ExportOutput(out, "measured_force")
        builder.BuildInto(self)


# -- table ---------------------------------------------------------------------
@dataclass(frozen=True)
class StructuralModeParams:
    """A lightly damped structural mode between the table's servo and its
    contact device.

    Parameters
    ----------
    frequency_hz : float
        Natural frequency of the mode, > 0.
    damping_ratio : float
        Its damping ratio, > 0.
    """

    frequency_hz: float
    damping_ratio: float = 0.05

    def __post_init__(self) -> None:
        object.__setattr__(self, "frequency_hz", check_positive("frequency_hz", self.frequency_hz))
        object.__setattr__(
            self, "damping_ratio", check_positive("damping_ratio", self.damping_ratio)
        )


def resonant_table_matrices(
    table: TableParams, mode: StructuralModeParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space (A, B, C, D) of the second-order table carrying a mode.

    The servo (state ``[p_s, v_s]``, the nominal table) moves the base of the
    mode (state ``[p, v]``)::

        p'' = w_r^2 (p_s - p) + 2 zeta_r w_r (v_s - v)

    Input ``[p_des, v_des]``; output ``[p, v, p'']`` (the contact device).
    An ideal servo (``p_s = p_des``, ``v_s = v_des``) leaves only the mode's state.
    """
    wr = 2.0 * math.pi * mode.frequency_hz
    zr = mode.damping_ratio
    kr, cr = wr * wr, 2.0 * zr * wr
    if table.is_ideal:
        A = np.array([[0.0, 1.0], [-kr, -cr]])
        B = np.array([[0.0, 0.0], [kr, cr]])
    else:
        As, Bs, _, _ = table_matrices(table)
        A = np.zeros((4, 4))
        A[:2, :2] = As
        A[2, 3] = 1.0
        A[3] = [kr, cr, -kr, -cr]
        B = np.zeros((4, 2))
        B[:2] = Bs
    n = A.shape[0]
    C = np.vstack([np.eye(n)[n - 2 :], A[n - 1]])
    D = np.vstack([np.zeros((2, 2)), B[n - 1]])
    return A, B, C, D


class ResonantTable(Diagram):
    """The second-order table with a structural mode (:func:`resonant_table_matrices`).

    Ports
    -----
    Input ``commanded_state`` (size 2: m, m/s)
        ``[p_des, v_des]``.
    Output ``motion`` (size 3: m, m/s, m/s^2)
        ``[p_act, v_act, a_act]`` of the contact device (what the position
        sensor and the contact see).
    """

    def __init__(self, table: TableParams, mode: StructuralModeParams) -> None:
        Diagram.__init__(self)
        self.params = table
        self.mode = mode
        A, B, C, D = resonant_table_matrices(table, mode)
        builder = DiagramBuilder()
        self._linear = builder.AddNamedSystem("resonant_table", LinearSystem(A, B, C, D))
        builder.ExportInput(self._linear.get_input_port(), "commanded_state")
        builder.ExportOutput(self._linear.get_output_port(), "motion")
        builder.BuildInto(self)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Servo and mode at ``position_m`` moving with ``velocity_m_per_s``
        (the mode unstrained)."""
        n = 2 if self.params.is_ideal else 4
        x = np.tile([position_m, velocity_m_per_s], n // 2)
        self.GetSubsystemContext(self._linear, context).SetContinuousState(x)


# -- user stages ---------------------------------------------------------------
class ChainedOutput(Diagram):
    """The ports of ``inner``, with its output ``port_name`` passed through
    ``stage`` (one input, one output of the same size).

    A table's ``set_initial_state`` is forwarded to ``inner``.

    Raises
    ------
    ParameterError
        If ``inner`` has no output ``port_name``.
    """

    def __init__(self, inner: System, stage: System, port_name: str) -> None:
        Diagram.__init__(self)
        if not inner.HasOutputPort(port_name):
            raise ParameterError(f"{inner.get_name() or 'system'} has no output port {port_name!r}")
        builder = DiagramBuilder()
        self.inner = builder.AddNamedSystem("inner", inner)
        self.stage = builder.AddNamedSystem("stage", stage)
        for i in range(inner.num_input_ports()):
            port = inner.get_input_port(i)
            builder.ExportInput(port, port.get_name())
        for i in range(inner.num_output_ports()):
            port = inner.get_output_port(i)
            if port.get_name() == port_name:
                builder.Connect(port, self.stage.get_input_port(0))
                builder.ExportOutput(self.stage.get_output_port(0), port_name)
            else:
                builder.ExportOutput(port, port.get_name())
        builder.BuildInto(self)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        setter = getattr(self.inner, "set_initial_state", None)
        if setter is not None:
            setter(self.GetSubsystemContext(self.inner, context), position_m, velocity_m_per_s)


def chain_output(inner: System, stage: System, port_name: str) -> ChainedOutput:
    """``inner`` with its output ``port_name`` passed through ``stage``
    (:class:`ChainedOutput`)."""
    return ChainedOutput(inner, stage, port_name)


class RecordedOffset(Diagram):
    """Adds a recorded series to a signal: ``y(t) = u(t) + r[k]`` for ``t``
    within half a tick of tick ``k`` (constant pieces centred on the ticks,
    so a reader at tick ``k`` gets ``r[k]`` whatever the rounding of the
    event time); ``r`` is held after its last tick.

    Ports
    -----
    Input ``u`` (size 1), output ``y`` (size 1), same unit.
    """

    def __init__(self, sample_period_s: float, values: np.ndarray) -> None:
        Diagram.__init__(self)
        h = check_positive("sample_period_s", sample_period_s)
        r = np.asarray(values, dtype=float).ravel()
        if r.size < 1 or not np.isfinite(r).all():
            raise ParameterError("RecordedOffset: values must be finite and not empty")
        breaks = h * (np.arange(r.size + 1) - 0.5)
        builder = DiagramBuilder()
        source = builder.AddNamedSystem(
            "recorded",
            TrajectorySource(
                PiecewisePolynomial.ZeroOrderHold(breaks, np.append(r, r[-1])[None, :])
            ),
        )
        adder = builder.AddNamedSystem("add", Adder(2, 1))
        builder.Connect(source.get_output_port(), adder.get_input_port(1))
        builder.ExportInput(adder.get_input_port(0), "u")
        builder.ExportOutput(adder.get_output_port(), "y")
        builder.BuildInto(self)
