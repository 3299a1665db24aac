"""The worked example of a user's own effect, ``examples/plugins/backlash.py``
(docs/plugins.md): its physics, and diagnose finding it when it comes in as a
``--plugin`` file, through a REAL entry point, and on the command line.

The runs are recorded with the Python API (``record_run``/``write_run``) on
the rig of the shipped examples (k = 60 kN/m, m = 675 kg, 4 ms, 30 Hz table,
1 kHz computer), with noise, at three velocities, with and without a
compensator. The registry is reset to the built-ins for every test.
"""

from __future__ import annotations

import ast
import functools
import importlib.util
import json
import sys
import textwrap
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from hybridtable.diagnosis.diagnose import diagnose
from hybridtable.diagnosis.fit import fit_effect
from hybridtable.effects import registry
from hybridtable.effects.library import BUILTIN_EFFECTS
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import ParameterError
from hybridtable.measurement.recorder import record_run, write_run
from hybridtable.measurement.replay import replay
from hybridtable.measurement.rig import RigPhysics, add_physical_part, rig_params
from hybridtable.measurement.run_reader import read_runs
from hybridtable.systems.noise import MeasurementNoiseParams
from hybridtable.systems.table import SecondOrderTable
from tests.examples import example_info

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "plugins"
BACKLASH = EXAMPLE / "backlash.py"
#: The plug-in as a user gives it: ``--plugin path/to/backlash.py:EFFECT``.
PLUGIN = f"{BACKLASH}:EFFECT"

#: The rig of ``examples/nominal`` (its run1.json).
INFO = example_info(run_id="backlash-run1")
#: (approach velocity m/s, compensator) of the three recorded runs.
PLAN = ((0.06, "none"), (0.08, "SDMDC"), (0.10, "none"))
SCALE = RigScale(60000.0, 675.475, 1e-3, 0.004, 0.10, 30.0)
#: The hidden backlash, m: 0.2 mm, about 2 % of the peak deflection (10.6 mm).
TRUE_B = 2e-4


@functools.cache
def _example():
    """The example module, imported privately (registers nothing)."""
    spec = importlib.util.spec_from_file_location("ht_backlash_example_under_test", BACKLASH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _physics(b: float):
    return _example().EFFECT.apply(ModelSpec(), {"backlash_m": b}, SCALE).physics()


@pytest.fixture(autouse=True)
def builtins_only(monkeypatch):
    """The registry with the built-ins only, entry points not loaded again."""
    monkeypatch.setattr(registry, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})
    monkeypatch.setattr(registry, "_entry_points_loaded", True)
    monkeypatch.setattr(registry, "_ENTRY_POINT_FILES", {})


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """Three noisy runs with the backlash hidden, written as hybridtable-run/1."""
    out = tmp_path_factory.mktemp("backlash_runs")
    force_std = 2e-3 * SCALE.peak_force_n
    for i, (v, compensator) in enumerate(PLAN, start=1):
        info = replace(
            INFO,
            run_id=f"backlash-run{i}",
            initial_velocity_m_per_s=v,
            compensator=compensator,
            force_deadband_n=5.0 * force_std,
        )
        noise = MeasurementNoiseParams(
            force_std_n=force_std, position_std_m=1e-4 * SCALE.peak_deflection_m, seed=40 + i
        )
        run, _ = record_run(info, _physics(TRUE_B), noise)
        write_run(run, out, f"run{i}")
    return out


@pytest.fixture(scope="module")
def runs(folder):
    return read_runs([folder])


# -- the physics -----------------------------------------------------------------
def test_no_backlash_is_exactly_the_nominal_table():
    # The nominal table as a factory keeps the closed loop on the diagram, as the
    # wrapped one is (the nominal systems alone run on the fast engine).
    on_diagram = RigPhysics(table=lambda p: SecondOrderTable(p.plant.table))
    nominal, _ = record_run(INFO, on_diagram)
    wrapped, _ = record_run(INFO, _physics(0.0))  # the closed loop
    for c in ("p_act_m", "f_mea_n", "f_comp_n", "v_des_m_per_s"):
        np.testing.assert_array_equal(getattr(wrapped, c), getattr(nominal, c))
    a, b = replay(nominal), replay(nominal, _physics(0.0))
    for c in ("p_act_m", "v_act_m_per_s", "f_act_n", "f_mea_n"):
        np.testing.assert_array_equal(getattr(b, c), getattr(a, c))


def test_backlash_leaves_the_force_and_lags_the_table_by_b_after_the_contact():
    run, _ = record_run(INFO)
    x, y = replay(run), replay(run, _physics(TRUE_B))
    # The contact pushes the device onto the drive's forward face: same force.
    np.testing.assert_array_equal(y.f_act_n, x.f_act_n)
    np.testing.assert_array_equal(y.f_mea_n, x.f_mea_n)
    last = np.flatnonzero(x.p_act_m > 0.0)[-1]  # the last tick in contact
    np.testing.assert_array_equal(y.p_act_m[: last + 1], x.p_act_m[: last + 1])
    # After it, the device rests at the contact surface until the rear face,
    # b behind, catches it; then it lags the retreating drive by b.
    after = slice(last + 1, None)
    expected = np.maximum(x.p_act_m[after], np.minimum(0.0, x.p_act_m[after] + TRUE_B))
    np.testing.assert_allclose(y.p_act_m[after], expected, rtol=0.0, atol=1e-15)
    stuck = y.p_act_m[after] == 0.0
    # b / v_out = 0.2 mm / 0.094 m/s = 2.1 ms: two ticks at rest.
    assert stuck.sum() == np.count_nonzero(x.p_act_m[after] + TRUE_B > 0.0) == 2
    assert np.all(y.v_act_m_per_s[after][stuck] == 0.0)
    np.testing.assert_allclose(y.p_act_m[-50:] - x.p_act_m[-50:], TRUE_B, rtol=1e-9)
    np.testing.assert_array_equal(y.v_act_m_per_s[-50:], x.v_act_m_per_s[-50:])


def test_the_replay_steps_the_wrapped_table_exactly_and_reproduces_the_closed_loop():
    params = rig_params(INFO)
    part = add_physical_part(DiagramBuilder(), params, _physics(TRUE_B), 1e-3)
    assert part.table_is_sampled  # BacklashTable.sampled(h) kept the replay exact
    run, _ = record_run(INFO, _physics(TRUE_B))  # continuous table, noise-free
    # The wrapper's set_initial_state reached the drive: the record starts at
    # the gap, moving (a wrapper without it would start the table at rest at 0).
    assert run.p_act_m[0] == pytest.approx(-INFO.initial_gap_m, abs=1e-9)
    rep = replay(run, _physics(TRUE_B))
    np.testing.assert_allclose(rep.p_act_m, run.p_act_m, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(rep.f_mea_n, run.f_mea_n, rtol=0.0, atol=1e-4)
    assert (run.p_act_m - replay(run).p_act_m)[-1] == pytest.approx(TRUE_B, rel=1e-6)


def test_the_stated_law_replays_without_a_simulator_bit_for_bit(monkeypatch):
    """BacklashTable states ``respond`` (its sampled form's motion at the ticks):
    the replay evaluates it instead of simulating, to the diagram's last bit; a
    subclass that only inherits it replays on the diagram."""
    from hybridtable.measurement import replay as replay_module

    run, _ = record_run(INFO, _physics(TRUE_B))
    params = rig_params(INFO)
    laws = replay_module._law_replay(params, _physics(TRUE_B), run.p_des_m, run.v_des_m_per_s)
    assert laws is not None and laws.steps == 0
    with monkeypatch.context() as m:
        m.setattr(replay_module, "_law_replay", lambda *args: None)
        diagram = replay(run, _physics(TRUE_B))
    assert diagram.steps > 0
    for c in ("p_act_m", "v_act_m_per_s", "f_act_n", "f_mea_n"):
        np.testing.assert_array_equal(getattr(laws, c), getattr(diagram, c))
    assert np.max(run.p_act_m - replay(run).p_act_m) == pytest.approx(TRUE_B, rel=1e-6)

    table = _example().BacklashTable

    class Inherits(table):  # states nothing itself
        def sampled(self, period_s):
            return Inherits(self.inner.sampled(period_s), self.stage.width_m, period_s)

    inherits = ModelSpec().wrap("table", lambda p, t: Inherits(t, TRUE_B, 1e-3)).physics()
    assert replay_module._law_replay(params, inherits, run.p_des_m, run.v_des_m_per_s) is None


# -- diagnose finds it -----------------------------------------------------------
def _check_found(runs) -> None:
    """Listed, a default candidate, fitted, and named by diagnose with it.

    Against every built-in candidate it is chosen on the command line
    (:func:`test_diagnose_on_the_command_line_names_the_plugin`); here, where
    only the way it is registered differs, diagnose is given it alone (7 s
    instead of 30 s a test)."""
    assert "backlash" in registry.effect_names()
    assert "backlash" in registry.default_effects("diagnose")
    fitted = fit_effect(runs, "backlash")["backlash_m"]
    assert fitted == pytest.approx(TRUE_B, rel=0.02)
    d = diagnose(runs, effects=["backlash"])
    assert "backlash" in d.verdict.split(" + ")
    value = d.selected_values["backlash"]["backlash_m"]
    std = d.selected_std["backlash"]["backlash_m"]
    assert std is not None and abs(value - TRUE_B) <= max(4.0 * std, 1e-3 * TRUE_B)
    assert d.staircase[-1]["heldout_error"] < 1.1


def test_a_plugin_file_is_found_by_diagnose(runs):
    [effect] = registry.load_plugin(PLUGIN)
    assert effect.name == "backlash" and registry.get_effect("backlash") is effect
    assert effect.parameter("backlash_m").unit == "m"
    _check_found(runs)


def test_a_real_entry_point_is_found_by_diagnose(runs, tmp_path, monkeypatch):
    # The package of examples/plugins/pyproject.toml, "installed": its module
    # and a dist-info with the entry points the pyproject declares.
    project = tomllib.loads((EXAMPLE / "pyproject.toml").read_text(encoding="utf-8"))
    declared = project["project"]["entry-points"][registry.ENTRY_POINT_GROUP]
    assert declared == {"backlash": "backlash:EFFECT"}
    module = "ht_backlash_ep"  # the module renamed, so that no other test's import is reused
    (tmp_path / f"{module}.py").write_text(BACKLASH.read_text(encoding="utf-8"), encoding="utf-8")
    dist = tmp_path / f"{module}-0.1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: ht-backlash-ep\nVersion: 0.1.0\n", encoding="utf-8"
    )
    (dist / "entry_points.txt").write_text(
        textwrap.dedent(
            f"""\
            [{registry.ENTRY_POINT_GROUP}]
            backlash = {module}:EFFECT
            """
        ),
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, module, raising=False)
    monkeypatch.setattr(registry, "_entry_points_loaded", False)
    try:
        assert "backlash" in registry.effect_names()
        assert registry.user_effect("backlash") is sys.modules[module].EFFECT
        # The file it was installed from, given again with --plugin: the same code,
        # registered once (a user following docs/plugins.md after pip install).
        registry.load_plugin(f"{BACKLASH}:EFFECT")
        assert registry.user_effect("backlash") is sys.modules[module].EFFECT
        other = tmp_path / "other_backlash.py"
        other.write_text(BACKLASH.read_text(encoding="utf-8") + "\n# changed\n", encoding="utf-8")
        with pytest.raises(ParameterError, match="already registered"):
            registry.load_plugin(f"{other}:EFFECT")  # another code under the same name
        _check_found(runs)
    finally:
        sys.modules.pop(module, None)


def test_diagnose_on_the_command_line_names_the_plugin(folder, tmp_path, capsys):
    from hybridtable.cli import main

    out = tmp_path / "diagnosis.json"
    code = main(["diagnose", str(folder), "--plugin", PLUGIN, "--json", str(out), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["verdict"] == "backlash"  # among every built-in candidate
    assert "backlash" in capsys.readouterr().out.splitlines()[0]
    value = data["parameters"]["backlash"]["backlash_m"]
    std = data["parameter_std"]["backlash"]["backlash_m"]
    assert std is not None and abs(value - TRUE_B) <= max(4.0 * std, 1e-3 * TRUE_B)
    assert data["staircase"][-1]["heldout_error"] < 1.1


def test_the_code_in_the_doc_is_the_example_file():
    doc = (EXAMPLE.parents[1] / "docs" / "plugins.md").read_text(encoding="utf-8")
    block = doc.split("after its docstring):\n\n```python\n", 1)[1].split("\n```\n", 1)[0]
    source = BACKLASH.read_text(encoding="utf-8")
    end = ast.parse(source).body[0].end_lineno  # the module docstring's last line
    code = "\n".join(source.splitlines()[end:]).strip("\n")
    assert block.strip("\n") == code
