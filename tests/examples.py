"""The example runs the repository ships (``examples/nominal``), for tests that
read them or need their rig."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from hybridtable.measurement.run_format import RunInfo
from hybridtable.measurement.run_reader import run_info_from_dict

__all__ = ["EXAMPLES", "example_info"]

#: The folder of the three nominal example runs.
EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "nominal"


def example_info(**changes) -> RunInfo:
    """The rig of the examples (``run1.json``: k = 6e4 N/m, m = 675.475 kg,
    4 ms delay, 1 kHz computer, table 30 Hz / 0.7), with ``changes``."""
    raw = json.loads((EXAMPLES / "run1.json").read_text(encoding="utf-8"))
    return replace(run_info_from_dict(raw, str(EXAMPLES / "run1.json")), **changes)
