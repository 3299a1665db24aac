"""Reading a CoR table: every bad input is refused in one line that names the file,
the line and the column; the noise comes from the cor_std, the scatter of repeated
rows or the rounding of the ``cor`` column; flags fill what the table does not state.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hybridtable.errors import MeasurementError
from hybridtable.explain.conditions import PAPER_CONDITIONS
from hybridtable.explain.table import read_cor_table


def _write(folder: Path, text: str, name: str = "table.csv") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _refused(path: Path, *parts: str, defaults: dict | None = None) -> str:
    """The one-line message of reading ``path``; it names the file and every part."""
    with pytest.raises(MeasurementError) as info:
        read_cor_table(path, defaults)
    message = str(info.value)
    assert "\n" not in message, message
    assert str(path) in message, message
    for part in parts:
        assert part in message, f"{part!r} not in {message!r}"
    return message


# -- refused, in one line naming where -----------------------------------------


def test_an_unknown_column_is_named(tmp_path):
    path = _write(tmp_path, "compensator,cor,stiffness\nnone,1.16,1e5\n")
    message = _refused(path, "'stiffness'")
    assert "contact_stiffness_n_per_m" in message  # the known columns are listed


def test_a_table_without_a_cor_column_is_refused(tmp_path):
    path = _write(tmp_path, "compensator,cor_std\nnone,0.01\n")
    _refused(path, "'cor'")


def test_a_row_without_a_cor_names_its_line(tmp_path):
    path = _write(tmp_path, "compensator,cor\nnone,1.16\nSDC,\n")
    _refused(path, f"{path}:3", "cor")


@pytest.mark.parametrize(
    ("text", "line", "column"),
    [
        ("compensator,cor\nnone,1.16\nSDC,1,1057\n", 3, None),  # 3 cells for 2 columns
        ("compensator,cor\nnone,abc\n", 2, "cor"),
        ("compensator,cor,sensor_delay_s\nnone,1.16,0.005\nSDC,1.10,5ms\n", 3, "sensor_delay_s"),
        ("compensator,cor,cor_std\nnone,1.16,nan\n", 2, "cor_std"),
    ],
)
def test_a_cell_that_is_not_a_number_names_its_line_and_column(tmp_path, text, line, column):
    path = _write(tmp_path, text)
    _refused(path, f"{path}:{line}", *([column] if column else []))


@pytest.mark.parametrize("cor", ["0", "-1.1", "0.0"])
def test_a_cor_at_or_below_zero_is_refused(tmp_path, cor):
    path = _write(tmp_path, f"compensator,cor\nnone,1.16\nSDC,{cor}\n")
    _refused(path, f"{path}:3", "cor")


def test_an_unknown_compensator_is_named_with_the_known_ones(tmp_path):
    path = _write(tmp_path, "compensator,cor\nnone,1.16\nPID,1.02\n")
    _refused(path, f"{path}:3", "'PID'", "none", "SDC", "MDC", "SDMDC")


def test_a_delay_between_ticks_of_the_stated_rate_is_read_as_stated(tmp_path):
    # 2.5 ms at 1 kHz is 2.5 ticks: the rig computer reads the two neighbouring
    # samples mixed, as every engine of the loop models it (no refusal).
    path = _write(
        tmp_path,
        "compensator,cor,sensor_delay_s,sample_rate_hz\nnone,1.16,0.003,1000\nSDC,1.10,0.0025,1000\n",
    )
    table = read_cor_table(path)
    assert [r.conditions.sensor_delay_s for r in table.rows] == [0.003, 0.0025]
    assert {r.conditions.sample_rate_hz for r in table.rows} == {1000.0}


def test_a_rate_from_a_flag_applies_to_every_row(tmp_path):
    path = _write(tmp_path, "compensator,cor,sensor_delay_s\nnone,1.16,0.0025\n")
    table = read_cor_table(path, {"sample_rate_hz": 1000.0})
    assert table.rows[0].conditions.sample_rate_hz == 1000.0
    assert table.rows[0].conditions.sensor_delay_s == 0.0025


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(MeasurementError) as info:
        read_cor_table(tmp_path / "nowhere.csv")
    assert "nowhere.csv" in str(info.value)
    assert "\n" not in str(info.value)


# -- the noise ------------------------------------------------------------------


def test_the_rounding_comes_from_the_most_decimals_of_the_cor_column(tmp_path):
    # 1.16 has 2 decimals, 1.1057 has 4: the column is rounded to 4 decimals,
    # a uniform error of 1e-4 wide, std 1e-4 / sqrt(12) = 2.89e-5.
    path = _write(tmp_path, "compensator,cor\nnone,1.16\nSDC,1.1057\nMDC,1.05\nSDMDC,1\n")
    table = read_cor_table(path)
    expected = 1e-4 / math.sqrt(12.0)
    assert table.rounding_std == pytest.approx(expected, rel=1e-12)
    std, source = table.noise()
    np.testing.assert_allclose(std, expected, rtol=1e-12)
    assert "4 decimals" in source


def test_the_rounding_of_a_cor_written_with_an_exponent(tmp_path):
    # 1.1057E+00 and 11057e-4 are both written to 1e-4
    path = _write(tmp_path, "compensator,cor\nnone,1.1057E+00\nSDC,11057e-4\n")
    table = read_cor_table(path)
    assert table.rounding_std == pytest.approx(1e-4 / math.sqrt(12.0), rel=1e-12)
    assert table.rows[1].cor == pytest.approx(1.1057)


def test_two_decimals_give_the_paper_table4_rounding(tmp_path):
    path = _write(tmp_path, "compensator,cor\nSDMDC,0.99\nSDMDC,0.98\n")
    assert read_cor_table(path).rounding_std == pytest.approx(0.0029, rel=0.01)


def test_repeated_rows_give_their_pooled_scatter(tmp_path):
    # none 1.10, 1.12, 1.11 (mean 1.11) and SDC 1.05, 1.07 (mean 1.06) at the same
    # conditions: squared deviations 2e-4 + 2e-4 over 2 + 1 degrees of freedom,
    # std sqrt(4e-4 / 3) = 0.01155 for every row; the MDC row is not repeated
    # but gets the same scatter.
    path = _write(
        tmp_path,
        "compensator,cor\nnone,1.10\nnone,1.12\nnone,1.11\nSDC,1.05\nSDC,1.07\nMDC,1.03\n",
    )
    table = read_cor_table(path)
    assert sorted(len(g) for g in table.groups()) == [1, 2, 3]
    std, source = table.noise()
    np.testing.assert_allclose(std, math.sqrt(4e-4 / 3.0), rtol=1e-9)
    assert "5 repeated rows" in source


def test_rows_at_other_conditions_are_not_repeats(tmp_path):
    # the same compensator at two stiffnesses: two measurements, not a scatter
    path = _write(
        tmp_path,
        "compensator,cor,contact_stiffness_n_per_m\nnone,1.10,1e5\nnone,1.12,2e5\n",
    )
    table = read_cor_table(path)
    assert all(len(g) == 1 for g in table.groups())
    std, source = table.noise()
    np.testing.assert_allclose(std, 0.01 / math.sqrt(12.0), rtol=1e-9)
    assert "rounding" in source


def test_a_scatter_below_the_rounding_is_floored_at_the_rounding(tmp_path):
    # two equal readings have no scatter; their noise is still the rounding's
    path = _write(tmp_path, "compensator,cor\nnone,1.16\nnone,1.16\nSDC,1.11\n")
    std, _ = read_cor_table(path).noise()
    np.testing.assert_allclose(std, 0.01 / math.sqrt(12.0), rtol=1e-9)


def test_a_stated_cor_std_wins_and_is_floored_at_the_rounding(tmp_path):
    path = _write(tmp_path, "compensator,cor,cor_std\nnone,1.1611,0.002\nSDC,1.1057,1e-6\n")
    std, source = read_cor_table(path).noise()
    np.testing.assert_allclose(std, [0.002, 1e-4 / math.sqrt(12.0)], rtol=1e-9)
    assert "cor_std" in source


# -- what each row states --------------------------------------------------------


def test_flags_fill_the_conditions_the_table_does_not_state(tmp_path):
    path = _write(
        tmp_path,
        "compensator,cor,contact_frequency_hz,table_response_hz\nnone,1.19,1,\nSDC,1.08,1,40\n",
    )
    table = read_cor_table(path, {"sensor_delay_s": 0.003, "table_response_hz": 30.0})
    first, second = (r.conditions for r in table.rows)
    # a flag fills every row that does not state it; a cell wins over the flag
    assert first.sensor_delay_s == second.sensor_delay_s == 0.003
    assert first.table_response_hz == 30.0
    assert second.table_response_hz == 40.0
    # the lead follows the delay when nothing states it
    assert first.lead_s == 0.003
    # what neither states is the paper's Table 1
    assert first.contact_stiffness_n_per_m == PAPER_CONDITIONS["contact_stiffness_n_per_m"]
    assert first.table_damping_ratio == PAPER_CONDITIONS["table_damping_ratio"]
    assert first.sample_rate_hz is None
    stated = dict(table.stated)
    assert stated["contact_frequency_hz"] == "table"
    assert stated["sensor_delay_s"] == "flag"
    assert stated["table_response_hz"] == "table and flag"
    assert stated["contact_stiffness_n_per_m"] == "assumed"
    assert "assumed" in stated["lead_time_s"]
    assert "contact_stiffness_n_per_m" in table.assumed
    assert "sensor_delay_s" not in table.assumed


def test_an_empty_cell_is_not_stated(tmp_path):
    path = _write(
        tmp_path,
        "compensator,cor,sensor_delay_s\nnone,1.19,0.003\nSDC,1.10,\n",
    )
    table = read_cor_table(path)
    assert table.rows[0].conditions.sensor_delay_s == 0.003
    assert table.rows[1].conditions.sensor_delay_s == PAPER_CONDITIONS["sensor_delay_s"]
    assert "assumed" in table.stated["sensor_delay_s"]
    assert "table" in table.stated["sensor_delay_s"]


def test_the_paper_table3_states_its_delay(tmp_path):
    path = Path(__file__).resolve().parents[2] / "examples" / "explain" / "table3_experiment.csv"
    table = read_cor_table(path)
    assert [r.compensator for r in table.rows] == ["none", "SDC", "MDC", "SDMDC"]
    assert all(r.conditions.sensor_delay_s == 0.003 for r in table.rows)
    assert all(r.conditions.lead_s == 0.003 for r in table.rows)
    assert table.stated["sensor_delay_s"] == "table"
    assert [r.line for r in table.rows] == [2, 3, 4, 5]
