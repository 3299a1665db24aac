"""Compensator plug-ins beyond the paper's SDMDC, registered on import.

=================  ==========================================================
name               compensator
=================  ==========================================================
``sdmdc-online``   SDMDC with online stiffness/damping identification
                   (:mod:`hybridtable.plugins.online`)
``polynomial``     polynomial extrapolation of the measured force over the
                   loop delay (:mod:`hybridtable.plugins.polynomial`)
``smith``          model-based Smith predictor (:mod:`hybridtable.plugins.smith`)
``smith-online``   the Smith predictor with the online identification
=================  ==========================================================

The time-domain passivity guard (:mod:`hybridtable.plugins.passivity`) wraps
any of them (``HybridLoopParams.passivity``); :mod:`hybridtable.plugins.noise`
adds seeded measurement noise in front of a compensator.
"""

from __future__ import annotations

from hybridtable.compensator import register_compensator
from hybridtable.plugins.online import make_online_sdmdc
from hybridtable.plugins.polynomial import make_polynomial
from hybridtable.plugins.smith import make_smith, make_smith_online

__all__ = ["PLUGIN_COMPENSATORS"]

#: Compensators this package registers.
PLUGIN_COMPENSATORS: tuple[str, ...] = ("sdmdc-online", "polynomial", "smith", "smith-online")

register_compensator("sdmdc-online", make_online_sdmdc)
register_compensator("polynomial", make_polynomial)
register_compensator("smith", make_smith)
register_compensator("smith-online", make_smith_online)
