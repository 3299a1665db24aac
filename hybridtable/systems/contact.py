"""The contact model: a unilateral spring k_con with optional viscous damping.

``f_act = max(k p_act + c v_act, 0)`` while ``p_act > 0`` (penetration), and
zero when the devices are apart: the contact pushes, never pulls.

The contact is the second swappable back-end of the hybrid loop: input
``motion`` (3), outputs ``force`` (1) and ``force_rate`` (1).
"""

from __future__ import annotations

from dataclasses import dataclass

from pydrake.systems.framework import System

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.laws.compiled import compiled_system
from hybridtable.laws.contact import spring_contact_force, spring_contact_force_rate

__all__ = ["ContactParams", "UnilateralSpringContact"]


@dataclass(frozen=True)
class ContactParams:
    """Parameters of the contact.

    Parameters
    ----------
    stiffness_n_per_m : float
        Contact stiffness k_con, > 0.
    damping_n_s_per_m : float
        Viscous contact damping c, >= 0 (the paper's contacts have none).
    """

    stiffness_n_per_m: float
    damping_n_s_per_m: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "stiffness_n_per_m", check_positive("stiffness_n_per_m", self.stiffness_n_per_m)
        )
        object.__setattr__(
            self,
            "damping_n_s_per_m",
            check_nonnegative("damping_n_s_per_m", self.damping_n_s_per_m),
        )


def UnilateralSpringContact(params: ContactParams, bilateral: bool = False) -> System:
    """Unilateral spring-damper contact between the table's device and the
    passive device, compiled from :mod:`hybridtable.laws.contact`.

    Ports
    -----
    Input ``motion`` (size 3: m, m/s, m/s^2)
        ``[p_act, v_act, a_act]``, penetration and its rates.
    Output ``force`` (size 1, N)
        Actual contact force f_act, compression positive, zero apart.
    Output ``force_rate`` (size 1, N/s)
        d f_act / dt (``k v + c a`` in contact, zero apart); used by the
        continuous-time SDC in analysis.

    ``bilateral=True`` drops the unilateral gating (``f = k p + c v`` for
    any sign of ``p``), the linearization used by the stability analysis:
    ``max(p, 0)`` has zero slope at ``p = 0`` (an ``AffineSystem``).
    """
    k, c = params.stiffness_n_per_m, params.damping_n_s_per_m

    def force(signals):
        p, v, _ = signals["motion"]
        return spring_contact_force(k, c, p, v, bilateral)

    def force_rate(signals):
        p, v, a = signals["motion"]
        return spring_contact_force_rate(k, c, p, v, a, bilateral)

    # A Python callback: the loop reads the contact once a step (the logger)
    # and at the sensor's ticks, fewer times than a compiled system's
    # integrated state would (benchmarks/bench_core.py).
    outputs = {"force": force, "force_rate": force_rate}
    system = compiled_system("contact", {"motion": 3}, outputs, compiled=False)
    system.params = params
    system.bilateral = bool(bilateral)
    #: ``force_law(p, v, a) -> f``: the law this system evaluates (on numbers or,
    #: elementwise, on arrays of samples).
    system.force_law = lambda p, v, a: spring_contact_force(k, c, p, v, bilateral)
    system.force_law_elementwise = True
    return system
