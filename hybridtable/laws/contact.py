"""The unilateral spring-damper contact: it pushes, never pulls.

``f = k p + c v`` while the devices overlap (``p > 0``) and the sum pushes
(``f > 0``); zero otherwise. Its rate is ``k v + c a`` where the force acts.
The Drake contact (:mod:`hybridtable.systems.contact`, compiled from these
functions) and the fast engine's contact force are this law; ``bilateral``
drops the gate (the linearization used by the stability analysis).
"""

from __future__ import annotations

import math
from typing import Any

from hybridtable.laws.select import both, select

__all__ = [
    "critical_damping_n_s_per_m",
    "hunt_crossley_force",
    "mass_for_contact_frequency_kg",
    "spring_contact_force",
    "spring_contact_force_rate",
]


def mass_for_contact_frequency_kg(stiffness_n_per_m: float, frequency_hz: float) -> float:
    """The mass [kg] on which the contact's spring rings at ``frequency_hz``:
    ``f = sqrt(k / m) / (2 pi)``, so ``m = k / (2 pi f)^2`` (how the paper
    states its runs)."""
    return stiffness_n_per_m / (2.0 * math.pi * frequency_hz) ** 2


def critical_damping_n_s_per_m(stiffness_n_per_m: float, mass_kg: float) -> float:
    """The damping ``2 sqrt(k m)`` [N s/m] at which the contact on the mass
    ``mass_kg`` stops rebounding (damping ratio 1)."""
    return 2.0 * math.sqrt(stiffness_n_per_m * mass_kg)


def hunt_crossley_force(elastic_n: Any, elastic_rate_n_per_m: Any, factor_s_per_m: Any, v: Any):
    """Hunt–Crossley dissipation on an elastic force: ``f = f_e (1 + alpha v)``
    of the elastic force ``f_e`` (N, its derivative by the penetration
    ``df_e/dp``, N/m) at penetration rate ``v`` (m/s), ``alpha`` in s/m; returns
    ``f`` and its derivatives by the penetration and by ``v``. Drake's
    compliant point contact is it with ``f_e = k p``
    (:mod:`hybridtable.six_dof.pads`); the 1-D contact law adds it to any
    elastic law (:func:`~hybridtable.systems.contact_law.contact_law_force`).
    Plain arithmetic: floats, arrays, ``AutoDiffXd``, and compiled by numba."""
    gain = 1.0 + factor_s_per_m * v
    return elastic_n * gain, elastic_rate_n_per_m * gain, elastic_n * factor_s_per_m


def _touching(p: Any, f: Any, bilateral: bool) -> Any:
    return True if bilateral else both(p > 0.0, f > 0.0)


def spring_contact_force(
    stiffness_n_per_m: float,
    damping_n_s_per_m: float,
    p_m: Any,
    v_m_per_s: Any,
    bilateral: bool = False,
) -> Any:
    """The contact force [N], compression positive, at penetration ``p_m`` and
    its rate ``v_m_per_s``."""
    f = stiffness_n_per_m * p_m + damping_n_s_per_m * v_m_per_s
    return select(_touching(p_m, f, bilateral), f, 0.0 * f)


def spring_contact_force_rate(
    stiffness_n_per_m: float,
    damping_n_s_per_m: float,
    p_m: Any,
    v_m_per_s: Any,
    a_m_per_s2: Any,
    bilateral: bool = False,
) -> Any:
    """``d f / dt`` [N/s]: ``k v + c a`` where the contact force acts, else 0."""
    f = stiffness_n_per_m * p_m + damping_n_s_per_m * v_m_per_s
    rate = stiffness_n_per_m * v_m_per_s + damping_n_s_per_m * a_m_per_s2
    return select(_touching(p_m, f, bilateral), rate, 0.0 * rate)
