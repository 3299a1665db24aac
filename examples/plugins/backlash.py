"""A user's own effect for ``hybridtable diagnose``: backlash in the table's drive.

Physics: the drive moves the table's contact device through a play of width
``b`` (m): the device sits between the drive's forward face (at ``x``, the
nominal table position, penetration > 0 in contact), which pushes it towards
the contact, and its return face (at ``x + b``), which pushes it away; guide
friction holds it wherever nothing pushes it. The contact force only ever
pushes the device back onto the forward face, so while the devices touch the
play stays taken up and the force is the nominal one. When the contact ends,
the retreating drive leaves the device at the contact surface (``p = 0``)
until the return face, ``b`` behind, catches it; from then on the table
position lags the drive by ``b``. Seen in ``p_act`` after the contact.

Use: ``--plugin examples/plugins/backlash.py:EFFECT``, or install this folder
(its ``pyproject.toml`` registers ``EFFECT`` as the entry point ``backlash``).
"""

import math

import numpy as np
from pydrake.systems.framework import LeafSystem

from hybridtable.effects.effect import Effect, EffectParameter, Signature
from hybridtable.systems.blocks import ChainedOutput

__all__ = ["Backlash", "BacklashTable", "EFFECT", "device_motion"]


def device_motion(y, x, v, a, width_m) -> tuple[float, float, float]:
    """The law: the device's motion for the drive's ``[x, v, a]``, the device
    last at ``y`` (NaN: on the forward face) and a play of ``width_m``."""
    y = x if math.isnan(y) else min(max(y, x), x + width_m)  # the faces push
    y = max(x, min(y, 0.0))  # the contact pushes it back: to the surface, or the face
    moving = y == x or y == x + width_m  # a face drives it
    return (y, v, a) if moving else (y, 0.0, 0.0)


class Backlash(LeafSystem):
    """Drive motion ``[x, v, a]`` in (``drive``), device motion out (``motion``);
    state: the device position at the last tick (NaN: on the forward face)."""

    def __init__(self, width_m: float, period_s: float) -> None:
        super().__init__()
        self.width_m = float(width_m)
        self.DeclareVectorInputPort("drive", 3)
        self.DeclareDiscreteState([math.nan])
        self.DeclarePeriodicDiscreteUpdateEvent(period_s, 0.0, self._update)
        self.DeclareVectorOutputPort("motion", 3, self._output)

    def _device(self, context) -> tuple[float, float, float]:
        x, v, a = self.get_input_port().Eval(context)
        y = context.get_discrete_state_vector().GetAtIndex(0)
        return device_motion(y, x, v, a, self.width_m)

    def _update(self, context, state) -> None:
        state.get_mutable_vector().SetAtIndex(0, self._device(context)[0])

    def _output(self, context, output) -> None:
        output.SetFromVector(np.array(self._device(context)))


class BacklashTable(ChainedOutput):
    """A table's ``motion`` through :class:`Backlash`, with the table's
    ``sampled(h)`` (the replay's exact stepping), ``set_initial_state`` and,
    sampled, ``respond`` (the replay without a simulator)."""

    def __init__(self, table, width_m: float, period_s: float) -> None:
        super().__init__(table, Backlash(width_m, period_s), "motion")

    def sampled(self, period_s: float):
        inner = getattr(self.inner, "sampled", None)
        discrete = inner(period_s) if inner is not None else None
        return None if discrete is None else BacklashTable(discrete, self.stage.width_m, period_s)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        super().set_initial_state(context, position_m, velocity_m_per_s)  # the drive
        # Approaching (v > 0): the play is taken up, the forward face pushes.
        self.GetMutableSubsystemContext(self.stage, context).SetDiscreteState([position_m])

    def respond(self, commands, position_m: float, velocity_m_per_s: float) -> np.ndarray:
        """The motion at the ticks (N, 3) of the sampled form (what its Drake
        diagram computes, without a simulator: the replay uses it): the inner
        table's ``respond`` through the play, its state updated at each tick."""
        drive = self.inner.respond(commands, position_m, velocity_m_per_s)
        out, y = [], position_m  # the state set_initial_state gives
        for x, v, a in drive.tolist():
            out.append(device_motion(y, x, v, a, self.stage.width_m))
            y = out[-1][0]
        return np.array(out).reshape(len(drive), 3)


def _late_offset(scale, residuals) -> list[dict[str, float]]:
    """Fit start: the median p_act residual over each run's last fifth (m)."""
    late = [np.median(r["p_act_m"][-max(len(r["p_act_m"]) // 5, 1) :]) for r in residuals]
    return [{"backlash_m": float(np.clip(np.mean(late), 0.0, 0.5 * scale.peak_deflection_m))}]


EFFECT = Effect(
    name="backlash",
    description="play of width b in the table's drive: after the contact the table "
    "stays at the contact surface, then lags the drive by b",
    parameters=(
        EffectParameter(
            "backlash_m",
            "m",
            "width b of the play between the drive's faces",
            lower=0.0,
            upper=lambda s: 0.5 * s.peak_deflection_m,
            scale=lambda s: 0.002 * s.peak_deflection_m,
            null=0.0,
        ),
    ),
    signature=Signature(
        ("p_act_m",),
        ("free_flight",),
        "after the contact the table stays at the contact surface for b / v, "
        "then lags the drive by b; no change of the force",
    ),
    apply=lambda spec, v, s: spec.wrap(
        "table",
        lambda params, table: BacklashTable(table, v["backlash_m"], params.sample_period_s or 1e-4),
    ),
    touches=("table.drive",),
    starts=_late_offset,
    separation_hint="a run with a longer record after the contact",
)
