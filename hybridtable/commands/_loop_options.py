"""The loop options of ``hybridtable simulate`` (defaults: the paper's Table 1
point), and the loop parameters they make.

The parser's defaults are ``None`` so that an option given on the command
line can be told from its default: a model's or a recording's own values fill
the options not given (:func:`given_loop_options`, :func:`loop_value`).
"""

from __future__ import annotations

import argparse

from hybridtable.limits import LIMITS, TABLE1_DEFAULTS

__all__ = [
    "LOOP_OPTIONS",
    "add_loop_option",
    "add_loop_arguments",
    "given_loop_options",
    "loop_value",
    "params_from_args",
]


#: What each loop option is, in words (its unit and range are those of
#: :data:`hybridtable.limits.LIMITS`; ``(default ...)`` words a derived default).
_WORDS: dict[str, str] = {
    "sensor_delay_s": "force-sensor delay",
    "table_response_hz": "table response frequency (inf: ideal table)",
    "table_damping_ratio": "table damping ratio",
    "contact_frequency_hz": "contact natural frequency sqrt(k/m)/2pi (sets the mass)",
    "contact_stiffness_n_per_m": "contact stiffness k",
    "contact_damping_n_s_per_m": "contact damping",
    "initial_velocity_m_per_s": "approach velocity",
    "initial_gap_m": "gap at t = 0",
    "lead_time_s": "SDC lead time (default: the sensor delay)",
    "compensator_stiffness_n_per_m": "stiffness the compensator believes (MDC, SDMDC, smith) "
    "or starts from (sdmdc-online's prior) (default: the true one)",
    "force_deadband_n": "readings at or below this are no contact",
    "sample_rate_hz": "sampled rig computer (default: continuous)",
    "time_step_s": "continuous-mode step (default: min(2e-4, 1/(5000 f_con)))",
}

#: The defaults of the options off the Table 1 point: those of
#: :class:`~hybridtable.loop.params.HybridLoopParams` (``None``: derived), which
#: a test holds them to (imported lazily, ``--help`` imports no Drake).
_LOOP_DEFAULTS: dict[str, float | None] = {
    "contact_damping_n_s_per_m": 0.0,
    "initial_gap_m": 0.001,
    "lead_time_s": None,
    "compensator_stiffness_n_per_m": None,
    "force_deadband_n": 0.0,
    "sample_rate_hz": None,
    "time_step_s": None,
}

#: The loop options: name -> (default, unit, help): the default from the Table 1
#: point (:data:`hybridtable.limits.TABLE1_DEFAULTS`) or the loop's, the unit
#: from :data:`hybridtable.limits.LIMITS`. The parser's defaults are ``None``
#: so that an option given on the command line can be told from its default (a
#: model's or a recording's own values fill the options not given).
LOOP_OPTIONS: dict[str, tuple[object, str, str]] = {
    name: ({**TABLE1_DEFAULTS, **_LOOP_DEFAULTS}[name], LIMITS[name].unit, words)
    for name, words in _WORDS.items()
}


#: Loop quantities some commands take besides :data:`LOOP_OPTIONS` (same shape).
EXTRA_OPTIONS: dict[str, tuple[object, str, str]] = {
    "contact_damping_ratio": (
        0.0,
        LIMITS["contact_damping_ratio"].unit,
        "contact damping as a ratio c / (2 sqrt(k m))",
    ),
}


def add_loop_option(
    parser, name: str, note: str = "", words: str | None = None, default: object = None
) -> None:
    """Add the flag of the loop quantity ``name`` to ``parser`` (a parser or a
    group): its unit, plausible range (:data:`hybridtable.limits.LIMITS`) and
    default from one place (:data:`LOOP_OPTIONS`), so no command re-types them.

    Parameters
    ----------
    note : str
        Words appended inside the default's parentheses (e.g. ``"; with
        --model: the model's"``).
    words : str, optional
        What the quantity is, in the command's words (default: the table's).
    default : float, optional
        The command's own default, shown in the help (default: the table's).
    """
    from hybridtable.commands._common import UNIT_METAVARS, number_type, range_words

    standard, unit, text = {**LOOP_OPTIONS, **EXTRA_OPTIONS}[name]
    what, _, derived = text.partition(" (default")
    if default is not None:
        shown = f" (default {default:g}{note})"
    elif derived:
        shown = f" (default{derived[:-1]}{note})"
    else:
        shown = f" (default {standard:g}{note})"
    parser.add_argument(
        "--" + name.replace("_", "-"),
        type=number_type(name, unit),
        metavar=UNIT_METAVARS[unit],
        default=None,
        help=f"{words or what} [{unit}], {range_words(name)}{shown}",
    )


def add_loop_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by the commands that set up one loop (defaults: Table 1)."""
    from hybridtable.compensators.registry import compensator_names

    g = parser.add_argument_group("loop parameters (defaults: the paper's Table 1 point)")
    g.add_argument(
        "--scenario",
        metavar="FILE.toml",
        help="the rig from a scenario file: simulate6's sections [spacecraft], [contact], "
        "[approach], [rig], [table], [compensator] (docs/six_dof.md, 'A scenario file'; "
        "e.g. examples/scenarios/table1_sdmdc.toml); the loop options given override it",
    )
    g.add_argument(
        "--compensator",
        default=None,
        metavar="NAME",
        help=f"one of {', '.join(compensator_names())} (default none)",
    )
    for name in LOOP_OPTIONS:
        add_loop_option(g, name)
    g.add_argument(
        "--passivity",
        action="store_true",
        help="guard the compensator with the time-domain passivity observer/controller",
    )
    g.add_argument("--clamp-nonnegative", action="store_true", help="clamp f_comp at zero")


def given_loop_options(args: argparse.Namespace) -> list[str]:
    """The loop options given on the command line (flag names)."""
    names = ["compensator", *LOOP_OPTIONS]
    given = ["--" + n.replace("_", "-") for n in names if getattr(args, n, None) is not None]
    for flag in ("passivity", "clamp_nonnegative"):
        if getattr(args, flag, False):
            given.append("--" + flag.replace("_", "-"))
    return given


def loop_value(args: argparse.Namespace, name: str):
    """A loop option's value: given, else its default."""
    value = getattr(args, name, None)
    if value is None:
        return "none" if name == "compensator" else LOOP_OPTIONS[name][0]
    return value


def params_from_args(args: argparse.Namespace):
    """HybridLoopParams from the options of :func:`add_loop_arguments`: the
    ``--scenario`` file's rig, or the Table 1 point, with the options given."""
    from hybridtable.studies.paper import paper_params

    if getattr(args, "scenario", None) is not None:
        return _scenario_params(args)
    v = {n: loop_value(args, n) for n in ("compensator", *LOOP_OPTIONS)}
    return paper_params(
        **v,
        clamp_nonnegative=args.clamp_nonnegative,
        passivity=getattr(args, "passivity", False),
    )


def _scenario_params(args: argparse.Namespace):
    """The ``--scenario`` file's loop with the loop options given on the command
    line (a given ``--contact-frequency-hz`` sets the mass with the stiffness)."""
    from hybridtable.errors import CommandError, ParameterError
    from hybridtable.laws.contact import mass_for_contact_frequency_kg
    from hybridtable.loop.scenario import load_loop_scenario

    try:
        params = load_loop_scenario(args.scenario)
        given = {n: getattr(args, n) for n in ("compensator", *LOOP_OPTIONS)}
        given = {n: v for n, v in given.items() if v is not None}
        given |= {f: True for f in ("clamp_nonnegative", "passivity") if getattr(args, f, False)}
        frequency = given.pop("contact_frequency_hz", None)
        params = params.with_(**given)
        if frequency is not None:
            k = params.contact_stiffness_n_per_m
            mass = mass_for_contact_frequency_kg(k, frequency)
            params = params.with_(spacecraft_mass_kg=mass)
    except ParameterError as err:
        raise CommandError(f"--scenario: {err}") from None
    return params
