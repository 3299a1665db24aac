"""Helpers of the compensator tests: run a discrete system tick by tick as a rig
computer does, and the four compensator inputs as arrays.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PLUGINS", "run_ticks", "compensator_inputs"]


PLUGINS = ("sdmdc-online", "polynomial", "smith", "smith-online")


def run_ticks(system, inputs, output="compensated_force"):
    """Run a discrete system as the rig computer does: at tick k fix the
    inputs, read the output (state of the earlier ticks), then update.

    ``inputs``: port name -> array (n_ticks, size). Returns (n_ticks, size).
    """
    ctx = system.CreateDefaultContext()
    n = len(next(iter(inputs.values())))
    out = []
    for k in range(n):
        for name, values in inputs.items():
            system.GetInputPort(name).FixValue(ctx, np.atleast_1d(values[k]))
        out.append(np.array(system.GetOutputPort(output).Eval(ctx)))
        ctx.SetDiscreteState(system.EvalUniquePeriodicDiscreteUpdate(ctx))
    return np.array(out)


def compensator_inputs(n, f=0.0, p_act=0.0, v_act=0.0, p_des=0.0, v_des=0.0):
    def col(x):
        return np.broadcast_to(np.asarray(x, dtype=float), (n,))

    return {
        "measured_force": col(f)[:, None],
        "measured_force_rate": np.zeros((n, 1)),
        "table_motion": np.stack([col(p_act), col(v_act), np.zeros(n)], axis=1),
        "commanded_state": np.stack([col(p_des), col(v_des)], axis=1),
    }
