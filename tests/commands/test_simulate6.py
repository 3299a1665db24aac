"""``hybridtable simulate6 SCENARIO.toml``: its JSON, its verdict, its refusals."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from hybridtable.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "six_dof"


def _scenario(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


BASE = (EXAMPLES / "on_axis.toml").read_text()


def test_on_axis_example_gives_the_1d_numbers_and_a_verdict(tmp_path, capsys):
    out = tmp_path / "r.json"
    plot = tmp_path / "w.png"
    argv = ["simulate6", str(EXAMPLES / "on_axis.toml"), "--compensator", "none"]
    assert main([*argv, "--json", str(out), "--plot", str(plot), "--no-progress"]) == 0
    text = capsys.readouterr().out.splitlines()
    assert text[0].startswith("none: the docking contact creates")
    doc = json.loads(out.read_text())
    for key in ("cor_normal", "energy_ratio", "peak_force_n", "peak_moment_n_m", "margins"):
        assert key in doc
    # The 1-D sampled loop at 1 kHz gives 1.15548 for this point.
    assert doc["cor_normal"] == pytest.approx(1.15548, abs=1e-4)
    assert doc["peak_moment_n_m"] < 1e-6  # on axis: no moment
    assert doc["reference"]["energy_ratio"] == pytest.approx(1.0, abs=1e-6)
    # Undamped contact, 5 ms delay, no compensation: the axial mode grows.
    assert doc["margins"]["stable"] is False
    assert plot.stat().st_size > 10_000
    # Outputs are not replaced without --force.
    assert main([*argv, "--json", str(out), "--no-progress"]) == 2
    assert "--force" in capsys.readouterr().err


def test_the_drogue_example_reads_and_a_miss_in_its_socket_is_captured(capsys, tmp_path):
    """The shipped probe-and-drogue scenario, on the ideal rig and 10 mm off
    the axis (straight into the socket: a few seconds, not a minute)."""
    text = (EXAMPLES / "drogue.toml").read_text()
    for old, new in (
        ("lateral_miss_m = [0.15, 0.0]", "lateral_miss_m = [0.01, 0.0]"),
        ("misalignment_deg = [0.0, 2.0]", "misalignment_deg = [0.0, 0.0]"),
        ("sensor_delay_s = 0.005", "sensor_delay_s = 0.0"),
        ("response_hz = 25.0", 'response_hz = "inf"'),
    ):
        assert old in text
        text = text.replace(old, new)
    scenario = tmp_path / "drogue.toml"
    scenario.write_text(text)
    argv = ["simulate6", str(scenario), "--compensator", "none", "--json", "-", "--no-reference"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["params"]["contact"]["geometry"] == "cone"
    assert doc["params"]["approach"]["lateral_miss_m"] == [0.01, 0.0]
    assert doc["metrics"]["captured"] is True
    assert 0.0 < doc["metrics"]["energy_ratio"] < 1.0  # the probe's dissipation


def test_json_to_stdout_is_only_json(capsys):
    argv = ["simulate6", str(EXAMPLES / "offset.toml"), "--json", "-", "--no-reference"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["compensator"] == "SDMDC"
    assert doc["peak_moment_n_m"] > 10.0  # off axis the force has a moment
    assert doc["reference"] is None and "reference null" in doc["note"]


@pytest.mark.parametrize(
    "change,words",
    [
        (
            ("inertia_kg_m2 = [1689.0, 1689.0, 1689.0]", "inertia_kg_m2 = [100.0, 100.0, 1000.0]"),
            "triangle inequality",
        ),
        (
            ("inertia_kg_m2 = [1689.0, 1689.0, 1689.0]", "inertia_kg_m2 = [1689.0, -5.0, 1689.0]"),
            "inertia_kg_m2 is unphysical",
        ),
        (
            (
                "inertia_kg_m2 = [1689.0, 1689.0, 1689.0]",
                "inertia_kg_m2 = [[1, 2, 0], [0, 1, 0], [0, 0, 1]]",
            ),
            "symmetric",
        ),
        (("sensor_delay_s = 0.005", "sensor_delay_s = -0.005"), "sensor_delay_s"),
        (("pad_count = 8", "pad_count = 2"), "pad_count"),
        (("pad_count = 8", "pad_counts = 8"), "unknown key 'pad_counts'"),
        (('name = "SDMDC"', 'name = "PID"'), "compensator must be one of"),
        (("response_hz = 25.0", 'response_hz = "fast"'), "response_hz must be a number"),
        (("misalignment_deg = [0.0, 0.0]", "misalignment_deg = [0.0, 45.0]"), "misalignment"),
        (("[rig]", "[rig\n"), "not valid TOML"),
        (
            ('stiffness_model = "linearized"', 'stiffness_model = "given"'),
            "needs compensator_stiffness_matrix",
        ),
        (
            ('stiffness_model = "linearized"', "stiffness_n_per_m = -1e5"),
            "compensator_stiffness_n_per_m",
        ),
    ],
)
def test_a_bad_scenario_gets_one_line_and_exit_2(tmp_path, capsys, change, words):
    path = _scenario(tmp_path, BASE.replace(*change))
    assert BASE.replace(*change) != BASE
    out = tmp_path / "r.json"
    assert main(["simulate6", str(path), "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert words in err[0] and str(path) in err[0]
    assert not out.exists()


def test_a_given_stiffness_matrix_is_used(tmp_path, capsys):
    """A given 6x6 K equal to the on-axis linearization gives the nominal MDC."""
    k = [[0.0] * 6 for _ in range(6)]
    k[5][2] = 1e5
    rows = ", ".join("[" + ", ".join(f"{v:g}" for v in row) + "]" for row in k)
    text = BASE.replace(
        'stiffness_model = "linearized"',
        f'stiffness_model = "given"\nstiffness_matrix = [{rows}]',
    ).replace('name = "SDMDC"', 'name = "MDC"')
    path = _scenario(tmp_path, text)
    assert main(["simulate6", str(path), "--json", "-", "--no-reference"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["cor_normal"] == pytest.approx(1.05022, abs=1e-4)  # the 1-D MDC


def test_sdmdc_online_finds_the_stiffness_the_scenario_gets_wrong(tmp_path, capsys):
    """The compensator believes 1.5e5 N/m, the contact is 1e5: sdmdc-online
    says what it identified, and the run matches the ideal rig."""
    text = BASE.replace('name = "SDMDC"', 'name = "sdmdc-online"\nstiffness_n_per_m = 1.5e5')
    path = _scenario(tmp_path, text)
    out = tmp_path / "r.json"
    assert main(["simulate6", str(path), "--json", str(out), "--no-progress"]) == 0
    text_out = capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["compensator"] == "sdmdc-online"
    assert doc["params"]["compensator_stiffness_n_per_m"] == 1.5e5
    assert doc["identified_stiffness_n_per_m"] == pytest.approx(1e5, rel=1e-3)
    assert "identified contact stiffness 1e+05 N/m" in text_out
    assert doc["energy_ratio"] == pytest.approx(doc["reference"]["energy_ratio"], abs=0.01)


def test_help_gives_the_plot_units(capsys):
    with pytest.raises(SystemExit):
        main(["simulate6", "--help"])
    text = capsys.readouterr().out
    assert re.search(r"--plot FILE.png .*\[N, N m\]", " ".join(text.split()))


STEWART = (EXAMPLES / "stewart.toml").read_text()


@pytest.mark.parametrize(
    "change,words",
    [
        (("misalignment_deg = [0.0, 2.0]", "misalignment_deg = [0.0, 25.0]"), "leg"),
        (("initial_gap_m = 0.001", "initial_gap_m = 0.4"), "Stewart"),
        (("reference_response_hz = 25.0", "reference_response_hz = 30.0"), "reference model"),
    ],
)
def test_a_stewart_scenario_out_of_reach_gets_one_line_and_exit_2(tmp_path, capsys, change, words):
    """A pose past a leg's stroke or joint limit, a start beyond the
    workspace, two responses for one table: refused before any simulation."""
    text = STEWART.replace(*change)
    assert text != STEWART
    path = _scenario(tmp_path, text)
    assert main(["simulate6", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


def test_the_verdict_says_when_the_compensator_pushes_harder_than_the_contact():
    """Energy alone can match the ideal rig while the compensator feeds the
    model lateral spikes (offset.toml with SDMDC: about 4.9 kN against a
    1.5 kN contact): the verdict says so, above 1.5 times the contact's peak."""
    from hybridtable.reports.six_dof import docking_verdict
    from hybridtable.six_dof.metrics import DockingMetrics

    def metrics(pushed_n: float) -> DockingMetrics:
        return DockingMetrics(1.0, 0.1, -0.1, 1.0, 0.0, 0.0, 1500.0, 0.0, 0.5, 0.0, pushed_n)

    ideal = metrics(1500.0)
    assert "but the compensator" not in docking_verdict("SDMDC", metrics(2200.0), ideal)
    words = docking_verdict("SDMDC", metrics(4861.0), ideal)
    assert (
        "matches the ideal rig" in words and "up to 4861 N, 3.2 times the contact's peak" in words
    )


def test_the_margins_are_of_the_rig_simulated(tmp_path, capsys):
    """With --add the margins are of the rig with the effect (an extra 2 ms
    of sensor delay grows the axial mode faster), and the JSON says whose."""
    argv = ["simulate6", str(EXAMPLES / "on_axis.toml"), "--compensator", "SDC"]
    docs = []
    for extra in ([], ["--add", "extra_delay:extra_delay_s=0.002"]):
        out = tmp_path / f"r{len(docs)}.json"
        assert main([*argv, *extra, "--json", str(out), "--no-progress", "--no-reference"]) == 0
        docs.append(json.loads(out.read_text()))
    nominal, added = (d["margins"] for d in docs)
    assert "rig" not in nominal and "--add" in added["rig"]
    assert added["max_growth_rate_per_s"] > nominal["max_growth_rate_per_s"] + 0.02
    assert docs[1]["cor_normal"] > docs[0]["cor_normal"]
