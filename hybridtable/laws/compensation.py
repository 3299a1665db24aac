"""The rig computer's compensation law (the paper's Eq. 2-7), 1-D and 6-DoF.

The compensator predicts the contact force at the pose the spacecraft model
commands from what the sensor measured at the pose the table reached::

    f_comp = f_mea + T_lead r                           (SDC: phase lead, Eq. 2-3)
                   + G (q_des - q_act) + D (qd_des - qd_act)   (MDC, Eq. 4-6)

- ``r`` is the measured force's rate: the rig computer's backward difference
  ``(f_mea[k] - f_mea[k-1]) / h`` (:func:`backward_difference`), or ``df/dt``
  in a continuous analysis;
- ``G = df/dq`` and ``D = df/dqd`` are the contact's gradients the compensator
  believes. Along one axis ``G = k_con`` and ``D = c_con`` (compression
  positive); on the wrench ``[moment; force]`` of the 6-DoF loop they are 6x6
  matrices, ``G = -K`` with the paper's stiffness ``K = -dw/dq``. The 1-D law is
  the 6-DoF law on the contact normal, but for the gate's level: the 6-DoF
  loop gates on the measured force's norm, the 1-D loop on the signed
  compression (a pull beyond the dead band opens the one, not the other).

Contact gating (``gate``): ``"measured_force"`` zeroes ``f_comp`` while the
measured force (its norm on a wrench) is at or below ``force_deadband_n``;
``"table_position"`` adds the MDC term only while the table's position says
the devices touch; ``"none"`` is the linear compensator of the stability
analysis. ``clamp_nonnegative`` keeps a 1-D ``f_comp`` (a wrench's force
along the docking axis) from pulling.

:func:`compensate` is the one definition: the Drake compensators are compiled
from it (:mod:`hybridtable.compensators.paper`, ``.online``), the fast engine
calls it per tick and derives its exact per-mode force rows from it
(:mod:`hybridtable.loop.fast`), the 6-DoF wrench compensator calls it on
arrays (:mod:`hybridtable.six_dof.compensator`), and the audits of a record
solve for its constants on the terms :func:`linear_terms` takes from it
(:mod:`hybridtable.measurement.audit`, :mod:`hybridtable.six_dof.audit_law6`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from hybridtable.laws.select import select

__all__ = [
    "CompensationLaw",
    "GATES",
    "above_deadband",
    "compensate",
    "backward_difference",
    "linear_terms",
    "nonnegative",
]

#: How the compensator tells contact.
GATES: tuple[str, ...] = ("measured_force", "table_position", "none")


@dataclass(frozen=True)
class CompensationLaw:
    """The switches and constants of the law; the gains ``G`` and ``D`` are
    arguments of :func:`compensate` (they may be signals: an online
    identifier's estimate, a stiffness linearized at every tick).

    Parameters
    ----------
    lead_time_s : float
        ``T_lead`` of the SDC (0: no lead); the constants may be symbolic
        variables (a law traced once for every value, :mod:`hybridtable.loop.fast`).
    motion_correction : bool
        Add the MDC term.
    force_deadband_n : float
        The measured-force gate's threshold [N].
    gate : {"measured_force", "table_position", "none"}
    clamp_nonnegative : bool
        Clamp a scalar ``f_comp`` at zero (a wrench: zero while its
        compression is below zero, :func:`compensate`'s ``compression``).
    """

    lead_time_s: float = 0.0
    motion_correction: bool = False
    force_deadband_n: float = 0.0
    gate: str = "measured_force"
    clamp_nonnegative: bool = False

    def __post_init__(self) -> None:
        if self.gate not in GATES:
            raise ValueError(f"gate must be one of {GATES}, not {self.gate!r}")

    @property
    def has_lead(self) -> bool:
        """The SDC lead acts (a symbolic lead time counts as one)."""
        lead = self.lead_time_s
        return not isinstance(lead, float | int) or lead > 0.0

    def gate_open(self, level: Any) -> Any:
        """The compensated force may act: the measured force's ``level`` is
        above the dead band (always, without the measured-force gate)."""
        return level > self.force_deadband_n if self.gate == "measured_force" else True

    def corrects_motion(self, touching: Any) -> Any:
        """The MDC term acts (with the table-position gate: only while ``touching``)."""
        if not self.motion_correction:
            return False
        return touching if self.gate == "table_position" else True

    def linear(self, motion_correction: bool | None = None) -> CompensationLaw:
        """The same law without its switches (no gate, no clamp), with or
        without the MDC term: the compensator between two switches."""
        return CompensationLaw(
            lead_time_s=self.lead_time_s,
            motion_correction=(
                self.motion_correction if motion_correction is None else motion_correction
            ),
            force_deadband_n=self.force_deadband_n,
            gate="none",
        )


def _times(gain: Any, x: Any) -> Any:
    """``gain x``: a product for scalars, a matrix product for a matrix gain."""
    return gain @ x if getattr(gain, "ndim", 0) >= 2 else gain * x


def nonnegative(force: Any, compression: Any = None) -> Any:
    """The force clamped at zero: a compensator that never pulls. A wrench is
    zero while its ``compression`` (its force along the axis, pressing) is
    below zero (default: a scalar force is its own compression)."""
    compression = force if compression is None else compression
    return select(compression < 0.0, 0.0 * force, force)


def above_deadband(reading: Any, deadband_n: float) -> Any:
    """A force reading, zero where it is at or below the dead band."""
    return select(reading > deadband_n, reading, 0.0 * reading)


def backward_difference(value: Any, previous: Any, period_s: float) -> Any:
    """The rig computer's rate of a sampled signal: ``(x[k] - x[k-1]) / h``."""
    return (value - previous) / period_s


def compensate(
    law: CompensationLaw,
    measured: Any,
    rate: Any = 0.0,
    response_error: Any = 0.0,
    rate_error: Any = 0.0,
    stiffness: Any = 0.0,
    damping: Any = None,
    touching: Any = True,
    gate_force: Any = None,
    compression: Callable[[Any], Any] | None = None,
) -> Any:
    """The compensated force (or wrench) fed to the spacecraft model.

    Parameters
    ----------
    law : CompensationLaw
    measured : scalar or ndarray
        ``f_mea`` [N] (or the wrench ``[moment; force]``, N m and N).
    rate : scalar or ndarray
        Its rate ``r`` [N/s] (read only with a lead).
    response_error, rate_error : scalar or ndarray
        ``q_des - q_act`` [m, rad] and ``qd_des - qd_act`` [m/s, rad/s].
    stiffness, damping : scalar or ndarray
        ``G`` and ``D`` (``damping=None``: no rate term).
    touching : bool or Formula
        The table's position says the devices touch (``p_act > 0``); read by
        the ``"table_position"`` gate.
    gate_force : scalar, optional
        What the measured-force gate compares with the dead band (default
        ``measured``; the norm of the force on a wrench).
    compression : callable, optional
        The clamp's compression of the compensated wrench (``lambda w:
        -w[5]`` on the docking axis); default: a scalar force is its own.
    """
    f = measured
    if law.has_lead:
        f = f + law.lead_time_s * rate
    if law.motion_correction:
        corrected = f + _times(stiffness, response_error)
        if damping is not None:
            corrected = corrected + _times(damping, rate_error)
        f = select(law.corrects_motion(touching), corrected, f)
    if law.clamp_nonnegative:
        f = nonnegative(f, None if compression is None else compression(f))
    level = measured if gate_force is None else gate_force
    return select(law.gate_open(level), f, 0.0 * measured)


def linear_terms(
    measured: Any,
    rate: Any,
    *,
    response_error: Any = 0.0,
    stiffness: Any = 0.0,
    rate_error: Any = 0.0,
    damping: Any = None,
) -> tuple[Any, Any, Any]:
    """The law between its switches as a sum of terms, one per constant:
    ``f_comp = a * reading + T_lead * lead + s * motion`` with ``a = 1`` and
    ``s = 1`` (the MDC's gains as believed) in the format's law.

    Each term is :func:`compensate` on the law without switches with that
    constant at one and the others' terms at zero, so an audit that solves a
    record for ``a``, ``T_lead`` and ``s`` (a regression on these terms)
    states the law from its one definition. Arguments as :func:`compensate`'s
    (by name but the first two).
    """
    zero = 0.0 * measured
    reading = compensate(CompensationLaw(gate="none"), measured)
    lead = compensate(CompensationLaw(lead_time_s=1.0, gate="none"), zero, rate)
    motion = compensate(
        CompensationLaw(motion_correction=True, gate="none"),
        zero,
        0.0,
        response_error,
        rate_error,
        stiffness,
        damping,
    )
    return reading, lead, motion
