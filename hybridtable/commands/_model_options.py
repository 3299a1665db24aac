"""The effect and model options the commands share: ``--plugin``, ``--add``,
``--model``, ``--save-model`` and ``--force``, and what they load.

``--plugin MODULE:ATTR`` (repeatable) registers a user's effect(s) from a
module or a ``.py`` file before anything else reads the registry; installed
packages register theirs through the entry-point group
``hybridtable.effects`` without a flag. ``--add EFFECT[:param=value,...]``
(repeatable) adds effects; ``--model FILE`` reads a model file
(``hybridtable-model/1``, :mod:`hybridtable.effects.model_file`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from hybridtable.errors import CommandError

__all__ = [
    "add_plugin_argument",
    "add_effect_argument",
    "add_model_argument",
    "add_save_model_arguments",
    "load_plugins",
    "parse_added",
    "parse_added_given",
    "load_model_arg",
    "check_model_output",
    "write_model",
]


def add_plugin_argument(parser: argparse.ArgumentParser) -> None:
    """``--plugin MODULE:ATTR`` (repeatable)."""
    parser.add_argument(
        "--plugin",
        metavar="MODULE:ATTR",
        action="append",
        default=[],
        help="register the effect (or list of effects) ATTR of a module or a .py file "
        "not installed as a package, e.g. --plugin ./backlash.py:EFFECT (repeatable; "
        "default: none); installed packages register theirs through the entry-point group "
        "hybridtable.effects",
    )


def add_effect_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--add EFFECT[:param=value,...]`` (repeatable); ``what`` ends the help."""
    parser.add_argument(
        "--add",
        metavar="EFFECT[:param=value,...]",
        action="append",
        default=[],
        help="add a physical effect (hybridtable effects lists them, with their "
        f"parameters and units; repeatable){what}",
    )


def add_model_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--model FILE``; ``what`` says what the command does with it."""
    parser.add_argument(
        "--model",
        metavar="FILE.json",
        help=f"a model file written by diagnose --save-model or compare --save-model: {what}",
    )


def add_save_model_arguments(parser: argparse.ArgumentParser) -> None:
    """``--save-model FILE`` (replaced only with the command's ``--force``)."""
    parser.add_argument(
        "--save-model",
        metavar="FILE.json",
        help="write the model (nominal parameters, effects with fitted values and "
        "standard errors, the runs, the tool version) for simulate/margins/"
        "compensators/compare --model",
    )


def load_plugins(args: argparse.Namespace) -> None:
    """Register the effects of every ``--plugin`` (before any effect is named)."""
    from hybridtable.effects.registry import load_plugin

    for text in getattr(args, "plugin", None) or ():
        load_plugin(text)


def parse_added(args: argparse.Namespace):
    """The ``--add`` effects as ``[(Effect, given values), ...]`` (checked)."""
    from hybridtable.effects.registry import parse_effect_specs

    return parse_effect_specs(getattr(args, "add", None) or ())


def parse_added_given(args: argparse.Namespace, why: str):
    """The ``--add`` effects (:func:`parse_added`), each with every parameter
    given (``why``: the words after the refusal's list, e.g. "(nothing to fit
    it to here)")."""
    added = parse_added(args)
    for effect, values in added:
        missing = [p for p in effect.parameter_names if p not in values]
        if missing:
            raise CommandError(
                f"--add {effect.name}: give {', '.join(f'{p}=...' for p in missing)} {why}"
            )
    return added


def load_model_arg(args: argparse.Namespace):
    """The :class:`~hybridtable.effects.model_file.RigModel` of ``--model`` (or None)."""
    if not getattr(args, "model", None):
        return None
    from hybridtable.effects.model_reader import load_model

    return load_model(args.model)


def check_model_output(path: str | None, force: bool, inputs=()) -> None:
    """Refuse a ``--save-model`` path that exists (without ``--force``), is a
    folder, or is an input."""
    if not path:
        return
    target = Path(path).resolve()
    if target in set(inputs):
        raise CommandError(f"--save-model {path} is one of the input files; not writing over it")
    if target.is_dir():
        raise CommandError(f"--save-model {path} is a folder")
    if target.exists() and not force:
        raise CommandError(f"--save-model {path} exists; give --force to replace it")


def write_model(path: str, model) -> None:
    """Write a model file atomically."""
    from hybridtable.commands._common import write_json

    write_json(path, model.to_json())
