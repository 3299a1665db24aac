"""``hybridtable diagnose --help`` names the built-in effects without importing them."""

from __future__ import annotations

from hybridtable.commands.diagnose import BUILTIN_EFFECT_NAMES
from hybridtable.effects.library import BUILTIN_EFFECTS


def test_help_names_every_built_in_effect_it_tries_in_order():
    named = [n.split(" ")[0] for n in BUILTIN_EFFECT_NAMES]
    assert named == [e.name for e in BUILTIN_EFFECTS if "diagnose" in e.default_for]


def test_help_says_what_is_decided_by_the_audit(capsys):
    from hybridtable.cli import main

    try:
        main(["diagnose", "--help"])
    except SystemExit as exit_:
        assert exit_.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "mass_error (decided by the audit)" in text
    assert "'none'" in text and "'unexplained'" in text
