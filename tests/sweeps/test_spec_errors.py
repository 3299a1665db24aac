"""Malformed sweep specs: one line naming the key, exit 2, nothing written.

Written from the docstrings of :mod:`hybridtable.sweeps.spec`,
:mod:`~hybridtable.sweeps.distributions`, :mod:`~hybridtable.sweeps.inputs` and
:mod:`~hybridtable.sweeps.metrics` only (the format, the error contract of
:class:`~hybridtable.errors.SpecError`: "one line naming the file and the key"),
not from their code. Every case of :data:`CASES` goes through the command line
in-process (``hybridtable sweep SPEC.toml --out FILE.parquet``) and, when it is
TOML at all, through :func:`~hybridtable.sweeps.spec.parse_spec`.

Decision on an empty file: it is refused (one line naming the file). The spec's
only attribute without a default is ``SweepSpec.name``, and a file with nothing
in it is a mistake (a wrong path, a save cut short) far more often than a wish
for one run of the paper's Table 1 point.

Assumption: the model file is given as the top-level key ``model`` (a path,
relative to the spec's folder); the docstrings name ``SweepSpec.model`` and
``model_path`` but not the TOML key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

from hybridtable.cli import main
from hybridtable.errors import ParameterError, SpecError
from hybridtable.sweeps.spec import load_spec, parse_spec

__all__: list[str] = []

TOP = 'name = "errors"\nseed = 1\nmetrics = ["cor"]\ncompensators = ["none", "SDMDC"]\n'
BASE = "contact_frequency_hz = 1.0\n"
GRID = "sensor_delay_s = [0.001, 0.003]\n"
MC = "samples = 4\n"
DRAW = 'initial_velocity_m_per_s = {distribution = "uniform", low = 0.05, high = 0.2}\n'


def spec_text(
    top: str = TOP,
    base: str = BASE,
    grid: str = GRID,
    points: str = "",
    mc: str = MC,
    draw: str = DRAW,
    extra: str = "",
) -> str:
    """A spec's TOML from its sections (the defaults make a valid spec)."""
    return (
        f"{top}\n[base]\n{base}\n[grid]\n{grid}\n{points}\n"
        f"[monte_carlo]\n{mc}\n[monte_carlo.draw]\n{draw}\n{extra}"
    )


def draw_of(table: str, name: str = "initial_velocity_m_per_s") -> str:
    return f"{name} = {{{table}}}\n"


VALID = spec_text()


@dataclass(frozen=True)
class Case:
    """One malformed spec: its text (None: not a file, see ``kind``) and the
    words its one-line message must hold."""

    id: str
    text: str | None
    words: tuple[str, ...]
    kind: str = "toml"  # "toml" | "raw" (not TOML) | "folder" | "missing"


D = "monte_carlo.draw.initial_velocity_m_per_s"

CASES = [
    # -- unknown parameters, in every section that takes them
    Case(
        "unknown-in-base",
        spec_text(base=BASE + "spacecraft_mas_kg = 10.0\n"),
        ("base.spacecraft_mas_kg",),
    ),
    Case(
        "unknown-in-grid",
        spec_text(grid=GRID + "table_response = [10.0, 25.0]\n"),
        ("grid.table_response",),
    ),
    Case(
        "unknown-in-points",
        spec_text(points="[[points]]\ncontact_stifness_n_per_m = 1e5\n"),
        ("points", "contact_stifness_n_per_m"),
    ),
    Case(
        "unknown-in-draw",
        spec_text(draw=DRAW + draw_of('distribution = "uniform", low = 1.0, high = 2.0', "speed")),
        ("monte_carlo.draw.speed",),
    ),
    # -- misspelt top-level keys and tables
    Case("misspelt-top-key", spec_text(top=TOP + 'metrcs = ["cor"]\n'), ("metrcs",)),
    Case(
        "misspelt-top-table",
        spec_text()
        .replace("[monte_carlo]", "[montecarlo]")
        .replace("[monte_carlo.draw]", "[montecarlo.draw]"),
        ("montecarlo",),
    ),
    Case("unknown-format", spec_text(top=TOP + 'format = "hybridtable-sweep/9"\n'), ("format",)),
    Case("unknown-engine", spec_text(top=TOP + 'engine = "gpu"\n'), ("engine",)),
    Case("name-not-text", spec_text(top=TOP.replace('"errors"', "3")), ("name",)),
    Case("seed-not-integer", spec_text(top=TOP.replace("seed = 1", "seed = 1.5")), ("seed",)),
    Case("seed-text", spec_text(top=TOP.replace("seed = 1", 'seed = "one"')), ("seed",)),
    # -- distributions
    Case(
        "bad-distribution-name",
        spec_text(draw=draw_of('distribution = "gaussian", mean = 0.1, std = 0.01')),
        (D,),
    ),
    Case(
        "missing-low", spec_text(draw=draw_of('distribution = "uniform", high = 0.2')), (D, "low")
    ),
    Case(
        "missing-high", spec_text(draw=draw_of('distribution = "uniform", low = 0.05')), (D, "high")
    ),
    Case(
        "low-above-high",
        spec_text(draw=draw_of('distribution = "uniform", low = 0.2, high = 0.05')),
        (D,),
    ),
    Case(
        "low-equals-high",
        spec_text(draw=draw_of('distribution = "uniform", low = 0.1, high = 0.1')),
        (D,),
    ),
    Case(
        "log-uniform-low-zero",
        spec_text(draw=draw_of('distribution = "log_uniform", low = 0.0, high = 0.2')),
        (D,),
    ),
    Case(
        "log-uniform-low-negative",
        spec_text(draw=draw_of('distribution = "log_uniform", low = -0.1, high = 0.2')),
        (D,),
    ),
    Case(
        "normal-std-zero",
        spec_text(draw=draw_of('distribution = "normal", mean = 0.1, std = 0.0')),
        (D, "std"),
    ),
    Case(
        "normal-std-negative",
        spec_text(draw=draw_of('distribution = "normal", mean = 0.1, std = -0.01')),
        (D, "std"),
    ),
    Case(
        "normal-missing-mean",
        spec_text(draw=draw_of('distribution = "normal", std = 0.01')),
        (D, "mean"),
    ),
    Case(
        "normal-truncation-inverted",
        spec_text(
            draw=draw_of('distribution = "normal", mean = 0.1, std = 0.01, low = 0.2, high = 0.05')
        ),
        (D,),
    ),
    Case(
        "normal-truncation-beyond-range",
        spec_text(
            draw=draw_of('distribution = "normal", mean = 0.1, std = 0.01, low = 0.05, high = 20.0')
        ),
        (D,),
    ),
    Case(
        "uniform-with-mean",
        spec_text(draw=draw_of('distribution = "uniform", low = 0.05, high = 0.2, mean = 0.1')),
        (D, "mean"),
    ),
    Case("draw-not-a-table", spec_text(draw="initial_velocity_m_per_s = 0.1\n"), (D,)),
    Case(
        "draw-beyond-plausible-range",
        spec_text(
            draw=DRAW
            + draw_of('distribution = "uniform", low = 0.0, high = 20.0', "contact_damping_ratio")
        ),
        ("monte_carlo.draw.contact_damping_ratio",),
    ),
    Case(
        "choice-empty-values",
        spec_text(draw=draw_of('distribution = "choice", values = []')),
        (D, "values"),
    ),
    Case(
        "choice-weights-length",
        spec_text(draw=draw_of('distribution = "choice", values = [0.1, 0.2], weights = [1.0]')),
        (D, "weights"),
    ),
    Case(
        "choice-negative-weight",
        spec_text(
            draw=draw_of('distribution = "choice", values = [0.1, 0.2], weights = [1.0, -1.0]')
        ),
        (D, "weights"),
    ),
    Case(
        "choice-value-out-of-range",
        spec_text(draw=draw_of('distribution = "choice", values = [0.1, 50.0]')),
        (D,),
    ),
    # -- the number of samples
    Case("samples-negative", spec_text(mc="samples = -5\n"), ("monte_carlo.samples",)),
    Case("samples-zero", spec_text(mc="samples = 0\n"), ("monte_carlo.samples",)),
    Case("samples-not-integer", spec_text(mc="samples = 2.5\n"), ("monte_carlo.samples",)),
    Case("samples-text", spec_text(mc='samples = "10"\n'), ("monte_carlo.samples",)),
    Case("samples-bool", spec_text(mc="samples = true\n"), ("monte_carlo.samples",)),
    # -- grid axes
    Case("grid-empty-list", spec_text(grid="sensor_delay_s = []\n"), ("grid.sensor_delay_s",)),
    Case(
        "grid-range-num-zero",
        spec_text(grid=GRID + "table_response_hz = {start = 10.0, stop = 100.0, num = 0}\n"),
        ("grid.table_response_hz",),
    ),
    Case(
        "grid-log-range-from-zero",
        spec_text(
            grid=GRID + 'table_response_hz = {start = 0.0, stop = 100.0, num = 3, scale = "log"}\n'
        ),
        ("grid.table_response_hz",),
    ),
    Case(
        "grid-range-unknown-scale",
        spec_text(
            grid=GRID
            + 'table_response_hz = {start = 10.0, stop = 100.0, num = 3, scale = "cubic"}\n'
        ),
        ("grid.table_response_hz",),
    ),
    Case(
        "grid-text-value",
        spec_text(grid='sensor_delay_s = [0.001, "fast"]\n'),
        ("grid.sensor_delay_s",),
    ),
    # -- values out of their plausible range, of the wrong type
    Case("delay-5-s", spec_text(grid="sensor_delay_s = [0.001, 5.0]\n"), ("grid.sensor_delay_s",)),
    Case(
        "negative-mass",
        spec_text(base="spacecraft_mass_kg = -1.0\n"),
        ("base.spacecraft_mass_kg",),
    ),
    Case("nan-gap", spec_text(base=BASE + "initial_gap_m = nan\n"), ("base.initial_gap_m",)),
    Case("inf-delay", spec_text(grid="sensor_delay_s = [0.001, inf]\n"), ("grid.sensor_delay_s",)),
    Case(
        "inf-stiffness-in-point",
        spec_text(points="[[points]]\ncontact_stiffness_n_per_m = inf\n"),
        ("points", "contact_stiffness_n_per_m"),
    ),
    Case(
        "string-for-number",
        spec_text(base=BASE + 'initial_gap_m = "0.001"\n'),
        ("base.initial_gap_m",),
    ),
    Case(
        "bool-for-number", spec_text(base=BASE + "initial_gap_m = true\n"), ("base.initial_gap_m",)
    ),
    Case("number-for-bool", spec_text(base=BASE + "passivity = 1\n"), ("base.passivity",)),
    Case(
        "unknown-contact-gate",
        spec_text(base=BASE + 'contact_gate = "laser"\n'),
        ("base.contact_gate",),
    ),
    # -- compensators and metrics
    Case(
        "unknown-compensator",
        spec_text(top=TOP.replace('["none", "SDMDC"]', '["none", "XYZ"]')),
        ("compensators", "XYZ"),
    ),
    Case(
        "unknown-metric",
        spec_text(top=TOP.replace('["cor"]', '["cor", "peak_force"]')),
        ("metrics", "peak_force"),
    ),
    Case("empty-metrics", spec_text(top=TOP.replace('["cor"]', "[]")), ("metrics",)),
    # -- a quantity set twice
    Case(
        "given-in-base-and-grid",
        spec_text(base=BASE + "sensor_delay_s = 0.002\n"),
        ("sensor_delay_s",),
    ),
    Case(
        "given-in-grid-and-draw",
        spec_text(
            draw=DRAW
            + draw_of('distribution = "uniform", low = 0.001, high = 0.003', "sensor_delay_s")
        ),
        ("sensor_delay_s",),
    ),
    Case(
        "compensator-in-base-and-compensators",
        spec_text(base=BASE + 'compensator = "SDC"\n'),
        ("compensator",),
    ),
    Case(
        "mass-and-contact-frequency",
        spec_text(base=BASE + "spacecraft_mass_kg = 2533.0\n"),
        ("spacecraft_mass_kg", "contact_frequency_hz"),
    ),
    Case(
        "damping-and-damping-ratio",
        spec_text(
            base=BASE + "contact_damping_ratio = 0.05\n",
            grid=GRID + "contact_damping_n_s_per_m = [0.0, 10.0]\n",
        ),
        ("contact_damping_n_s_per_m", "contact_damping_ratio"),
    ),
    Case(
        "points-with-different-keys",
        spec_text(
            points="[[points]]\ncontact_stiffness_n_per_m = 1e5\n"
            "[[points]]\ninitial_gap_m = 0.002\n"
        ),
        ("points",),
    ),
    # -- campaign too large
    Case("too-many-runs", spec_text(mc="samples = 100000000\n"), ("runs",)),
    # -- the file itself
    Case(
        "model-missing",
        spec_text(top=TOP + 'model = "no_such_model.json"\n'),
        ("model", "no_such_model.json"),
    ),
    Case("not-toml", "this is [not = = TOML\n", (), kind="raw"),
    Case("empty-file", "", ()),
    Case("spec-is-a-folder", None, (), kind="folder"),
    Case("spec-missing", None, (), kind="missing"),
]

TOML_CASES = [c for c in CASES if c.kind == "toml"]


def write_case(case: Case, folder: Path) -> Path:
    """The spec's path in ``folder`` (the file, a folder or nothing)."""
    path = folder / f"{case.id}.toml"
    if case.kind == "folder":
        path.mkdir()
    elif case.kind != "missing":
        path.write_text(case.text, encoding="utf-8")
    return path


def assert_one_line(message: str, words: tuple[str, ...]) -> None:
    line = message.strip("\n")
    assert line, "no message"
    assert "\n" not in line, f"more than one line: {message!r}"
    assert "Traceback" not in line
    for word in words:
        assert word in line, f"{word!r} not named in {line!r}"


def test_the_base_spec_is_valid(tmp_path):
    """Every case below breaks one thing of this spec, which is accepted."""
    path = tmp_path / "valid.toml"
    path.write_text(VALID, encoding="utf-8")
    spec = load_spec(path)
    assert spec.n_runs == 4 * 2 * 2
    assert spec.samples == 4


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_command_line_refuses(case, tmp_path, capsys):
    path = write_case(case, tmp_path)
    before = sorted(tmp_path.iterdir())
    out = tmp_path / "results.parquet"
    # Refuse here first: a spec the checks let through would start a campaign.
    with pytest.raises(ParameterError):
        load_spec(path)
    capsys.readouterr()
    try:
        code = main(["sweep", str(path), "--out", str(out), "--no-progress"])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    captured = capsys.readouterr()
    assert code == 2, captured.err
    assert_one_line(captured.err, case.words + (path.name,))
    assert captured.err.startswith("hybridtable sweep: error: "), captured.err
    assert not out.exists()
    assert sorted(tmp_path.iterdir()) == before, "the command wrote something"


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_load_spec_refuses(case, tmp_path):
    path = write_case(case, tmp_path)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert_one_line(str(info.value), case.words + (path.name,))


@pytest.mark.parametrize("case", TOML_CASES, ids=[c.id for c in TOML_CASES])
def test_parse_spec_refuses(case, tmp_path):
    raw = tomllib.loads(case.text)
    source = str(tmp_path / f"{case.id}.toml")
    with pytest.raises(ParameterError) as info:
        parse_spec(raw, source=source, folder=tmp_path)
    assert_one_line(str(info.value), case.words)


def test_ideal_table_is_accepted(tmp_path):
    """``inf`` is refused above where it is no value, but an ideal table
    (``table_response_hz = inf``) is one (``limits``: ``ideal_inf``)."""
    raw = tomllib.loads(spec_text(grid=GRID + "table_response_hz = [25.0, inf]\n"))
    spec = parse_spec(raw, source="ideal.toml", folder=tmp_path)
    values = {spec.run_inputs(i).values["table_response_hz"] for i in range(spec.n_runs)}
    assert values == {25.0, math.inf}
