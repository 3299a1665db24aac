"""Shared 6-DoF parameters: the paper's Table 1 point (k 1e5 N/m, f_con 1 Hz,
v0 0.1 m/s, delay 5 ms, table 25 Hz, zeta 0.8) on a 1 kHz rig computer."""

from __future__ import annotations

import math

from hybridtable.six_dof.params import (
    ApproachParams,
    DockingContactParams,
    DockingLoopParams,
    RigidBodyParams,
)

MASS_KG = 1e5 / (2.0 * math.pi) ** 2
INERTIA_KG_M2 = (1689.0, 1689.0, 1689.0)


def docking_params(
    offset_m: float = 0.0,
    pitch_deg: float = 0.0,
    inertia=INERTIA_KG_M2,
    friction: float = 0.0,
    dissipation: float = 0.0,
    **kwargs,
) -> DockingLoopParams:
    """Table 1 on a 6-DoF rig; ``kwargs`` go to DockingLoopParams."""
    body = RigidBodyParams(MASS_KG, inertia, 1.5, (offset_m, 0.0))
    contact = DockingContactParams(
        1e5, contact_dissipation_s_per_m=dissipation, friction_coefficient=friction
    )
    approach = ApproachParams(0.1, 0.001, (0.0, math.radians(pitch_deg)))
    kwargs.setdefault("sample_rate_hz", 1000.0)
    return DockingLoopParams(spacecraft=body, contact=contact, approach=approach, **kwargs)
