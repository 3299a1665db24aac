"""The diagrams of ``hybridtable diagram NAME``: the hybrid loop as a Drake
diagram (Graphviz), and small tables of the paper's scenarios run through it.

Each diagram writes into an output folder and returns a
:class:`DiagramOutput`: one plain sentence (the first console line), the
lines of its table and the files written. :data:`DIAGRAMS` names them with a
one-line description; :func:`diagram_files` lists the files a diagram will
write, so that a command can check them before any work.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from hybridtable._files import write_text_atomic

__all__ = [
    "DIAGRAMS",
    "DEFAULT_SAMPLE_RATES_HZ",
    "DELAY_SCENARIOS",
    "DiagramOutput",
    "diagram_files",
    "draw",
]


#: Name -> what the diagram shows (``hybridtable diagram --list``).
DIAGRAMS: dict[str, str] = {
    "hybrid-loop": "the hybrid loop at the Table 1 point with SDMDC as a Drake diagram "
    "(Graphviz .dot, and .svg when Graphviz is installed)",
    "sampled-rig": "the Table 1 point on a rig computer at a sample rate (zero-order hold, "
    "sampled sensor) against the continuous loop, for the four compensators",
    "delay-scenarios": "the paper's Figs. 3-5 scenarios without compensation: CoR against "
    "the estimate exp(pi^2 f_con tau_eff)",
    "table1-compensators": "the paper's Table 1 point: CoR and peak force of the four "
    "compensators beside the paper's CoR",
}

#: Sample rates of ``sampled-rig`` unless given [Hz].
DEFAULT_SAMPLE_RATES_HZ: tuple[float, ...] = (1000.0, 5000.0)

#: The paper's Figs. 3-5 scenarios: label -> sensor delay [s] and table response [Hz].
DELAY_SCENARIOS: dict[str, dict[str, float]] = {
    "Fig. 3, T_fms 1 ms": dict(sensor_delay_s=0.001, table_response_hz=math.inf),
    "Fig. 3, T_fms 3 ms": dict(sensor_delay_s=0.003, table_response_hz=math.inf),
    "Fig. 3, T_fms 5 ms": dict(sensor_delay_s=0.005, table_response_hz=math.inf),
    "Fig. 4, f_resp 100 Hz": dict(sensor_delay_s=0.0, table_response_hz=100.0),
    "Fig. 4, f_resp 50 Hz": dict(sensor_delay_s=0.0, table_response_hz=50.0),
    "Fig. 4, f_resp 25 Hz": dict(sensor_delay_s=0.0, table_response_hz=25.0),
    "Fig. 5, 5 ms + 25 Hz": dict(sensor_delay_s=0.005, table_response_hz=25.0),
}


@dataclass
class DiagramOutput:
    """What a diagram gives: ``verdict`` (one plain sentence), the ``lines``
    of its table or notes, the ``files`` written and its figures as ``data``
    (for ``--json``; CoRs [1], rates [Hz])."""

    verdict: str
    lines: list[str] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    data: dict = field(default_factory=dict)


def _up(x: float) -> str:
    """``x`` rounded up to four decimals, as text."""
    return f"{math.ceil(round(x * 1e4, 6)) / 1e4:.4f}"


def _stem(name: str) -> str:
    return name.replace("-", "_")


def diagram_files(name: str, out_dir: str | Path) -> list[Path]:
    """The files :func:`draw` writes for diagram ``name`` into ``out_dir``."""
    out = Path(out_dir)
    if name == "hybrid-loop":
        files = [out / "hybrid_loop.dot"]
        if shutil.which("dot") is not None:
            files.append(out / "hybrid_loop.svg")
        return files
    return [out / f"{_stem(name)}.txt"]


def _hybrid_loop(out: Path, **_: object) -> DiagramOutput:
    from hybridtable.loop.builder import build_hybrid_loop
    from hybridtable.studies.paper import table1_params

    loop = build_hybrid_loop(table1_params("SDMDC"))
    systems = [s.get_name() for s in loop.diagram.GetSystems()]
    dot_path = out / "hybrid_loop.dot"
    write_text_atomic(dot_path, loop.diagram.GetGraphvizString(max_depth=2))
    svg_path = out / "hybrid_loop.svg"
    render = f"dot -Tsvg {dot_path} -o {svg_path}"
    lines = [f"systems: {', '.join(systems)}"]
    files = [dot_path]
    dot = shutil.which("dot")
    if dot is None:
        lines.append(f"Graphviz is not installed; to draw it, install graphviz and run: {render}")
        shown = dot_path
    else:
        done = subprocess.run(
            [dot, "-Tsvg", str(dot_path), "-o", str(svg_path)],
            capture_output=True,
            text=True,
            check=False,
        )
        if done.returncode == 0:
            files.append(svg_path)
            shown = svg_path
        else:
            msg = (done.stderr.strip().splitlines() or ["no message"])[0]
            lines.append(f"Graphviz could not draw it ({msg}); the .dot is written: {render}")
            shown = dot_path
    verdict = (
        f"The hybrid loop (Table 1 point, SDMDC) is a Drake diagram of {len(systems)} "
        f"systems, drawn in {shown}"
    )
    return DiagramOutput(verdict, lines, files, data={"systems": systems})


def _sampled_rig(out: Path, sample_rates_hz: Sequence[float] = (), **_: object) -> DiagramOutput:
    from hybridtable.compensators.paper import COMPENSATORS
    from hybridtable.loop.simulation import simulate
    from hybridtable.studies.paper import table1_params

    rates = tuple(sample_rates_hz) or DEFAULT_SAMPLE_RATES_HZ
    head = f"{'compensator':<12}{'continuous':>12}" + "".join(f"{f'{r:g} Hz':>12}" for r in rates)
    lines = ["CoR [1] at the Table 1 point", head]
    cors: dict[str, tuple[float, list[float]]] = {}
    for name in COMPENSATORS:
        cont = simulate(table1_params(name)).metrics.cor
        sampled = [simulate(table1_params(name, sample_rate_hz=r)).metrics.cor for r in rates]
        cors[name] = (cont, sampled)
        lines.append(f"{name:<12}{cont:>12.5f}" + "".join(f"{c:>12.5f}" for c in sampled))
    none, sdmdc = cors["none"], cors["SDMDC"]
    verdict = (
        f"A rig computer at {rates[0]:g} Hz gives CoR {none[1][0]:.5f} with no compensation "
        f"and {sdmdc[1][0]:.5f} with SDMDC, against {none[0]:.5f} and {sdmdc[0]:.5f} for the "
        "continuous loop"
    )
    data = {
        "sample_rates_hz": list(rates),
        "cor": {n: {"continuous": c, "sampled": s} for n, (c, s) in cors.items()},
    }
    return DiagramOutput(verdict, lines, data=data)


def _delay_scenarios(out: Path, **_: object) -> DiagramOutput:
    from hybridtable.loop.simulation import simulate
    from hybridtable.studies.paper import cor_estimate, paper_params

    lines = [f"{'scenario':<24}{'CoR [1]':>10}{'estimate [1]':>14}{'difference':>12}"]
    worst = 0.0
    rows = []
    for label, kwargs in DELAY_SCENARIOS.items():
        p = paper_params(**kwargs)
        cor, estimate = simulate(p).metrics.cor, cor_estimate(p)
        worst = max(worst, abs(cor - estimate))
        rows.append({"scenario": label, **kwargs, "cor": cor, "cor_estimate": estimate})
        lines.append(f"{label:<24}{cor:>10.5f}{estimate:>14.5f}{cor - estimate:>+12.5f}")
    lines.append("estimate: exp(pi^2 f_con tau_eff), tau_eff = T_fms + 2 zeta / omega_resp")
    verdict = (
        "Without compensation the CoR follows exp(pi^2 f_con tau_eff) within "
        f"{_up(worst)} over the paper's {len(DELAY_SCENARIOS)} delay "
        "scenarios (Figs. 3-5)"
    )
    return DiagramOutput(verdict, lines, data={"scenarios": rows})


def _table1_compensators(out: Path, **_: object) -> DiagramOutput:
    from hybridtable.compensators.paper import COMPENSATORS
    from hybridtable.loop.simulation import simulate
    from hybridtable.studies.paper import load_tables, table1_params

    paper = load_tables()["table1_simulation"]["cor"]
    lines = [
        "Table 1 point: k 1e5 N/m, f_con 1 Hz, 25 Hz table (zeta 0.8), 5 ms sensor delay, "
        "0.1 m/s approach",
        f"{'compensator':<12}{'CoR [1]':>10}{'paper [1]':>11}{'peak force [N]':>16}",
    ]
    cor: dict[str, float] = {}
    worst = 0.0
    for name in COMPENSATORS:
        m = simulate(table1_params(name)).metrics
        cor[name] = m.cor
        worst = max(worst, abs(m.cor - paper[name]))
        lines.append(f"{name:<12}{m.cor:>10.5f}{paper[name]:>11.4f}{m.peak_force_n:>16.1f}")
    gain = cor["none"] ** 2 - 1.0
    verdict = (
        f"At the Table 1 point SDMDC keeps CoR at {cor['SDMDC']:.3f} where no compensation "
        f"gives {cor['none']:.3f} (energy {gain:+.0%}); every CoR within "
        f"{_up(worst)} of the paper's"
    )
    data = {"cor": cor, "cor_paper": {n: paper[n] for n in cor}}
    return DiagramOutput(verdict, lines, data=data)


_DRAW: dict[str, Callable[..., DiagramOutput]] = {
    "hybrid-loop": _hybrid_loop,
    "sampled-rig": _sampled_rig,
    "delay-scenarios": _delay_scenarios,
    "table1-compensators": _table1_compensators,
}


def draw(name: str, out_dir: str | Path, sample_rates_hz: Sequence[float] = ()) -> DiagramOutput:
    """Run diagram ``name`` and write its files into ``out_dir``.

    Parameters
    ----------
    name : str
        One of :data:`DIAGRAMS`.
    out_dir : path
        The output folder (created). ``hybrid-loop`` writes ``hybrid_loop.dot``
        (and ``hybrid_loop.svg`` when Graphviz's ``dot`` is on the path); the
        others write ``NAME.txt`` (their sentence and table).
    sample_rates_hz : sequence of float
        Rig computer rates of ``sampled-rig`` [Hz] (default
        :data:`DEFAULT_SAMPLE_RATES_HZ`).

    Returns
    -------
    DiagramOutput
        The sentence, the table's lines and the files written.
    """
    from hybridtable.errors import ParameterError

    if name not in _DRAW:
        raise ParameterError(f"diagram must be one of {', '.join(DIAGRAMS)} (got {name!r})")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = _DRAW[name](out, sample_rates_hz=sample_rates_hz)
    if name != "hybrid-loop":
        path = out / f"{_stem(name)}.txt"
        write_text_atomic(path, "\n".join([result.verdict, *result.lines]) + "\n")
        result.files.append(path)
    return result
