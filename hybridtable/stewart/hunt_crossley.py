"""Hunt–Crossley dissipation of the Stewart plant's contact from a viscous damping.

Drake's point contact has no viscous damping, only Hunt–Crossley dissipation
``f = k x (1 + d dx/dt)``: :func:`hunt_crossley_cor` is the CoR of an impact on
such a contact, and :func:`hunt_crossley_dissipation` the dissipation ``d``
whose impact has the CoR of the loop's viscous contact ``k x + c v``.
"""

from __future__ import annotations

import math
from functools import lru_cache

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m

__all__ = ["hunt_crossley_cor", "hunt_crossley_dissipation"]


@lru_cache(maxsize=256)
def hunt_crossley_cor(dissipation_times_velocity: float) -> float:
    """CoR of a mass hitting a linear Hunt–Crossley contact
    ``f = k x (1 + d dx/dt)`` at speed v; it depends on ``d v`` only."""
    from scipy.integrate import solve_ivp

    beta = check_nonnegative("dissipation_times_velocity", dissipation_times_velocity)
    if beta == 0.0:
        return 1.0

    # Dimensionless: x = (v / w) xi, t = tau / w; xi'' = -xi (1 + beta xi').
    def rhs(_, y):
        return [y[1], -y[0] * (1.0 + beta * y[1]) if y[0] > 0.0 else 0.0]

    def out(_, y):
        return y[0]

    out.terminal = True
    out.direction = -1.0
    sol = solve_ivp(
        rhs, (0.0, 50.0), [0.0, 1.0], events=out, rtol=1e-10, atol=1e-12, first_step=1e-6
    )
    if not sol.t_events[0].size:
        return 0.0
    return float(-sol.y_events[0][0][1])


def hunt_crossley_dissipation(
    stiffness_n_per_m: float,
    damping_n_s_per_m: float,
    mass_kg: float,
    velocity_m_per_s: float,
) -> float:
    """Hunt–Crossley dissipation d (s/m) whose impact of ``mass_kg`` at
    ``velocity_m_per_s`` has the CoR of the viscous contact ``k x + c v``.

    Point contact in Drake has no viscous damping; this maps the loop's
    ``contact_damping_n_s_per_m`` to the dissipation with the same energy
    loss in the run's first impact. Zero damping gives zero dissipation.
    """
    k = check_positive("stiffness_n_per_m", stiffness_n_per_m)
    c = check_nonnegative("damping_n_s_per_m", damping_n_s_per_m)
    m = check_positive("mass_kg", mass_kg)
    v = check_positive("velocity_m_per_s", velocity_m_per_s)
    if c == 0.0:
        return 0.0
    zeta = c / critical_damping_n_s_per_m(k, m)
    if zeta >= 1.0:
        raise ParameterError(
            f"contact damping ratio {zeta:.3f} >= 1 has no Hunt–Crossley equivalent "
            "(the viscous contact does not rebound)"
        )
    target = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta))
    from scipy.optimize import brentq

    # hunt_crossley_cor decreases from 1 (beta = 0) towards 0.
    hi = 1.0
    while hunt_crossley_cor(hi) > target:
        hi *= 2.0
        if hi > 1e6:
            raise ParameterError(f"no Hunt–Crossley dissipation reaches CoR {target:.4f}")
    beta = brentq(lambda b: hunt_crossley_cor(b) - target, 0.0, hi, xtol=1e-12)
    return beta / v
