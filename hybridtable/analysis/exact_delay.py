"""The loop with the exact sensor delay ``e^{-sT}``, to measure the Pade error.

The Drake-linearized loop is cut at the delay
(:meth:`~hybridtable.analysis.blockwise.ContactLoopLinearizer.delay_cut`): a finite model
``H`` from ``[u, f_mea, df_mea/dt]`` to ``[f_comp, f, df/dt]``. Closing the
delay exactly, ``[f_mea, df_mea/dt] = e^{-sT} [f, df/dt]``, gives the open
loop

    G(s) = H_yu + H_yw D (I - H_zw D)^-1 H_zu,    D = e^{-sT} I,

evaluated at any complex ``s``. The closed-loop characteristic function
``1 - G(s)`` is a quasi-polynomial (infinitely many roots); its contact root is
found with ``scipy.optimize.root`` from the Pade model's contact pole, and the
frequency response ``L(i w) = -G(i w)`` gives the exact phase margin.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import root

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.interconnect import StateSpaceBlock
from hybridtable.analysis.margins import (
    contact_pole,
    continuous_poles,
    cor_from_pole,
    crossover_phase_margin,
    damping_ratio,
    effective_delay,
    ideal_crossover_frequency,
)
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "ExactDelayMargins",
    "delay_closed_response",
    "exact_open_loop",
    "exact_contact_root",
    "exact_growth",
    "exact_margins",
]


@dataclass(frozen=True)
class ExactDelayMargins:
    """Contact root and margins with the exact delay, beside the Pade ones.

    Attributes
    ----------
    contact_root : complex
        Root of the quasi-polynomial nearest the Pade contact pole (rad/s).
    predicted_cor, damping_ratio : float
        From ``contact_root`` as in :mod:`hybridtable.analysis.margins`.
    phase_margin_deg, crossover_rad_per_s, effective_delay_s : float
        From the exact frequency response.
    pade_contact_pole : complex
        The Pade model's contact pole (the starting point).
    pade_cor_error : float
        Pade predicted CoR minus exact predicted CoR.
    """

    contact_root: complex
    predicted_cor: float
    damping_ratio: float
    phase_margin_deg: float
    crossover_rad_per_s: float
    effective_delay_s: float
    pade_contact_pole: complex
    pade_cor_error: float

    def to_dict(self) -> dict:
        d = asdict(self)
        for key in ("contact_root", "pade_contact_pole"):
            d[key] = [getattr(self, key).real, getattr(self, key).imag]
        return d


def delay_closed_response(
    cut: StateSpaceBlock, delay_s: float, s: complex | np.ndarray
) -> np.ndarray:
    """``G(s)`` of a delay cut (first input/output: the loop's ``u``/``y``,
    the others: the delayed channels) with the exact delay ``e^{-s T}``."""
    s = np.asarray(s, dtype=complex)
    H = cut.transfer(s)
    nd = H.shape[-1] - 1
    d = np.exp(-s * delay_s)[..., None, None] * np.eye(nd)
    Hyu, Hyw = H[..., :1, :1], H[..., :1, 1:]
    Hzu, Hzw = H[..., 1:, :1], H[..., 1:, 1:]
    inner = np.linalg.solve(np.eye(nd) - Hzw @ d, Hzu)
    return (Hyu + Hyw @ d @ inner)[..., 0, 0]


def exact_open_loop(linearizer: ContactLoopLinearizer, params: HybridLoopParams):
    """``s -> G(s)`` with the exact delay, for ``params``."""
    cut = linearizer.delay_cut(params)
    T = params.sensor_delay_s
    return lambda s: delay_closed_response(cut, T, s)


def exact_contact_root(
    linearizer: ContactLoopLinearizer,
    params: HybridLoopParams,
    start: complex | None = None,
) -> complex:
    """Root of ``1 - G(s)`` (exact delay) from the Pade model's contact pole.

    Raises
    ------
    RuntimeError
        If the root finder does not converge.
    """
    if start is None:
        loop = linearizer.open_loop(params)
        start = contact_pole(continuous_poles(loop.closed_loop_poles(), 0.0), params)
    if params.sensor_delay_s == 0.0:
        return complex(start)  # no delay: the Pade model is exact
    G = exact_open_loop(linearizer, params)
    scale = abs(start)

    def f(x: np.ndarray) -> list[float]:
        r = 1.0 - G(complex(x[0], x[1]) * scale)
        return [float(np.real(r)), float(np.imag(r))]

    sol = root(f, [start.real / scale, start.imag / scale], method="hybr", tol=1e-14)
    s = complex(sol.x[0], sol.x[1]) * scale
    if not sol.success and abs(1.0 - G(s)) > 1e-9:
        raise RuntimeError(f"exact-delay contact root did not converge: {sol.message}")
    return s


def exact_growth(linearizer: ContactLoopLinearizer):
    """``params -> Re(contact root)`` with the exact delay, for the
    critical-delay search of :mod:`hybridtable.analysis.margins` (tracks the contact root
    only: the quasi-polynomial's other roots are not searched)."""
    return lambda params: exact_contact_root(linearizer, params).real


def exact_margins(linearizer: ContactLoopLinearizer, params: HybridLoopParams) -> ExactDelayMargins:
    """Contact root, CoR and phase margin with the exact delay, and the Pade
    model's CoR error."""
    loop = linearizer.open_loop(params)
    pade_pole = contact_pole(continuous_poles(loop.closed_loop_poles(), 0.0), params)
    s = exact_contact_root(linearizer, params, pade_pole)
    G = exact_open_loop(linearizer, params)
    w0 = ideal_crossover_frequency(params)
    pm, wgc = crossover_phase_margin(lambda w: -G(1j * w), w0)
    cor = cor_from_pole(s)
    return ExactDelayMargins(
        contact_root=s,
        predicted_cor=cor,
        damping_ratio=damping_ratio(s),
        phase_margin_deg=pm,
        crossover_rad_per_s=wgc,
        effective_delay_s=effective_delay(params, pm, wgc),
        pade_contact_pole=pade_pole,
        pade_cor_error=cor_from_pole(pade_pole) - cor if math.isfinite(cor) else math.nan,
    )
