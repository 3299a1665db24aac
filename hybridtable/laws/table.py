"""The motion table: a second-order response, and any linear part over a held tick.

Each coordinate of the table follows ``x'' = w^2 (u - x) - 2 zeta w x'``
(``w = 2 pi f``): :func:`second_order_matrices` states it once. Over a tick
``h`` with the command ``u`` held, a linear part ``x' = A x + B u`` moves
exactly by ``x(t + h) = e^{A h} x(t) + int_0^h e^{A s} ds B u``
(:func:`held_tick`: the exponential of ``[[A, B], [0, 0]] h``). The Drake table
(``systems.table``), its sampled replay, the 1-D fast engine's sampled
table, the 6-DoF table model, the Stewart servo's reference model and its
identification, and the sampled stability analysis's plant all take the
table and the held tick from here.

The force sensor's compliant mount (the effect ``mount_resonance``) is the
same second-order law on the force, driven by a force that is linear between
the ticks (:func:`ramp_tick`: the first-order hold).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

__all__ = ["held_tick", "ramp_tick", "second_order_matrices", "second_order_tick"]


def second_order_matrices(
    response_hz: float, damping_ratio: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of one coordinate, state ``[x, x']``, input the command ``u``:
    ``A = [[0, 1], [-w^2, -2 zeta w]]``, ``B = [[0], [w^2]]``."""
    w = 2.0 * math.pi * response_hz
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * damping_ratio * w]])
    B = np.array([[0.0], [w * w]])
    return A, B


def held_tick(A: np.ndarray, B: np.ndarray, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)``: ``x' = A x + B u`` over a tick ``h`` with ``u`` held,
    ``x(t + h) = Phi x(t) + Gamma u``: the exact zero-order-hold solution,
    the exponential of ``[[A, B], [0, 0]] h`` (``scipy.linalg.expm``: on a
    table with ``w h = 1.3`` it is within 3e-15 of the exact value, Drake's
    ``DiscreteTimeApproximation`` 1.4e-11, measured against an 80-bit series)."""
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = np.atleast_2d(np.asarray(B, dtype=float))
    n, m = B.shape
    big = np.zeros((n + m, n + m))
    big[:n, :n] = A
    big[:n, n:] = B
    e = expm(big * period_s)
    return e[:n, :n], e[:n, n:]


def ramp_tick(
    A: np.ndarray, B: np.ndarray, period_s: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi, G0, G1)``: ``x' = A x + B u`` over a tick ``h`` with ``u``
    linear between the ticks (the first-order hold),
    ``x(t + h) = Phi x(t) + G0 u(t) + G1 u(t + h)``: exact, the exponential
    of ``[[A, B, 0], [0, 0, I], [0, 0, 0]] h`` (the input and its slope as
    states)."""
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = np.atleast_2d(np.asarray(B, dtype=float))
    n, m = B.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = A
    big[:n, n : n + m] = B
    big[n : n + m, n + m :] = np.eye(m)
    e = expm(big * period_s)
    slope = e[:n, n + m :] / period_s  # per unit of u(t + h) - u(t)
    return e[:n, :n], e[:n, n : n + m] - slope, slope


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
    Phi, Gamma = held_tick(*second_order_matrices(response_hz, damping_ratio), period_s)
    return Phi, Gamma[:, 0]
