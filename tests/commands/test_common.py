"""The command layer's helpers: field names in a library's message become the
command line's flags, and only those."""

from __future__ import annotations

from hybridtable.commands._common import flag_words


def test_flag_words_rewrites_whole_field_names_only():
    fields = ["sensor_delay_s", "sample_rate_hz", "table_response_hz"]
    text = (
        "table_response_hz 200 is too fast at sample_rate_hz 1000: needs table_response_hz "
        "<= 50; nominal.sensor_delay_s and --sensor-delay-s and my_sensor_delay_s stay"
    )
    assert flag_words(text, fields) == (
        "--table-response-hz 200 is too fast at --sample-rate-hz 1000: needs "
        "--table-response-hz <= 50; nominal.sensor_delay_s and --sensor-delay-s and "
        "my_sensor_delay_s stay"
    )
    assert flag_words(text, []) == text
