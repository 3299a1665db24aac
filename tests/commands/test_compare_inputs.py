"""A log whose columns are named otherwise: ``hybridtable compare`` says in one
line which column is missing, what the log has, and the ``--column-map`` that
reads it; the proposed option then works."""

from __future__ import annotations

import shutil
from pathlib import Path

from hybridtable.cli import main
from tests.examples import EXAMPLES


def _log(tmp_path: Path, header: str) -> Path:
    """run1 of the examples with its header replaced."""
    shutil.copy(EXAMPLES / "run1.json", tmp_path / "run1.json")
    lines = (EXAMPLES / "run1.csv").read_text().splitlines()
    csv = tmp_path / "run1.csv"
    csv.write_text("\n".join([header, *lines[1:]]) + "\n")
    return csv


def _error(capsys, *args: str) -> str:
    assert main(["compare", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err  # one line
    return err


def test_missing_column_proposes_the_similar_one_and_the_proposal_works(tmp_path, capsys):
    csv = _log(tmp_path, "time_s,p_des_m,p_act_m,Force,f_comp_n,v_des_m_per_s")
    err = _error(capsys, str(csv))
    assert "run1.csv line 1: missing column(s) f_mea_n" in err
    assert "(has: time_s, p_des_m, p_act_m, Force, f_comp_n, v_des_m_per_s)" in err
    assert err.endswith("map it with --column-map f_mea_n=Force")
    option = err.split("--column-map ")[1]
    assert main(["compare", str(csv), "--column-map", option, "--json", "-"]) == 0


def test_two_missing_columns_each_get_their_own_proposal(tmp_path, capsys):
    csv = _log(tmp_path, "t,p_des_m,p_act_m,force_N,f_comp_n,v_des_m_per_s")
    err = _error(capsys, str(csv))
    assert "missing column(s) time_s, f_mea_n" in err
    assert err.endswith("map them with --column-map time_s=t,f_mea_n=force_N")


def test_no_similar_column_gives_the_syntax_and_no_other_column_says_so(tmp_path, capsys):
    csv = _log(tmp_path, "time_s,p_des_m,p_act_m,f_mea_n,temperature_c,v_des_m_per_s")
    err = _error(capsys, str(csv))
    assert err.endswith("map it with --column-map f_comp_n=LOG_COLUMN")
    lines = (EXAMPLES / "run1.csv").read_text().splitlines()
    csv.write_text("\n".join(",".join(x.split(",")[:4] + x.split(",")[5:]) for x in lines) + "\n")
    err = _error(capsys, str(csv))
    assert "missing column(s) f_comp_n" in err
    assert err.endswith("the log has no other column to read it from")
