"""Reading a model file (``hybridtable-model/1``): every key checked, one line
per defect.

:func:`load_model` reads a file, :func:`model_from_json` a parsed document;
both raise :class:`~hybridtable.errors.ParameterError` naming the file and
the key: malformed JSON, another format version, an effect that is not
registered (its plug-in not loaded), a parameter it does not have or out of
its bounds, a rig-computer key the run format does not know.
"""

from __future__ import annotations

import json
import math
from dataclasses import fields
from pathlib import Path
from typing import Any

from hybridtable._files import read_user_json
from hybridtable._validation import check_choice
from hybridtable.compensators.registry import compensator_names
from hybridtable.effects.model_file import (
    MODEL6_FORMAT,
    MODEL_FORMAT,
    FittedEffect,
    ModelRun,
    RigModel,
    tool_version,
)
from hybridtable.effects.registry import get_effect
from hybridtable.effects.spec import RigScale
from hybridtable.errors import MeasurementError, ParameterError
from hybridtable.laws.spacecraft import INTEGRATORS
from hybridtable.limits import check_plausible
from hybridtable.measurement.rig import COMPUTER_PARAMS
from hybridtable.measurement.run_format import RunInfo
from hybridtable.measurement.run_reader import run_info_from_dict

__all__ = [
    "load_model",
    "model_from_json",
    "check_document",
    "provenance",
    "effect_from_json",
    "effects_from_json",
    "runs_from_json",
    "scale_from_json",
]


def model_from_json(data: Any, where: str) -> RigModel:
    """A model from its JSON document (``where`` names it in messages).

    Raises
    ------
    ParameterError
        One line naming ``where`` and the key at fault.
    """
    check_document(
        data,
        where,
        MODEL_FORMAT,
        ("nominal", "scale", "effects"),
        {
            MODEL6_FORMAT: "a model of a six-axis rig ({fmt}); it is for 6-DoF runs "
            "(compare RUNS6 --model) and simulate6 --model",
            "hybridtable-model/": "model format {fmt!r} is not supported "
            f"(this hybridtable {tool_version()} reads {MODEL_FORMAT!r})",
        },
    )
    nominal = _info(data["nominal"], f"{where}: nominal")
    scale = scale_from_json(data["scale"], where)
    effects = effects_from_json(data["effects"], scale, where)
    computer = _computer(data.get("computer", {}), f"{where}: computer")
    runs = []
    for i, raw in enumerate(runs_from_json(data, where)):
        w = f"{where}: runs[{i}]"
        cor = raw.get("cor_measured")
        if cor is not None and not (_finite(cor) and 0.0 <= float(cor) <= 100.0):
            raise ParameterError(
                f"{w}: cor_measured must be a number between 0 and 100 (a CoR), or null; "
                f"got {cor!r}"
            )
        runs.append(
            ModelRun(
                raw["run_id"],
                _info(raw.get("nominal"), f"{w}.nominal"),
                _computer(raw.get("computer", {}), f"{w}.computer"),
                None if cor is None else float(cor),
                raw.get("csv"),
                raw.get("sha256"),
            )
        )
    return RigModel(
        nominal=nominal,
        scale=scale,
        effects=effects,
        computer=computer,
        runs=tuple(runs),
        **provenance(data),
    )


# -- checks of the file's parts ------------------------------------------------
def provenance(data: dict) -> dict[str, Any]:
    """Where a model file came from, as its dataclass takes it: ``source``,
    ``evidence`` (an object, else empty), ``tool_version`` and ``created``."""
    evidence = data.get("evidence", {})
    return {
        "source": str(data.get("source", "user")),
        "evidence": evidence if isinstance(evidence, dict) else {},
        "tool_version": str(data.get("tool_version", "unknown")),
        "created": str(data.get("created", "")),
    }


def check_document(
    data: Any,
    where: str,
    expected: str,
    keys: tuple[str, ...],
    others: dict[str, str],
    kind: str = "model file",
) -> None:
    """``data`` is a ``kind`` of format ``expected`` holding ``keys``, else
    one line naming ``where``. ``others`` maps another kind's format (or a
    prefix of formats, ending in ``/``) to what to say of it (``{fmt}``: the
    format found)."""
    if not isinstance(data, dict):
        raise ParameterError(f"{where}: not a {kind} (a JSON object is expected)")
    fmt = data.get("format")
    if fmt != expected:
        for other, words in others.items():
            if isinstance(fmt, str) and (
                fmt == other or (other.endswith("/") and fmt.startswith(other))
            ):
                raise ParameterError(f"{where}: {words.format(fmt=fmt)}")
        raise ParameterError(
            f"{where}: not a {kind} (key format must be {expected!r}, got {json.dumps(fmt)})"
        )
    for key in keys:
        if key not in data:
            raise ParameterError(f"{where}: missing key {key}")


def _finite(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _info(raw: Any, where: str) -> RunInfo:
    try:
        return run_info_from_dict(raw, where)
    except MeasurementError as err:
        raise ParameterError(str(err)) from None


def scale_from_json(raw: Any, where: str) -> RigScale:
    """The model file's ``scale`` (every :class:`RigScale` field, each > 0)."""
    names = [f.name for f in fields(RigScale)]
    if not isinstance(raw, dict) or set(raw) != set(names):
        raise ParameterError(f"{where}: key scale must hold {', '.join(names)}")
    for k in names:
        if not (_finite(raw[k]) and raw[k] > 0):
            raise ParameterError(f"{where}: scale.{k} must be a number > 0 (got {raw[k]!r})")
    return RigScale(**{k: float(raw[k]) for k in names})


def _computer(raw: Any, where: str) -> dict[str, Any]:
    if not isinstance(raw, dict):
        raise ParameterError(f"{where}: must be an object")
    bad = [k for k in raw if k not in COMPUTER_PARAMS]
    if bad:
        raise ParameterError(
            f"{where}: {', '.join(bad)} not rig-computer parameters "
            f"(one of {', '.join(COMPUTER_PARAMS)})"
        )
    for k, v in raw.items():
        if k == "compensator":
            if not isinstance(v, str):
                raise ParameterError(f"{where}.compensator must be a string")
            try:
                check_choice("compensator", v, compensator_names())
            except ParameterError as err:
                raise ParameterError(f"{where}.{err}") from None
        elif k == "computer_integrator":
            if not isinstance(v, str):
                raise ParameterError(f"{where}.computer_integrator must be a string")
            try:
                check_choice("computer_integrator", v, tuple(INTEGRATORS))
            except ParameterError as err:
                raise ParameterError(f"{where}.{err}") from None
        elif not (_finite(v) and v >= 0):
            raise ParameterError(f"{where}.{k} must be a number >= 0 (got {v!r})")
        else:
            check_plausible(k, v, where=where)
    return dict(raw)


def effect_from_json(raw: Any, scale: RigScale, where: str) -> FittedEffect:
    """One of the model file's ``effects``: a registered effect, every
    parameter given once, within its bounds at ``scale``."""
    if not isinstance(raw, dict) or not isinstance(raw.get("name"), str):
        raise ParameterError(f"{where}: must be an object with a name")
    name = raw["name"]
    try:
        effect = get_effect(name)
    except ParameterError:
        raise ParameterError(
            f"{where}: effect {name!r} is not registered; load its plug-in with "
            "--plugin MODULE:ATTR or install the package that provides it"
        ) from None
    params = raw.get("parameters")
    if not isinstance(params, dict):
        raise ParameterError(f"{where} ({name}): key parameters must be an object")
    missing = [p for p in effect.parameter_names if p not in params]
    if missing:
        raise ParameterError(f"{where} ({name}): missing parameter(s) {', '.join(missing)}")
    values: dict[str, float] = {}
    std: dict[str, float | None] = {}
    fitted = []
    for key, item in params.items():
        if key not in effect.parameter_names:
            raise ParameterError(
                f"{where} ({name}): no parameter {key!r} "
                f"(its parameters: {', '.join(effect.parameter_names)})"
            )
        if not isinstance(item, dict) or not _finite(item.get("value")):
            raise ParameterError(f"{where} ({name}).{key}: needs a finite number as value")
        s = item.get("std")
        if s is not None and not (_finite(s) and s >= 0):
            raise ParameterError(f"{where} ({name}).{key}: std must be a number >= 0 or null")
        values[key] = float(item["value"])
        std[key] = None if s is None else float(s)
        if item.get("fitted"):
            fitted.append(key)
    try:
        effect.check_values(values, scale)
    except ParameterError as err:
        raise ParameterError(f"{where}: {err}") from None
    return FittedEffect(name, values, std, tuple(fitted))


def effects_from_json(raw: Any, scale: RigScale, where: str) -> tuple[FittedEffect, ...]:
    """The model file's ``effects`` (a list; each :func:`effect_from_json`,
    none twice), of a 1-D or a six-axis rig."""
    if not isinstance(raw, list):
        raise ParameterError(f"{where}: key effects must be a list")
    effects = tuple(
        effect_from_json(item, scale, f"{where}: effects[{i}]") for i, item in enumerate(raw)
    )
    names = [e.name for e in effects]
    if len(set(names)) != len(names):
        raise ParameterError(f"{where}: an effect is listed twice ({', '.join(names)})")
    return effects


def runs_from_json(data: dict, where: str) -> list[dict]:
    """The model file's ``runs`` (none: empty), each an object with a
    ``run_id``, of a 1-D or a six-axis rig."""
    raw = data.get("runs", [])
    if not isinstance(raw, list):
        raise ParameterError(f"{where}: key runs must be a list")
    for i, item in enumerate(raw):
        if not isinstance(item, dict) or not isinstance(item.get("run_id"), str):
            raise ParameterError(f"{where}: runs[{i}]: must be an object with a run_id")
    return raw


# -- files ---------------------------------------------------------------------
def load_model(path: str | Path) -> RigModel:
    """Read and check a model file.

    Raises
    ------
    ParameterError
        One line naming the file: unreadable, not JSON, not a model of this
        format version, an effect not registered, a value out of bounds.
    """
    return model_from_json(read_user_json(path, ParameterError), str(path))
