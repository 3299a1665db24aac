"""The force-measurement chain of a sampled rig: first-order low pass, the
sensor mount's mode, fractional delay and offset (:class:`MeasurementChain`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    Adder,
    ConstantVectorSource,
    LinearSystem,
    PassThrough,
)

from hybridtable._components import add_component, connect_input
from hybridtable._validation import check_finite, check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.laws.table import ramp_tick, second_order_matrices
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams, sample_taps

__all__ = [
    "MeasurementChainParams",
    "MeasurementChain",
    "first_order_hold_filter",
    "low_pass_system",
    "mount_system",
]


# -- force-measurement chain ---------------------------------------------------
@dataclass(frozen=True)
class MeasurementChainParams:
    """The force-measurement chain of a sampled rig, SI units.

    ``f_mea[k] = b + y(t_k - D)``, ``y`` the force through a first-order low
    pass of time constant ``tau``, then through the mount's mode
    ``y'' = w^2 (u - y) - 2 zeta w y'`` (``w = 2 pi f``; the sensor on a
    compliant mount rings); a delay ``D`` between ticks is linear
    interpolation of the two neighbouring tick samples. Both filters are
    exact for a force linear between the ticks.

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
    mount_frequency_hz : float
        The mount's natural frequency ``f``, > 0 (``inf``: a rigid mount, none).
    mount_damping_ratio : float
        The mount's damping ratio ``zeta``, > 0.
    """

    sample_period_s: float
    delay_s: float = 0.0
    time_constant_s: float = 0.0
    bias_n: float = 0.0
    mount_frequency_hz: float = math.inf
    mount_damping_ratio: float = 0.05

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "sample_period_s", check_positive("sample_period_s", self.sample_period_s))
        s(self, "delay_s", check_nonnegative("delay_s", self.delay_s))
        s(self, "time_constant_s", check_nonnegative("time_constant_s", self.time_constant_s))
        s(self, "bias_n", check_finite("bias_n", self.bias_n))
        f = float(self.mount_frequency_hz)
        if not f > 0.0:  # inf allowed: no mount
            raise ParameterError(
                f"mount_frequency_hz must be > 0 (got {self.mount_frequency_hz!r})"
            )
        s(self, "mount_frequency_hz", f)
        s(
            self,
            "mount_damping_ratio",
            check_positive("mount_damping_ratio", self.mount_damping_ratio),
        )

    @property
    def has_mount(self) -> bool:
        return math.isfinite(self.mount_frequency_hz)

    def taps(self) -> tuple[int, float]:
        """Whole ticks ``M`` and fraction ``alpha`` of the delay,
        ``D = (M + alpha) h`` (:func:`~hybridtable.systems.sensor.sample_taps`)."""
        return sample_taps(self.delay_s, self.sample_period_s)

    def sensor(self) -> ForceSensorDelay:
        """The chain's delay: the sampled sensor of delay ``D``."""
        return ForceSensorDelay(SensorParams(self.delay_s), "sampled", self.sample_period_s)


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


def low_pass_system(
    time_constant_s: float, sample_period_s: float, channels: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of the low pass on ``channels`` independent channels
    as a discrete ``LinearSystem`` with feedthrough
    (:func:`first_order_hold_filter`): with ``y[k+1] = a y[k] + b0 u[k] + b1
    u[k+1]`` the state is ``z = y - b1 u``: ``z[k+1] = a z[k] + (a b1 + b0)
    u[k]``, ``y = z + b1 u``."""
    a, b0, b1 = first_order_hold_filter(time_constant_s, sample_period_s)
    eye = np.eye(channels)
    return a * eye, (a * b1 + b0) * eye, eye, b1 * eye


def mount_system(
    frequency_hz: float, damping_ratio: float, sample_period_s: float, channels: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of the mount's mode on ``channels`` independent
    channels as a discrete ``LinearSystem`` with feedthrough: the table's
    second-order law (:func:`~hybridtable.laws.table.second_order_matrices`,
    unit gain) over a tick with the force linear between the ticks
    (:func:`~hybridtable.laws.table.ramp_tick`). With ``x[k+1] = Phi x[k] +
    G0 u[k] + G1 u[k+1]`` the state is ``z = x - G1 u``: ``z[k+1] = Phi z[k]
    + (Phi G1 + G0) u[k]``, ``y = c z + c G1 u``, ``c = [1, 0]``."""
    phi, g0, g1 = ramp_tick(*second_order_matrices(frequency_hz, damping_ratio), sample_period_s)
    c = np.array([[1.0, 0.0]])
    eye = np.eye(channels)
    return (
        np.kron(eye, phi),
        np.kron(eye, phi @ g1 + g0),
        np.kron(eye, c),
        np.kron(eye, c @ g1),
    )


class MeasurementChain(Diagram):
    """The force-measurement chain as Drake primitives (:class:`MeasurementChainParams`).

    Ports
    -----
    Input ``force`` (size 1, N)
        Actual contact force.
    Output ``measured_force`` (size 1, N)
        The reading the rig computer gets at its ticks.

    ``force -> [low pass] -> [mount] -> ForceSensorDelay "sampled" (taps M, M+1 mixed by
    (1 - alpha, alpha)) -> + b``.
    The low pass is a discrete ``LinearSystem`` with feedthrough (the
    first-order-hold discretization of the continuous filter: exact while the
    force is linear between ticks). The taps follow the sampled sensor's
    semantics (``DiscreteTimeDelay(h, M - 1)`` read at tick ``k`` is
    ``u(t_k - M h)``), so with ``tau = 0``, ``b = 0`` and a whole-tick delay it
    is exactly :class:`~hybridtable.systems.sensor.ForceSensorDelay` ``"sampled"``.
    """

    def __init__(self, params: MeasurementChainParams) -> None:
        Diagram.__init__(self)
        self.params = params
        h = params.sample_period_s
        builder = DiagramBuilder()
        entry = builder.AddNamedSystem("entry", PassThrough(1))
        signal = entry.get_output_port()
        if params.time_constant_s > 0.0:
            lowpass = builder.AddNamedSystem(
                "low_pass",
                LinearSystem(*low_pass_system(params.time_constant_s, h), time_period=h),
            )
            builder.Connect(signal, lowpass.get_input_port())
            signal = lowpass.get_output_port()
        if params.has_mount:
            mount = builder.AddNamedSystem("mount", LinearSystem(*self._mount(), time_period=h))
            builder.Connect(signal, mount.get_input_port())
            signal = mount.get_output_port()
        delay = add_component(builder, "delay", params.sensor())
        connect_input(builder, signal, delay, "force")
        out = delay.outputs["measured_force"]
        if params.bias_n != 0.0:
            bias = builder.AddNamedSystem("bias", ConstantVectorSource([params.bias_n]))
            adder = builder.AddNamedSystem("add_bias", Adder(2, 1))
            builder.Connect(out, adder.get_input_port(0))
            builder.Connect(bias.get_output_port(), adder.get_input_port(1))
            out = adder.get_output_port()
        builder.ExportInput(entry.get_input_port(), "force")
        builder.ExportOutput(out, "measured_force")
        builder.BuildInto(self)

    def _mount(self):
        p = self.params
        return mount_system(p.mount_frequency_hz, p.mount_damping_ratio, p.sample_period_s)

    def readings(self, force_n: np.ndarray) -> np.ndarray:
        """The readings at the ticks for the actual force at the ticks: the
        chain's difference equations, operation for operation those of its
        Drake primitives (no simulator)."""
        p = self.params
        y = np.asarray(force_n, dtype=float)
        if p.time_constant_s > 0.0:
            a, b0, b1 = first_order_hold_filter(p.time_constant_s, p.sample_period_s)
            gain, z, out = a * b1 + b0, 0.0, np.empty(len(y))
            for k, u in enumerate(y.tolist()):
                out[k] = 1.0 * z + b1 * u
                z = a * z + gain * u
            y = out
        if p.has_mount:  # y = c z + d u, z = A z + b u: Eigen's order of operations
            A, B, _, D = self._mount()
            (a00, a01), (a10, a11) = A.tolist()
            (b0, b1), d = B[:, 0].tolist(), float(D[0, 0])
            z0 = z1 = 0.0
            out = np.empty(len(y))
            for k, u in enumerate(y.tolist()):
                out[k] = z0 + d * u
                z0, z1 = (a00 * z0 + a01 * z1) + b0 * u, (a10 * z0 + a11 * z1) + b1 * u
            y = out
        out = p.sensor().readings(y)
        if p.bias_n != 0.0:
            out = out + p.bias_n
        return out
