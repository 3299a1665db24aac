"""``hybridtable simulate`` with a plug-in compensator, a prior stiffness and the
passivity guard.
"""

from __future__ import annotations


def test_simulate_command_takes_a_plugin_the_prior_stiffness_and_passivity(tmp_path, capsys):
    import json

    from hybridtable.cli import main

    out = tmp_path / "run.json"
    argv = ["simulate", "--compensator", "smith", "--compensator-stiffness-n-per-m", "5e4"]
    assert main([*argv, "--json", str(out)]) == 0
    assert json.loads(out.read_text())["cor"] > 1.05  # the model stiffness is half the true one
    assert main([*argv, "--passivity", "--json", str(out)]) == 2  # exists: needs --force
    assert "give --force" in capsys.readouterr().err
    assert main([*argv, "--passivity", "--json", str(out), "--force"]) == 0
    assert json.loads(out.read_text())["cor"] <= 1.0 + 1e-6
    assert main(["simulate", "--compensator", "nonesuch"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sdmdc-online" in err[0]
