"""The force-sensor delay T_fms: ``f_mea(t) = f_act(t - T_fms)``.

Three realizations of the same pure delay, with the same ports:

- ``"continuous"``: Drake's ``DiscreteTimeDelay`` at a fine period ``h``. Seen
  by continuous consumers, ``DiscreteTimeDelay(h, N)`` delays by ``N h`` to
  ``(N + 1) h``, on average ``N h + h/2``, so ``h = T / (N + 1/2)``.
- ``"sampled"``: the rig computer's view at a sample rate. Discrete consumers
  updating at tick ``k`` read ``DiscreteTimeDelay(h, N)`` as ``u(t_k - (N+1) h)``,
  so a delay of ``M`` samples is ``DiscreteTimeDelay(h, M - 1)`` and
  ``f_mea[k] = f_act(t_k - M h)`` exactly. A delay between ticks,
  ``D = (M + alpha) h`` (:func:`sample_taps`; a real sensor's filter delay is
  rarely a whole number of ticks), reads the two neighbouring samples linearly
  interpolated: ``f_mea[k] = (1 - alpha) f_act(t_k - M h) + alpha f_act(t_k - (M + 1) h)``.
- ``"pade"``: a continuous Pade approximant (``control.pade``) for analysis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import (
    DiscreteTimeDelay,
    LinearSystem,
    MatrixGain,
    Multiplexer,
    PassThrough,
)

from hybridtable._components import Block, Component
from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError

__all__ = [
    "SensorParams",
    "ForceSensorDelay",
    "continuous_delay_period",
    "sample_taps",
    "delayed_by_ticks",
    "pade_state_space",
]


@dataclass(frozen=True)
class SensorParams:
    """Parameters of the force-measurement chain.

    Parameters
    ----------
    sensor_delay_s : float
        Pure delay T_fms of the measured force behind the actual force, >= 0.
    """

    sensor_delay_s: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "sensor_delay_s", check_nonnegative("sensor_delay_s", self.sensor_delay_s)
        )


def continuous_delay_period(delay_s: float, max_period_s: float) -> tuple[float, int]:
    """Period ``h`` and length ``N`` of a ``DiscreteTimeDelay`` whose mean delay
    ``N h + h/2`` equals ``delay_s``, with ``h <= max_period_s``."""
    check_positive("sensor_delay_s", delay_s)
    check_positive("time_step_s", max_period_s)
    n = max(0, math.ceil(delay_s / max_period_s - 0.5))
    return delay_s / (n + 0.5), n


def sample_taps(delay_s: float, sample_period_s: float) -> tuple[int, float]:
    """Whole ticks ``M`` and fraction ``alpha`` in ``[0, 1)`` of a delay
    ``delay_s = (M + alpha) h`` read at ticks of period ``h`` (a fraction below
    1e-9 of a tick is rounding: the delay is whole; a fit's finite differences
    of a delay must still see the fraction)."""
    x = delay_s / sample_period_s
    m = math.floor(x + 1e-9)
    alpha = x - m
    return m, (0.0 if alpha < 1e-9 else alpha)


def pade_state_space(
    delay_s: float, order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space (A, B, C, D) of the order-``order`` Pade approximant of e^{-sT}."""
    import control  # only analysis needs it; keeps it out of the CLI's start-up

    if order < 1:
        raise ParameterError(f"pade_order must be >= 1 (got {order})")
    num, den = control.pade(delay_s, order)
    ss = control.tf2ss(control.tf(num, den))
    return (np.asarray(ss.A), np.asarray(ss.B), np.asarray(ss.C), np.asarray(ss.D))


class ForceSensorDelay(Component):
    """Pure delay of the force-measurement chain, as a Drake system.

    Ports
    -----
    Input ``force`` (size ``size``, N and/or N/s)
        Actual contact force f_act (and optionally its rate, for analysis).
    Output ``measured_force`` (size ``size``)
        The same signal delayed by T_fms: f_mea.

    Parameters
    ----------
    params : SensorParams
    mode : {"continuous", "sampled", "pade"}
    period_s : float
        Fine period of the continuous realization (an upper bound) or the
        sample period of the sampled one; unused for ``"pade"``.
    pade_order : int
        Order of the Pade approximant.
    size : int
        Number of channels delayed (1, or 2 for ``[f, df/dt]``).
    """

    def __init__(
        self,
        params: SensorParams,
        mode: str = "continuous",
        period_s: float = 1e-4,
        pade_order: int = 3,
        size: int = 1,
    ) -> None:
        Component.__init__(self)
        self.params = params
        self.mode = mode
        self.size = size
        T = params.sensor_delay_s
        self.update_period_s: float | None = None
        self._samples: int | None = 0 if T == 0.0 else None
        self._alpha = 0.0
        if T == 0.0:
            pass
        elif mode == "continuous":
            self.update_period_s, self._ticks = continuous_delay_period(T, period_s)
        elif mode == "sampled":
            self.update_period_s = period_s
            self._samples, self._alpha = sample_taps(T, period_s)
            self._ticks = self._samples
        elif mode == "pade":
            self._pade = pade_state_space(T, pade_order)
        else:
            raise ParameterError(f"sensor mode must be continuous, sampled or pade (got {mode!r})")
        self._build("delay")

    def _add(self, builder: DiagramBuilder, name: str) -> Block:
        size, h = self.size, self.update_period_s
        if self._alpha:
            return self._add_taps(builder, name)
        if self._samples == 0:
            inner = PassThrough(size)
        elif self.mode == "continuous":
            inner = DiscreteTimeDelay(h, self._ticks, size)
        elif self.mode == "sampled":
            inner = DiscreteTimeDelay(h, self._ticks - 1, size)
        else:
            eye = np.eye(size)
            inner = LinearSystem(*(np.kron(eye, M) for M in self._pade))
        inner = builder.AddNamedSystem(name, inner)
        return Block(
            self, {"force": [inner.get_input_port()]}, {"measured_force": inner.get_output_port()}
        )

    def _add_taps(self, builder: DiagramBuilder, name: str) -> Block:
        """A sampled delay between ticks: taps ``M`` and ``M + 1``, mixed by
        ``(1 - alpha, alpha)``."""
        size, h, m, alpha = self.size, self.update_period_s, self._samples, self._alpha

        def tap(j: int):
            inner = PassThrough(size) if j == 0 else DiscreteTimeDelay(h, j - 1, size)
            return builder.AddNamedSystem(f"{name}_tap{j}", inner)

        near, far = tap(m), tap(m + 1)
        taps = builder.AddNamedSystem(f"{name}_taps", Multiplexer([size, size]))
        builder.Connect(near.get_output_port(), taps.get_input_port(0))
        builder.Connect(far.get_output_port(), taps.get_input_port(1))
        mix = builder.AddNamedSystem(
            name, MatrixGain(np.kron(np.array([[1.0 - alpha, alpha]]), np.eye(size)))
        )
        builder.Connect(taps.get_output_port(), mix.get_input_port())
        return Block(
            self,
            {"force": [near.get_input_port(), far.get_input_port()]},
            {"measured_force": mix.get_output_port()},
        )

    def readings(self, force_n: np.ndarray) -> np.ndarray | None:
        """The readings at the ticks for the actual force at the ticks
        (``f_mea[k] = f_act[k - M]``, or the two taps' mix for a delay between
        ticks, zero before the start), operation for operation the Drake
        primitives'; None unless the delay is sampled or zero."""
        if self._samples is None:
            return None
        x = np.asarray(force_n, dtype=float)
        out = delayed_by_ticks(x, self._samples)
        if self._alpha:
            out = (1 - self._alpha) * out + self._alpha * delayed_by_ticks(x, self._samples + 1)
        return out


def delayed_by_ticks(x: np.ndarray, ticks: int) -> np.ndarray:
    """``x[k - ticks]``, zero before the start: a sampled ``DiscreteTimeDelay``
    read at the ticks (``DiscreteTimeDelay(h, ticks - 1)``, see above)."""
    if ticks == 0:
        return x.copy()
    m = min(ticks, len(x))
    return np.concatenate([np.zeros(m), x[: len(x) - m]])
