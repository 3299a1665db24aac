"""Helpers of the analysis tests."""

from __future__ import annotations

from hybridtable.loop.params import HybridLoopParams

__all__ = ["damped"]


def damped(p: HybridLoopParams, zeta: float) -> HybridLoopParams:
    """``p`` with a contact damping of ratio ``zeta``: ``c = 2 zeta sqrt(k m)`` (N s/m)."""
    return p.with_contact_damping_ratio(zeta)
