"""Every figure of the package carries its units, and every figure of a report
has a caption.

Each figure writer runs on a small input with ``Figure.savefig`` wrapped: every
axes' x and y label (a colour bar's label is its axes' label) that is not empty
must carry a unit in brackets (``force [N]``, ``time [s]``, ``CoR [1]``). Each
``*.md`` the writer leaves must put one italic caption line right under every
``![title](file.png)``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from hybridtable.cli import main
from tests.examples import EXAMPLES

#: Whole loops, fits or commands, many times: make test runs them, make check does not.
pytestmark = pytest.mark.slow

EXAMPLE_RUN = EXAMPLES / "run1.csv"

#: A unit in brackets anywhere in the label.
UNIT = re.compile(r"\[[^\[\]]+\]")
FIGURE_LINE = re.compile(r"!\[[^\]]*\]\([^)]*\.png\)")
CAPTION_LINE = re.compile(r"\*[^*\s].*\*")


@pytest.fixture
def labels(monkeypatch):
    """``(file, axes title, which, label)`` of every axes of every figure saved."""
    from matplotlib.figure import Figure

    seen: list[tuple[str, str, str, str]] = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        for ax in self.axes:
            for which, text in (("xlabel", ax.get_xlabel()), ("ylabel", ax.get_ylabel())):
                seen.append((Path(str(fname)).name, ax.get_title(), which, text))
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return seen


def _simulate_plot(out: Path) -> None:
    out.mkdir()
    assert main(["simulate", "--plot", str(out / "run.png")]) == 0


def _reproduce(out: Path) -> None:
    from hybridtable.reports.reproduce import FIGURES, reproduce
    from hybridtable.studies.paper import load_tables

    tables = load_tables()
    t2 = tables["table2_simulation_sdmdc"]
    t2["rows"] = t2["rows"][:1]  # one Table 2 row is enough for the figures
    path = out.parent / "tables.json"
    path.write_text(json.dumps(tables))
    rep = reproduce(out_dir=out, tables_path=path, progress=False)
    assert sorted(Path(f).name for f in rep.figures) == sorted(FIGURES)


def _compensators(out: Path) -> None:
    argv = ["compensators", "--quick", "--compensators", "SDMDC,sdmdc-online"]
    argv += ["--scenarios", "mismatch", "--prior-ratios", "0.5,1", "--jobs", "1"]
    assert main([*argv, "--no-progress", "--report", str(out)]) == 0


def _compensators_model(out: Path) -> None:
    from tests.studies.test_model_compensators import write_damped_model

    model = write_damped_model(out.parent / "rig")
    argv = ["compensators", "--model", str(model), "--compensators", "none,SDMDC"]
    assert main([*argv, "--jobs", "1", "--no-progress", "--report", str(out)]) == 0


def _compare(out: Path) -> None:
    assert main(["compare", str(EXAMPLE_RUN), "--report", str(out)]) == 0


def _diagnose(out: Path) -> None:
    argv = ["diagnose", str(EXAMPLE_RUN), "--effects", "force_bias", "--no-progress"]
    assert main([*argv, "--report", str(out)]) == 0


def _margins(out: Path) -> None:
    argv = ["margins", "--sensor-delay-s", "0.002,0.01", "--table-response-hz", "20,80"]
    assert main([*argv, "--no-progress", "--report", str(out)]) == 0


def _sweep(out: Path) -> None:
    spec = out.parent / "spec.toml"
    spec.write_text(
        'compensators = ["none", "SDMDC"]\n[grid]\nsensor_delay_s = [0.002, 0.008]\n'
        "table_response_hz = [20.0, 60.0]\n"
    )
    argv = ["sweep", str(spec), "--out", str(out.parent / "runs.parquet"), "--workers", "1"]
    assert main([*argv, "--no-progress", "--report", str(out)]) == 0


WRITERS = {
    "simulate-plot": _simulate_plot,
    "reproduce": _reproduce,
    "compensators": _compensators,
    "compensators-model": _compensators_model,
    "compare": _compare,
    "diagnose": _diagnose,
    "margins": _margins,
    "sweep": _sweep,
}


@pytest.mark.parametrize("writer", list(WRITERS))
def test_every_axis_label_has_a_unit_and_every_figure_a_caption(writer, labels, tmp_path):
    out = tmp_path / "out"
    WRITERS[writer](out)
    assert labels, f"{writer} saved no figure"
    missing = [
        f"{file} ({title or 'untitled'}): {which} {text!r}"
        for file, title, which, text in labels
        if text.strip() and not UNIT.search(text)
    ]
    assert not missing, "labels without a unit in brackets:\n" + "\n".join(missing)
    uncaptioned = []
    for md in sorted(out.glob("*.md")):
        lines = [line.strip() for line in md.read_text().splitlines()] + [""]
        for i, line in enumerate(lines[:-1]):
            if FIGURE_LINE.fullmatch(line) and not CAPTION_LINE.fullmatch(lines[i + 1]):
                uncaptioned.append(f"{md.name}: {line}")
    assert not uncaptioned, "figures without an italic caption line:\n" + "\n".join(uncaptioned)
