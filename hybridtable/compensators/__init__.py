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

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "online": ("make_online_sdmdc",),
        "paper": (
            "COMPENSATORS",
            "CONTACT_GATES",
            "Compensator",
            "CompensatorParams",
        ),
        "passivity": (
            "PassivityGuard",
            "PassivityParams",
            "passivity_guarded",
        ),
        "polynomial": (
            "PolynomialExtrapolator",
            "PolynomialParams",
        ),
        "registry": (
            "CompensatorFactory",
            "compensator_factory",
            "compensator_names",
            "make_compensator",
            "register_compensator",
        ),
        "smith": (
            "SmithParams",
            "SmithPredictor",
        ),
    },
)
