"""The motion table over one tick of a held command: a second-order response.

Each coordinate of the table follows ``x'' = w^2 (u - x) - 2 zeta w x'``
(``w = 2 pi f``) under the command ``u`` held over the tick ``h``; the exact
update is the matrix exponential of ``[[0, 1, 0], [-w^2, -2 zeta w, w^2],
[0, 0, 0]] h``. The 1-D fast engine's sampled table, the 6-DoF table model,
the Stewart servo's reference model and its identification all take it from
:func:`second_order_tick`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

__all__ = ["second_order_tick"]


def second_order_tick(
    response_hz: float, damping_ratio: float, period_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)`` of one coordinate over a tick with the command held.

    ``[x, x'](t + h) = Phi [x, x'](t) + Gamma u``.

    Parameters
    ----------
    response_hz : float
        Natural frequency ``f`` [Hz], finite and > 0.
    damping_ratio : float
        ``zeta``, >= 0.
    period_s : float
        The tick ``h`` [s].

    Returns
    -------
    Phi : ndarray (2, 2)
    Gamma : ndarray (2,)
    """
    w = 2.0 * math.pi * response_hz
    m = np.zeros((3, 3))
    m[:2, :2] = [[0.0, 1.0], [-w * w, -2.0 * damping_ratio * w]]
    m[1, 2] = w * w
    e = expm(m * period_s)
    return e[:2, :2], e[:2, 2]
