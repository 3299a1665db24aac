"""Seeded measurement noise in front of a compensator.

The rig computer reads noisy sensors: the measured force and the table
position carry Gaussian noise, a new sample every computer period, held in
between: white, or coloured as a stationary AR(1) sequence
``e[k] = phi e[k-1] + sqrt(1 - phi^2) sigma w[k]`` (``phi`` the lag-one
correlation, the same ``sigma`` whatever ``phi``). :func:`with_measurement_noise` puts a :class:`MeasurementNoise`
between the loop's sensors and any compensator, as one system with the
compensator's ports; the loop's log keeps the noise-free signals.

The noise sequence is a function of ``(seed, channel, tick)`` (and ``phi``)
only, so a run is reproducible, two runs with the same seed see the same
noise, and :func:`noise_series` gives the samples the computer read.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, Diagram, DiagramBuilder, LeafSystem_, System
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative, check_positive, check_seed
from hybridtable.errors import ParameterError

__all__ = [
    "MeasurementNoiseParams",
    "MeasurementNoise",
    "MeasurementNoise_",
    "noise_sample",
    "noise_series",
    "with_measurement_noise",
]

_CHUNK = 4096


@lru_cache(maxsize=256)
def _chunk(seed: int, channel: int, index: int) -> np.ndarray:
    return np.random.default_rng([seed, channel, index]).standard_normal(_CHUNK)


def noise_sample(seed: int, channel: int, tick: int) -> float:
    """Standard normal sample number ``tick`` of a channel (deterministic)."""
    return float(_chunk(seed, channel, tick // _CHUNK)[tick % _CHUNK])


@lru_cache(maxsize=256)
def _ar1_chunk(seed: int, channel: int, phi: float, index: int) -> np.ndarray:
    """Chunk ``index`` of the unit-variance AR(1) sequence (each chunk
    continues the previous one)."""
    w = _chunk(seed, channel, index)
    out = np.empty(_CHUNK)
    gain = math.sqrt(1.0 - phi * phi)
    prev = _ar1_chunk(seed, channel, phi, index - 1)[-1] if index > 0 else None
    for k in range(_CHUNK):
        prev = w[k] if prev is None else phi * prev + gain * w[k]
        out[k] = prev
    return out


def _unit_sample(seed: int, channel: int, phi: float, tick: int) -> float:
    if phi == 0.0:
        return noise_sample(seed, channel, tick)
    return float(_ar1_chunk(seed, channel, phi, tick // _CHUNK)[tick % _CHUNK])


def noise_series(params: MeasurementNoiseParams, channel: str, n: int) -> np.ndarray:
    """The noise of ``channel`` (``"force"``, N, or ``"position"``, m) at ticks
    ``0 .. n - 1``: exactly what :class:`MeasurementNoise` adds."""
    index, std = {
        "force": (0, params.force_std_n),
        "position": (1, params.position_std_m),
    }[channel]
    phi = params.ar1_coefficient
    return np.array([std * _unit_sample(params.seed, index, phi, k) for k in range(n)])


@dataclass(frozen=True)
class MeasurementNoiseParams:
    """White measurement noise, SI units.

    Parameters
    ----------
    force_std_n : float
        Standard deviation of the force noise, >= 0.
    position_std_m : float
        Standard deviation of the table position noise, >= 0.
    seed : int
        Seed of the noise sequence, >= 0.
    ar1_coefficient : float
        Lag-one correlation ``phi`` of both channels' noise, in (-1, 1)
        (0: white).
    """

    force_std_n: float = 0.0
    position_std_m: float = 0.0
    seed: int = 0
    ar1_coefficient: float = 0.0

    def __post_init__(self) -> None:
        for name in ("force_std_n", "position_std_m"):
            object.__setattr__(self, name, check_nonnegative(name, getattr(self, name)))
        object.__setattr__(self, "seed", check_seed("seed", self.seed))
        phi = float(self.ar1_coefficient)
        if not (math.isfinite(phi) and -1.0 < phi < 1.0):
            raise ParameterError(f"ar1_coefficient must be in (-1, 1) (got {self.ar1_coefficient})")
        object.__setattr__(self, "ar1_coefficient", phi)


@TemplateSystem.define("MeasurementNoise_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__])
def MeasurementNoise_(T):
    class Impl(LeafSystem_[T]):
        """Adds held noise (white or AR(1)) to the measured force and table position.

        Ports
        -----
        Input ``measured_force`` (size 1, N), input ``table_motion`` (size 3)
        Output ``measured_force`` (size 1, N)
            Plus ``force_std_n`` noise.
        Output ``table_motion`` (size 3: m, m/s, m/s^2)
            Position plus ``position_std_m`` noise (velocity and acceleration
            unchanged).

        Discrete state ``[tick, force noise, position noise]``, a new sample
        every ``period_s`` (the rig computer's period).
        """

        def _construct(self, params: MeasurementNoiseParams, period_s: float, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.period_s = check_positive("period_s", period_s)
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self._m = self.DeclareVectorInputPort("table_motion", 3)
            self.DeclareDiscreteState(self._sample(0))
            self.DeclarePeriodicDiscreteUpdateEvent(self.period_s, 0.0, self._draw)
            self.DeclareVectorOutputPort("measured_force", BasicVector_[T](1), self._calc_force)
            self.DeclareVectorOutputPort("table_motion", BasicVector_[T](3), self._calc_motion)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.period_s, converter=converter)

        def _sample(self, tick: int) -> np.ndarray:
            p = self.params
            phi = p.ar1_coefficient
            return np.array(
                [
                    float(tick),
                    p.force_std_n * _unit_sample(p.seed, 0, phi, tick),
                    p.position_std_m * _unit_sample(p.seed, 1, phi, tick),
                ]
            )

        def _draw(self, context, discrete_state):
            tick = context.get_discrete_state(0).value()[0]
            tick = int(round(tick.value() if hasattr(tick, "value") else tick)) + 1
            discrete_state.get_mutable_vector(0).SetFromVector(self._sample(tick))

        def _calc_force(self, context, output):
            noise = context.get_discrete_state(0).GetAtIndex(1)
            output.SetAtIndex(0, self._f.Eval(context)[0] + noise)

        def _calc_motion(self, context, output):
            noise = context.get_discrete_state(0).GetAtIndex(2)
            p, v, a = self._m.Eval(context)
            output.SetFromVector(np.array([p + noise, v, a]))

    return Impl


MeasurementNoise = MeasurementNoise_[None]


def with_measurement_noise(
    compensator: System, noise: MeasurementNoiseParams, period_s: float
) -> Diagram:
    """``compensator`` reading its force and table position through a
    :class:`MeasurementNoise`, as one system with the compensator's ports."""
    builder = DiagramBuilder()
    inner = builder.AddNamedSystem("inner_compensator", compensator)
    source = builder.AddNamedSystem("measurement_noise", MeasurementNoise(noise, period_s))
    builder.Connect(source.GetOutputPort("measured_force"), inner.GetInputPort("measured_force"))
    builder.Connect(source.GetOutputPort("table_motion"), inner.GetInputPort("table_motion"))
    builder.ExportInput(source.GetInputPort("measured_force"), "measured_force")
    builder.ExportInput(inner.GetInputPort("measured_force_rate"), "measured_force_rate")
    builder.ExportInput(source.GetInputPort("table_motion"), "table_motion")
    builder.ExportInput(inner.GetInputPort("commanded_state"), "commanded_state")
    builder.ExportOutput(inner.GetOutputPort("compensated_force"), "compensated_force")
    diagram = builder.Build()
    diagram.set_name(f"noisy_{compensator.get_name() or 'compensator'}")
    return diagram
