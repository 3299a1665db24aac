"""The 6-axis force/torque sensor of the 6-DoF loop: a delay and white noise;
and the table's encoders: white noise on the measured pose.

The delay is the 1-D loop's sampled delay line on six channels
(:class:`~hybridtable.systems.sensor.ForceSensorDelay`); the noise is
deterministic per seed, channel and tick (:func:`~hybridtable.systems.noise.noise_sample`),
so a run repeats exactly.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem, System

from hybridtable.six_dof.params import FTNoiseParams
from hybridtable.six_dof.pose import rotation_exp, rotation_log
from hybridtable.systems.noise import noise_sample
from hybridtable.systems.sensor import ForceSensorDelay, SensorParams

__all__ = ["WrenchNoise", "PoseNoise", "add_wrench_sensor"]

#: Noise channels of the six wrench components (distinct from the 1-D channels).
_CHANNELS = (601, 602, 603, 604, 605, 606)

#: Noise channels of the measured pose: position x, y, z, then the attitude's turn.
_POSE_CHANNELS = (611, 612, 613, 614, 615, 616)


class WrenchNoise(LeafSystem):
    """Adds white noise to a wrench at the rig computer's ticks.

    Ports
    -----
    Input ``wrench`` (6: N m, N), output ``noisy_wrench`` (6: N m, N):
    ``wrench + sigma * n[k]`` with ``k`` the tick of the current time.
    """

    def __init__(self, moment_std_n_m: float, force_std_n: float, seed: int, period_s: float):
        LeafSystem.__init__(self)
        self._std = np.array([moment_std_n_m] * 3 + [force_std_n] * 3)
        self._seed = int(seed)
        self._h = float(period_s)
        self._in = self.DeclareVectorInputPort("wrench", 6)
        self.DeclareVectorOutputPort("noisy_wrench", BasicVector(6), self._calc)

    def _calc(self, context, output) -> None:
        tick = int(round(context.get_time() / self._h))
        n = np.array([noise_sample(self._seed, c, tick) for c in _CHANNELS])
        output.SetFromVector(self._in.Eval(context) + self._std * n)


class PoseNoise(LeafSystem):
    """The table's pose as its encoders read it, at the rig computer's ticks.

    Ports
    -----
    Input ``table_state`` (12: m, rad, m/s, rad/s), output
    ``measured_table_state`` (12): the position plus ``sigma_p n[k]``, the
    attitude ``R`` turned to ``exp(sigma_a n'[k]) R`` (its rotation vector),
    the twist as it is; ``k`` the tick of the current time.
    """

    def __init__(self, position_std_m: float, attitude_std_rad: float, seed: int, period_s: float):
        LeafSystem.__init__(self)
        self._std = (float(position_std_m), float(attitude_std_rad))
        self._seed = int(seed)
        self._h = float(period_s)
        self._in = self.DeclareVectorInputPort("table_state", 12)
        self.DeclareVectorOutputPort("measured_table_state", BasicVector(12), self._calc)

    def _calc(self, context, output) -> None:
        tick = int(round(context.get_time() / self._h))
        n = np.array([noise_sample(self._seed, c, tick) for c in _POSE_CHANNELS])
        x = np.array(self._in.Eval(context))
        x[0:3] += self._std[0] * n[0:3]
        if self._std[1] > 0.0:
            x[3:6] = rotation_log(rotation_exp(self._std[1] * n[3:6]) @ rotation_exp(x[3:6]))
        output.SetFromVector(x)


def add_wrench_sensor(
    builder: DiagramBuilder,
    sensor: SensorParams,
    period_s: float,
    noise: FTNoiseParams | None = None,
) -> tuple[System, System]:
    """Add the sensor: the 1-D sensor's sampled delay (``sensor``) on six
    channels, then ``noise``. Returns ``(input system, output system)``:
    connect the contact wrench to the first's input ``force`` (6) and read the
    measured wrench from the last's output 0."""
    delay = builder.AddNamedSystem(
        "ft_sensor", ForceSensorDelay(sensor, "sampled", period_s, size=6)
    )
    if noise is None or (noise.force_std_n == 0.0 and noise.moment_std_n_m == 0.0):
        return delay, delay
    noisy = builder.AddNamedSystem(
        "ft_noise", WrenchNoise(noise.moment_std_n_m, noise.force_std_n, noise.seed, period_s)
    )
    builder.Connect(delay.GetOutputPort("measured_force"), noisy.get_input_port())
    return delay, noisy
