"""The old import path of ``explain``'s effects (before ``diagnose`` and ``explain``
shared one effect core): use :mod:`hybridtable.effects` instead.

Kept so that a plug-in or script written against ``hybridtable.explain``'s
``CorEffect``, ``CorParameter``, ``register_cor_effect``, ``cor_effect_names``
or ``get_cor_effect`` still runs; it defines nothing of its own.
"""

from hybridtable.effects.legacy import CorEffect, CorParameter
from hybridtable.effects.registry import default_effects, get_effect, register_cor_effect

__all__ = ["CorEffect", "CorParameter", "register_cor_effect", "cor_effect_names", "get_cor_effect"]


def cor_effect_names() -> list[str]:
    """The effects ``explain`` tries by default (the old name of
    ``default_effects("explain")``)."""
    return list(default_effects("explain"))


#: The registered effect of a name (the old name of ``get_effect``).
get_cor_effect = get_effect
