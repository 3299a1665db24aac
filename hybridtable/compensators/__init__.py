"""Delay compensators: the paper's four and the plug-ins, behind one registry.

==================  ========================================================
name                compensator (module)
==================  ========================================================
``none``, ``SDC``,  the paper's (Eq. 2-7): :mod:`~hybridtable.compensators.paper`
``MDC``, ``SDMDC``
``sdmdc-online``    SDMDC with online stiffness/damping identification
                    (:mod:`~hybridtable.compensators.online`,
                    :mod:`~hybridtable.compensators.identification`)
``polynomial``      polynomial extrapolation of the measured force over the
                    loop delay (:mod:`~hybridtable.compensators.polynomial`)
``smith``           model-based Smith predictor (:mod:`~hybridtable.compensators.smith`)
``smith-online``    the Smith predictor with the online identification
==================  ========================================================

:mod:`~hybridtable.compensators.passivity` wraps any of them in the
time-domain passivity observer/controller (``HybridLoopParams.passivity``).
:mod:`~hybridtable.compensators.registry` maps names to factories; a new
compensator is one module here (copy ``polynomial.py``) and one line in the
registry's ``BUILTIN``, or, outside this repository, an entry point of the
group ``hybridtable.compensators``.
"""

from hybridtable.compensators.online import make_online_sdmdc
from hybridtable.compensators.paper import (
    COMPENSATORS,
    CONTACT_GATES,
    Compensator,
    CompensatorParams,
)
from hybridtable.compensators.passivity import PassivityGuard, PassivityParams, passivity_guarded
from hybridtable.compensators.polynomial import PolynomialExtrapolator, PolynomialParams
from hybridtable.compensators.registry import (
    CompensatorFactory,
    compensator_factory,
    compensator_names,
    make_compensator,
    register_compensator,
)
from hybridtable.compensators.smith import SmithParams, SmithPredictor

__all__ = [
    "COMPENSATORS",
    "CONTACT_GATES",
    "Compensator",
    "CompensatorFactory",
    "CompensatorParams",
    "PassivityGuard",
    "PassivityParams",
    "PolynomialExtrapolator",
    "PolynomialParams",
    "SmithParams",
    "SmithPredictor",
    "compensator_factory",
    "compensator_names",
    "make_compensator",
    "make_online_sdmdc",
    "passivity_guarded",
    "register_compensator",
]
