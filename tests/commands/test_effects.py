"""``hybridtable effects``: the registered effects with their parameters, units
and bounds, on the console and as JSON; plug-ins by ``--plugin`` and by entry
point; bad ``--plugin`` specs (one line, exit code 2).

The registry is reset to the built-ins for every test.
"""

from __future__ import annotations

import json
import math
import sys
import textwrap
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.effects import registry
from hybridtable.effects.library import BUILTIN_EFFECTS
from hybridtable.measurement.recorder import record_run, write_run
from hybridtable.measurement.run_format import RunInfo

BACKLASH = Path(__file__).resolve().parents[2] / "examples" / "plugins" / "backlash.py"
BUILTIN_NAMES = [e.name for e in BUILTIN_EFFECTS]
KEYS = {"name", "description", "parameters", "stage", "signature", "source", "bounds_at"}
PARAMETER_KEYS = {
    "name",
    "unit",
    "description",
    "lower",
    "upper",
    "typical",
    "null",
    "bounds_depend_on_rig",
}


@pytest.fixture(autouse=True)
def builtins_only(monkeypatch):
    """The registry with the built-ins only, entry points not loaded again."""
    monkeypatch.setattr(registry, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})
    monkeypatch.setattr(registry, "_entry_points_loaded", True)


def _json(capsys, *args: str) -> list[dict]:
    assert main(["effects", "--json", "-", *args]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    doc = json.loads(captured.out)  # nothing but the JSON on stdout
    # A document like every command's: what it was asked, then the effects.
    assert list(doc) == ["inputs", "registered", "effects"]
    assert doc["inputs"]["command"] == "effects"
    assert doc["registered"] == len(doc["effects"])
    return doc["effects"]


def _by_name(items: list[dict]) -> dict[str, dict]:
    return {e["name"]: e for e in items}


def test_console_opens_with_one_sentence_then_the_table(capsys):
    assert main(["effects"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    n = len(BUILTIN_EFFECTS)
    assert lines[0] == f"{n} effects registered ({n} built-in, 0 from plug-ins)."
    assert "the paper's Table 1 point" in lines[1] and "k = 1e+05 N/m" in lines[1]
    rows = {line.split()[0]: line for line in lines[2:] if line and not line.startswith(" ")}
    for e in BUILTIN_EFFECTS:
        assert rows[e.name].split()[1:3] == ["built-in", e.stage]
        assert e.description in rows[e.name]
        for p in e.parameters:
            row = next(line for line in lines if line.startswith(f"  {p.name} "))
            assert f" {p.unit} " in row
    # The critical damping at Table 1, 2 sqrt(k m), marked as rig-dependent.
    damping = next(line for line in lines if line.split()[:1] == ["damping_n_s_per_m"])
    assert "3.183e+04*" in damping


def test_json_is_a_list_of_effects_with_their_bounds_at_the_paper_point(capsys, tmp_path):
    items = _json(capsys)
    assert [e["name"] for e in items] == BUILTIN_NAMES
    for e in items:
        assert KEYS <= set(e) and e["source"] == "built-in"
        assert {"channels", "phases", "text"} <= set(e["signature"])
        assert e["bounds_at"]["rig"] == "the paper's Table 1 point"
        for p in e["parameters"]:
            assert PARAMETER_KEYS <= set(p)
            assert p["lower"] < p["upper"] and p["typical"] > 0.0
    by = _by_name(items)
    scale = by["contact_damping"]["bounds_at"]
    assert scale["stiffness_n_per_m"] == 1e5 and scale["sample_period_s"] == 1e-3
    assert scale["velocity_m_per_s"] == 0.1 and scale["table_frequency_hz"] == 25.0
    [damping] = by["contact_damping"]["parameters"]
    assert damping["unit"] == "N s/m" and damping["null"] == 0.0
    assert damping["upper"] == pytest.approx(2.0 * math.sqrt(1e5 * scale["mass_kg"]))
    assert damping["bounds_depend_on_rig"] is True
    [ratio] = by["mass_error"]["parameters"]
    assert (ratio["lower"], ratio["upper"], ratio["bounds_depend_on_rig"]) == (0.5, 2.0, False)
    assert by["mass_error"]["stage"] == "closed_loop"
    assert by["table_resonance"]["parameters"][0]["null"] is None  # a mode has no null value
    # --json FILE: the same list, and the console too.
    out = tmp_path / "effects.json"
    assert main(["effects", "--json", str(out)]) == 0
    assert json.loads(out.read_text(encoding="utf-8"))["effects"] == items
    assert capsys.readouterr().out.startswith(f"{len(BUILTIN_EFFECTS)} effects registered")


def test_a_plugin_is_listed_with_its_source(capsys):
    items = _json(capsys, "--plugin", f"{BACKLASH}:EFFECT")
    assert [e["name"] for e in items] == [*BUILTIN_NAMES, "backlash"]
    backlash = items[-1]
    assert backlash["source"] == "plug-in" and backlash["stage"] == "replay"
    [b] = backlash["parameters"]
    assert (b["name"], b["unit"], b["lower"], b["null"]) == ("backlash_m", "m", 0.0, 0.0)
    assert b["bounds_depend_on_rig"] is True
    assert b["upper"] == pytest.approx(0.5 * backlash["bounds_at"]["peak_deflection_m"])
    assert main(["effects", "--plugin", f"{BACKLASH}:EFFECT"]) == 0
    lines = capsys.readouterr().out.splitlines()
    n = len(BUILTIN_EFFECTS)
    assert lines[0] == f"{n + 1} effects registered ({n} built-in, 1 from plug-ins: 1 by --plugin)."
    assert any(line.split()[:3] == ["backlash", "plug-in", "replay"] for line in lines)


def test_an_entry_point_is_listed_with_its_source(capsys, tmp_path, monkeypatch):
    module = "ht_effects_cmd_plugin"
    (tmp_path / f"{module}.py").write_text(
        "from dataclasses import replace\n"
        "from hybridtable.effects.library.force_bias import EFFECT as _BIAS\n"
        "OFFSET = replace(_BIAS, name='demo_offset', touches=('demo.offset',))\n",
        encoding="utf-8",
    )
    dist = tmp_path / f"{module}-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: ht-effects-cmd-plugin\nVersion: 0.1\n", encoding="utf-8"
    )
    (dist / "entry_points.txt").write_text(
        textwrap.dedent(
            f"""\
            [hybridtable.effects]
            demo_offset = {module}:OFFSET
            """
        ),
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, module, raising=False)
    monkeypatch.setattr(registry, "_entry_points_loaded", False)
    try:
        items = _json(capsys, "--plugin", f"{BACKLASH}:EFFECT")
        sources = {e["name"]: e["source"] for e in items}
        assert sources["demo_offset"] == "entry point" and sources["backlash"] == "plug-in"
        monkeypatch.setattr(registry, "EFFECTS", {e.name: e for e in BUILTIN_EFFECTS})
        monkeypatch.setattr(registry, "_entry_points_loaded", False)
        assert main(["effects"]) == 0
        first = capsys.readouterr().out.splitlines()[0]
        n = len(BUILTIN_EFFECTS)
        assert first == (
            f"{n + 1} effects registered ({n} built-in, 1 from plug-ins: 1 from entry points)."
        )
    finally:
        sys.modules.pop(module, None)


def test_rig_evaluates_the_bounds_at_a_recorded_run(capsys, tmp_path):
    info = RunInfo(
        run_id="rig-run1",
        sample_rate_hz=500.0,
        spacecraft_mass_kg=300.0,
        contact_stiffness_n_per_m=3e4,
        sensor_delay_s=0.004,
        table_natural_frequency_hz=20.0,
        table_damping_ratio=0.7,
        compensator="none",
        lead_time_s=0.004,
        initial_gap_m=0.002,
        initial_velocity_m_per_s=0.05,
        force_deadband_n=1.0,
    )
    run, _ = record_run(info)
    write_run(run, tmp_path, "run1")
    items = _json(capsys, "--rig", str(tmp_path / "run1.json"))
    scale = items[0]["bounds_at"]
    assert "rig-run1" in scale["rig"]
    assert scale["stiffness_n_per_m"] == 3e4 and scale["mass_kg"] == 300.0
    assert scale["sample_period_s"] == pytest.approx(2e-3) and scale["velocity_m_per_s"] == 0.05
    [damping] = _by_name(items)["contact_damping"]["parameters"]
    assert damping["upper"] == pytest.approx(2.0 * math.sqrt(3e4 * 300.0))
    [mode_f, _] = _by_name(items)["table_resonance"]["parameters"]
    assert (mode_f["lower"], mode_f["upper"]) == pytest.approx((10.0, 225.0))
    assert main(["effects", "--rig", str(tmp_path)]) == 0  # a folder too
    assert "the rig of" in capsys.readouterr().out.splitlines()[1]


def _error(capsys, *args: str) -> str:
    assert main(["effects", *args]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("hybridtable effects: error: ")
    return lines[0]


def test_bad_plugins_give_one_line_and_exit_code_2(capsys, tmp_path):
    missing = tmp_path / "missing.py"
    assert "no such file" in _error(capsys, "--plugin", f"{missing}:EFFECT")
    assert "has no attribute 'NOPE'" in _error(capsys, "--plugin", f"{BACKLASH}:NOPE")
    number = tmp_path / "number.py"
    number.write_text("X = 3\n", encoding="utf-8")
    assert "X is not an Effect" in _error(capsys, "--plugin", f"{number}:X")
    clash = tmp_path / "clash.py"
    clash.write_text(
        "from dataclasses import replace\n"
        "from hybridtable.effects.library.contact_damping import EFFECT as _DAMPING\n"
        "EFFECT = replace(_DAMPING, description='my own damping')\n",
        encoding="utf-8",
    )
    line = _error(capsys, "--plugin", f"{clash}:EFFECT")
    assert "'contact_damping' is already registered" in line
    assert registry.get_effect("contact_damping") is BUILTIN_EFFECTS[0]  # still the built-in
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('boom')\n", encoding="utf-8")
    assert "failed to load" in _error(capsys, "--plugin", f"{broken}:EFFECT")
    assert "expected MODULE:ATTR" in _error(capsys, "--plugin", "no_colon")
    assert "no such file or folder" in _error(capsys, "--rig", str(tmp_path / "none"))


def test_help_names_the_default_rig(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["effects", "--help"])
    assert exit_.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "Table 1 point" in text and "--plugin" in text and "--rig RUN" in text
