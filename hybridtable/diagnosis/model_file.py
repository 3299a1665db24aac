"""The old import path of the model file (before it moved to the effect core):
use :mod:`hybridtable.effects.model_file` instead. Kept so that a script
written against ``hybridtable.diagnosis.model_file`` still loads; it defines
nothing of its own."""

from hybridtable.diagnosis.diagnose import model_from_diagnosis
from hybridtable.effects.model_file import (
    MODEL6_FORMAT,
    MODEL_FORMAT,
    RIG_KEYS,
    FittedEffect,
    ModelRun,
    RigModel,
    created_now,
    describe_effects,
    effects_json,
    tool_version,
)

__all__ = [
    "MODEL_FORMAT",
    "MODEL6_FORMAT",
    "RIG_KEYS",
    "FittedEffect",
    "ModelRun",
    "RigModel",
    "created_now",
    "describe_effects",
    "effects_json",
    "model_from_diagnosis",
    "tool_version",
]
