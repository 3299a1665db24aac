"""The rig computer's spacecraft model over one tick: semi-implicit Euler.

The model ``m p'' = -f`` (Eq. 1; ``f`` the compensated force, compression
positive, pushes the spacecraft back) is stepped by the rig computer's
semi-implicit Euler rule, ``v+ = v - f h / m`` then ``p+ = p + h v+``, as the
matrices ``[p+, v+] = A [p, v] + B f`` of :func:`computer_step`. The Drake
spacecraft of a sampled loop (:func:`hybridtable.systems.spacecraft.spacecraft_matrices`,
a discrete ``LinearSystem``) and the fast engine's sampled tick
(:mod:`hybridtable.loop.fast`) both take them from here, and evaluate them in
the same order (``A x`` then ``+ B f``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["computer_step"]


def computer_step(mass_kg: float, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` (2x2, 2x1) of one tick of the rig computer's model.

    Parameters
    ----------
    mass_kg : float
        The mass the model integrates with, > 0.
    period_s : float
        The tick ``h``, > 0.
    """
    h, m = period_s, mass_kg
    return np.array([[1.0, h], [0.0, 1.0]]), np.array([[-h * h / m], [-h / m]])
