"""The rig computer's spacecraft model over one tick: semi-implicit Euler, or another rule.

The model ``m p'' = -f`` (Eq. 1; ``f`` the compensated force, compression
positive, pushes the spacecraft back) is stepped by the rig computer's
semi-implicit Euler rule (the format's), ``v+ = v - f h / m`` then
``p+ = p + h v+``, as the matrices ``[p+, v+] = A [p, v] + B f`` of
:func:`computer_step`. A real computer may step it otherwise
(:data:`INTEGRATORS`): with the force held over the tick, every such rule is
``p+ = p + h (theta v+ + (1 - theta) v)`` for a weight ``theta`` of the new
velocity: 1 semi-implicit Euler, 0 explicit Euler, 1/2 the trapezoid rule
(classical RK4 with the force held over the tick gives the same step,
``p+ = p + h v - f h^2 / (2 m)``, exactly). The Drake
spacecraft of a sampled loop (:func:`hybridtable.systems.spacecraft.spacecraft_matrices`,
a discrete ``LinearSystem``) and the fast engine's sampled tick
(:mod:`hybridtable.loop.fast`) both take them from here, and evaluate them in
the same order (``A x`` then ``+ B f``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["INTEGRATORS", "DEFAULT_INTEGRATOR", "computer_step"]

#: The rules a rig computer may step its model by: name -> the weight ``theta``
#: of the new velocity in the position's step (see the module).
INTEGRATORS: dict[str, float] = {
    "semi_implicit_euler": 1.0,
    "trapezoid": 0.5,
    "explicit_euler": 0.0,
}

#: The format's rule (``docs/run-format.md``, step 3).
DEFAULT_INTEGRATOR = "semi_implicit_euler"


def computer_step(
    mass_kg: float, period_s: float, integrator: str = DEFAULT_INTEGRATOR
) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` (2x2, 2x1) of one tick of the rig computer's model.

    Parameters
    ----------
    mass_kg : float
        The mass the model integrates with, > 0.
    period_s : float
        The tick ``h``, > 0.
    integrator : str
        The rule it steps by, one of :data:`INTEGRATORS`.
    """
    h, m, theta = period_s, mass_kg, INTEGRATORS[integrator]
    return np.array([[1.0, h], [0.0, 1.0]]), np.array([[-theta * h * h / m], [-h / m]])
