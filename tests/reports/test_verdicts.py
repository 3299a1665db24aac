"""The words of a contact's verdict: the energy is CoR^2, the direction and
size of the change are stated, and the simulate command opens with them."""

from __future__ import annotations

import pytest

from hybridtable.reports.verdicts import contact_verdict, cor_phrase, energy_change_percent


def test_energy_change_is_the_square_of_the_cor():
    assert energy_change_percent(1.0) == 0.0
    assert energy_change_percent(1.16115) == pytest.approx(34.83, abs=0.01)
    assert energy_change_percent(0.9) == pytest.approx(-19.0)
    assert cor_phrase(1.16115) == "CoR 1.161, energy +35%"
    assert cor_phrase(0.995) == "CoR 0.995, energy -1.0%"


@pytest.mark.parametrize(
    ("cor", "damped", "words"),
    [
        (1.16115, False, "adds energy: the spacecraft leaves 16.1% faster"),
        (1.002, False, "keeps its energy"),
        (0.93, False, "the loop takes energy out: the spacecraft leaves 7.0% slower"),
        (0.93, True, "the contact's damping and the loop take energy out"),
    ],
)
def test_the_verdict_names_direction_and_size(cor, damped, words):
    text = contact_verdict("SDC", cor, damped=damped)
    assert words in text and text.startswith("With SDC") and text.endswith(".")
    assert text.count("\n") == 0


def test_simulate_opens_with_the_verdict(capsys):
    from hybridtable.cli import main

    assert main(["simulate"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("With no compensation the loop adds energy")
    assert "CoR 1.161, energy +35%" in first
    assert main(["simulate", "--compensator", "SDMDC"]) == 0
    assert "SDMDC the contact keeps its energy" in capsys.readouterr().out.splitlines()[0]
