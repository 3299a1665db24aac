"""The old import path of the model file's reader (before it moved to the
effect core): use :mod:`hybridtable.effects.model_reader` instead. Kept so
that a script written against ``hybridtable.diagnosis.model_reader`` still
loads; it defines nothing of its own."""

from hybridtable.effects.model_reader import (
    check_document,
    effect_from_json,
    load_model,
    model_from_json,
    provenance,
    scale_from_json,
)

__all__ = [
    "check_document",
    "effect_from_json",
    "load_model",
    "model_from_json",
    "provenance",
    "scale_from_json",
]
