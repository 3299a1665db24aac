"""Helpers of the analysis tests."""

from __future__ import annotations

import math

from hybridtable.loop.params import HybridLoopParams

__all__ = ["damped"]


def damped(p: HybridLoopParams, zeta: float) -> HybridLoopParams:
    """``p`` with a contact damping of ratio ``zeta``: ``c = 2 zeta sqrt(k m)`` (N s/m)."""
    c = 2 * zeta * math.sqrt(p.contact_stiffness_n_per_m * p.spacecraft_mass_kg)
    return p.with_(contact_damping_n_s_per_m=c)
