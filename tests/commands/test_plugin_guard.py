"""A plug-in's own code never hangs a command, prints a traceback or passes
for a model that does not fit: whatever it does (raise, ``sys.exit``, NaN),
the command says it in one line naming the plug-in, exit 2, or, for a system
that outputs NaN in a run, exit 1 at once (:mod:`hybridtable._plugins`)."""

from __future__ import annotations

import json
import textwrap
import time
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.effects import registry

ROOT = Path(__file__).resolve().parents[2]
NOMINAL = ROOT / "examples" / "nominal"
TABLE3 = ROOT / "examples" / "explain" / "table3_experiment.csv"

#: A plug-in file: effects whose code misbehaves in each way a user's can.
PLUGIN = textwrap.dedent(
    '''
    import math
    from pydrake.systems.framework import LeafSystem
    from hybridtable.effects.effect import Effect, EffectParameter, Signature

    def _parameter(upper=2.0):
        return EffectParameter("gain", "1", "a gain", lower=0.0,
                               upper=lambda s: upper, scale=lambda s: 0.1, null=1.0)

    class Sensor(LeafSystem):
        """A force sensor whose reading is ``how``: NaN, or a division by zero after 5 ms."""
        def __init__(self, how):
            super().__init__()
            self.DeclareVectorInputPort("force", 1)
            def out(context, output):
                if how == "nan":
                    output.SetFromVector([math.nan])
                    return
                if context.get_time() > 0.005:
                    1 / 0
                output.SetFromVector(self.get_input_port().Eval(context))
            self.DeclareVectorOutputPort("measured_force", 1, out)

    def _effect(name, apply, upper=2.0):
        return Effect(name=name, description=name, parameters=(_parameter(upper),),
                      signature=Signature(("f_mea_n",), ("compression",), name),
                      apply=apply, touches=(f"sensor.{name}",))

    def _raises(spec, values, scale):
        raise RuntimeError("boom in apply")

    RAISES = _effect("guard_raises", _raises)
    NAN_BOUND = _effect("guard_nan_bound", lambda spec, v, s: spec, upper=math.nan)
    NOT_A_SPEC = _effect("guard_not_a_spec", lambda spec, v, s: 42)
    NAN_SENSOR = _effect("guard_nan_sensor",
                         lambda spec, v, s: spec.wrap("sensor", lambda p, sensor: Sensor("nan")))
    DIVIDES = _effect("guard_divides",
                      lambda spec, v, s: spec.wrap("sensor", lambda p, sensor: Sensor("divide")))
    '''
)


@pytest.fixture
def plugin(tmp_path):
    path = tmp_path / "misbehaving.py"
    path.write_text(PLUGIN, encoding="utf-8")
    yield path
    for name in list(registry.EFFECTS):
        if name.startswith("guard_"):
            registry.unregister_effect(name)


def _one_line(capsys, argv: list[str], code: int) -> str:
    started = time.monotonic()
    assert main(argv) == code
    assert time.monotonic() - started < 120.0  # never a hang
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0].split("error: ", 1)[1]


def test_a_module_that_exits_or_raises_while_loading(tmp_path, capsys):
    exits = tmp_path / "exits.py"
    exits.write_text("import sys\nsys.exit(0)\n", encoding="utf-8")
    text = _one_line(capsys, ["effects", "--plugin", f"{exits}:EFFECT"], 2)
    assert "failed to load: called sys.exit(0)" in text
    raises = tmp_path / "raises.py"
    raises.write_text("x = 1\nraise KeyError('k')\n", encoding="utf-8")
    text = _one_line(capsys, ["effects", "--plugin", f"{raises}:EFFECT"], 2)
    assert "failed to load: raised KeyError" in text and f"{raises}, line 2" in text


@pytest.mark.parametrize(
    "attr, add, words",
    [
        ("RAISES", "guard_raises:gain=1", "apply raised RuntimeError: boom in apply"),
        ("NAN_BOUND", "guard_nan_bound:gain=1", "gain's upper returned nan, not a finite"),
        ("NOT_A_SPEC", "guard_not_a_spec:gain=1", "apply returned int, not a ModelSpec"),
    ],
)
def test_an_effects_function_that_fails_names_the_effect(plugin, capsys, attr, add, words):
    argv = ["simulate", "--plugin", f"{plugin}:{attr}", "--add", add]
    text = _one_line(capsys, [*argv, "--sample-rate-hz", "1000"], 2)
    name = add.split(":")[0]
    assert f"effect '{name}' (--plugin {plugin}:{attr})" in text and words in text


def test_a_system_that_raises_in_a_run_names_the_file_and_line(plugin, capsys):
    argv = ["simulate", "--plugin", f"{plugin}:DIVIDES", "--add", "guard_divides:gain=1"]
    text = _one_line(capsys, [*argv, "--sample-rate-hz", "1000"], 2)
    assert "a user's system raised ZeroDivisionError" in text and str(plugin) in text


def test_a_system_that_outputs_nan_stops_the_run_at_once(plugin, capsys):
    argv = ["simulate", "--plugin", f"{plugin}:NAN_SENSOR", "--add", "guard_nan_sensor:gain=1"]
    text = _one_line(capsys, [*argv, "--sample-rate-hz", "1000"], 1)
    assert "measured_force is not finite" in text


@pytest.mark.slow
def test_diagnose_and_explain_stop_on_a_failing_plugin(plugin, capsys):
    """A fit never takes the plug-in's failure for a model that does not fit."""
    argv = ["diagnose", str(NOMINAL), "--plugin", f"{plugin}:DIVIDES"]
    text = _one_line(capsys, [*argv, "--effects", "guard_divides", "--no-progress"], 2)
    assert "ZeroDivisionError" in text and str(plugin) in text
    argv = ["explain", str(TABLE3), "--plugin", f"{plugin}:RAISES"]
    text = _one_line(capsys, [*argv, "--effects", "guard_raises", "--no-progress"], 2)
    assert "apply raised RuntimeError" in text


#: A plug-in that registers compensators (docs/compensators.md) which misbehave.
COMPENSATORS = textwrap.dedent(
    '''
    import math
    from pydrake.systems.framework import LeafSystem
    from hybridtable.compensators.registry import register_compensator

    print("a plug-in that talks while it loads")

    class NanAfter(LeafSystem):
        """The measured force, then NaN from 20 ms on."""
        def __init__(self):
            super().__init__()
            self.DeclareVectorInputPort("measured_force", 1)
            self.DeclareVectorInputPort("measured_force_rate", 1)
            self.DeclareVectorInputPort("table_motion", 3)
            self.DeclareVectorInputPort("commanded_state", 2)
            def out(context, output):
                f = float(self.get_input_port(0).Eval(context)[0])
                output.SetFromVector([math.nan if context.get_time() > 0.02 else f])
            self.DeclareVectorOutputPort("compensated_force", 1, out)

    for name, factory in (("guard_nan", lambda p, h: NanAfter()),
                          ("guard_none", lambda p, h: None),
                          ("guard_raises", lambda p, h: 1 / 0)):
        register_compensator(name, factory, replace=True)
    '''
)


@pytest.fixture
def compensators(tmp_path, monkeypatch):
    """The compensators beside the effects of :data:`PLUGIN` (``--plugin FILE:RAISES``);
    the registry of compensators is restored after the test (a copy is patched in)."""
    from hybridtable.compensators import registry as compensator_registry

    monkeypatch.setattr(compensator_registry, "_REGISTRY", dict(compensator_registry._REGISTRY))
    path = tmp_path / "compensators.py"
    path.write_text(PLUGIN + COMPENSATORS, encoding="utf-8")
    yield path
    for name in list(registry.EFFECTS):
        if name.startswith("guard_"):
            registry.unregister_effect(name)


@pytest.mark.parametrize(
    "name, code, words",
    [
        ("guard_nan", 1, "is not finite"),
        ("guard_none", 2, "the factory of compensator 'guard_none' returned NoneType, not a Drake"),
        ("guard_raises", 2, "the factory of compensator 'guard_raises' raised ZeroDivisionError"),
    ],
)
def test_a_plugin_compensator_that_fails_is_one_line(compensators, capsys, name, code, words):
    argv = ["simulate", "--plugin", f"{compensators}:RAISES", "--compensator", name]
    text = _one_line(capsys, [*argv, "--initial-velocity-m-per-s", "0.2"], code)
    assert words in text


def test_a_plugins_print_leaves_json_on_stdout_alone(compensators, capsys):
    assert main(["effects", "--plugin", f"{compensators}:NAN_SENSOR", "--json", "-"]) == 0
    out, err = capsys.readouterr()
    json.loads(out)
    assert "a plug-in that talks" in err


def test_a_given_system_without_the_loops_ports_names_the_connection(tmp_path, capsys):
    path = tmp_path / "wrong.py"
    path.write_text(
        PLUGIN
        + textwrap.dedent(
            """
            class TwoWide(LeafSystem):
                def __init__(self):
                    super().__init__()
                    self.DeclareVectorInputPort("force", 1)
                    self.DeclareVectorOutputPort(
                        "measured_force", 2, lambda c, o: o.SetFromVector([0.0, 0.0]))

            WIDE = _effect("guard_wide",
                           lambda spec, v, s: spec.wrap("sensor", lambda p, sensor: TwoWide()))
            """
        ),
        encoding="utf-8",
    )
    argv = ["simulate", "--plugin", f"{path}:WIDE", "--add", "guard_wide:gain=1"]
    text = _one_line(capsys, [*argv, "--sample-rate-hz", "1000"], 2)
    assert "cannot wire the loop's force_sensor.measured_force to compensator" in text
    for name in list(registry.EFFECTS):
        if name.startswith("guard_"):
            registry.unregister_effect(name)
