"""The old import path of effects (before ``diagnose`` and ``explain`` shared one
effect core): use :mod:`hybridtable.effects` instead.

Kept so that a plug-in written against ``hybridtable.diagnosis.effects`` (or a
script calling ``hybridtable.diagnosis.register_effect`` or
``hybridtable.diagnosis.load_model``: the model file is the effect core's
too) still loads; it defines nothing of its own.
"""

from hybridtable.effects.effect import STAGES, Effect, EffectParameter, Signature
from hybridtable.effects.model_file import FittedEffect, RigModel
from hybridtable.effects.model_reader import load_model
from hybridtable.effects.registry import (
    effect_names,
    get_effect,
    load_plugin,
    parse_effect_spec,
    register_effect,
)
from hybridtable.effects.spec import ModelSpec, RigScale

__all__ = [
    "STAGES",
    "Effect",
    "EffectParameter",
    "Signature",
    "ModelSpec",
    "RigScale",
    "effect_names",
    "get_effect",
    "load_plugin",
    "parse_effect_spec",
    "register_effect",
    "FittedEffect",
    "RigModel",
    "load_model",
]
