"""The margins at one operating point, the plain verdict and the console text of
``hybridtable margins``.

- :func:`point_margins`: per compensator at one (sensor delay, table
  frequency) point: predicted CoR and energy growth per contact, the classical
  gain / phase / delay margins (:mod:`hybridtable.analysis.robustness`, loop
  broken at the spacecraft model's force input), the critical sensor delay
  and the delay up to which the predicted CoR stays within a limit;
- :func:`margins_verdict`: the one sentence the console opens with. An
  undamped contact is marginal by construction (its poles sit on the
  imaginary axis without delay, any net delay pushes them right), so the
  sentence then speaks of the CoR over the grid; a damped one has a
  meaningful critical delay, and the sentence gives it;
- :func:`format_point`, :func:`format_grid`: the console lines;
  :func:`point_markdown`: the same point in the report.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hybridtable.analysis.linearize import LinearLoop
from hybridtable.analysis.margins import (
    LoopMargins,
    critical_sensor_delay,
    growth_of,
    loop_margins,
)
from hybridtable.analysis.robustness import (
    BROKEN_AT,
    DEFAULT_COR_LIMIT,
    GainDelayMargins,
    cor_limited_delay,
    gain_delay_margins,
    predicted_cor_of,
)
from hybridtable.analysis.sweep import SweepResult, model_function
from hybridtable.loop.params import HybridLoopParams

__all__ = [
    "MEANING",
    "PointMargins",
    "point_margins",
    "margins_verdict",
    "format_point",
    "format_grid",
    "point_markdown",
]

#: What the figures at the operating point mean (console, JSON, report).
MEANING = {
    "loop": "broken " + BROKEN_AT,
    "gain_margin": "factor by which the force fed to the spacecraft model may grow (a force-path "
    "gain error, or a spacecraft model gm times lighter) before the loop is unstable; below 1 "
    "for an unstable loop: the factor it must shrink to; python-control's stability_margins",
    "delay_margin_s": "phase margin / gain crossover: the extra delay of the whole force "
    "feedback path (no lead following it) the loop tolerates; negative: the lead it lacks",
    "critical_delay_s": "smallest sensor delay with an unstable loop (the lead follows the "
    "delay unless a lead time is fixed); 0: not stable at zero delay",
    "cor_limited_delay_s": "largest sensor delay up to which the predicted CoR stays within "
    "the CoR limit; 0: exceeded at zero delay; inf: within it up to the search limit",
    "undamped": "an undamped contact is marginal by construction: a perfect rig leaves its "
    "poles on the imaginary axis at every gain (phase -180 deg at every frequency, no gain "
    "margin, phase and delay margin 0); any net delay pushes them right, so the critical "
    "delay is 0 and the figures that matter are the CoR and the delay a CoR limit allows",
}


@dataclass
class PointMargins:
    """Every figure of :func:`point_margins`, per compensator (SI units)."""

    sensor_delay_s: float
    table_response_hz: float
    cor_limit: float
    max_delay_s: float
    kind: str
    params: dict[str, HybridLoopParams] = field(default_factory=dict)
    loops: dict[str, LinearLoop] = field(default_factory=dict, repr=False)
    margins: dict[str, LoopMargins] = field(default_factory=dict)
    robust: dict[str, GainDelayMargins] = field(default_factory=dict)
    critical_delay_s: dict[str, float] = field(default_factory=dict)
    cor_limited_delay_s: dict[str, float] = field(default_factory=dict)
    cor_at_zero_delay: dict[str, float] = field(default_factory=dict)

    @property
    def undamped(self) -> bool:
        """The contact of the linear loop (after any model) has no damping."""
        return all(p.contact_damping_n_s_per_m == 0.0 for p in self.params.values())

    def to_dict(self) -> dict:
        comps = {}
        for c in self.params:
            m = self.margins[c]
            comps[c] = {
                "predicted_cor": m.predicted_cor,
                "energy_growth_per_contact": m.energy_growth_per_contact,
                "damping_ratio": m.damping_ratio,
                **self.robust[c].to_dict(),
                "critical_delay_s": self.critical_delay_s[c],
                "cor_limited_delay_s": self.cor_limited_delay_s[c],
                "cor_at_zero_delay": self.cor_at_zero_delay[c],
            }
        return {
            "sensor_delay_s": self.sensor_delay_s,
            "table_response_hz": self.table_response_hz,
            "model": self.kind,
            "cor_limit": self.cor_limit,
            "search_max_delay_s": self.max_delay_s,
            "contact_damped": not self.undamped,
            "compensators": comps,
            "meaning": dict(MEANING),
        }


def point_margins(
    base: HybridLoopParams,
    compensators,
    sensor_delay_s: float,
    table_response_hz: float,
    pade_order: int = 3,
    cor_limit: float = DEFAULT_COR_LIMIT,
    transform: Callable[[HybridLoopParams], HybridLoopParams] | None = None,
    linearizer=None,
) -> PointMargins:
    """The figures of :class:`PointMargins` at ``(sensor_delay_s,
    table_response_hz)``, the rest from ``base`` (sampled when it has a sample
    rate; ``transform``: a model's physics, as in
    :func:`~hybridtable.sweeps.margins_grid.sweep_margins`). The searches run up to
    a quarter contact period."""
    bare, _ = model_function(base, pade_order, linearizer)
    model = bare if transform is None else (lambda p: bare(transform(p)))
    max_delay = 0.25 / base.contact_frequency_hz
    out = PointMargins(
        sensor_delay_s,
        table_response_hz,
        cor_limit,
        max_delay,
        "sampled" if base.sample_rate_hz is not None else "continuous",
    )
    cor, growth = predicted_cor_of(model), growth_of(model)
    for c in compensators:
        p = base.with_(
            compensator=c, sensor_delay_s=sensor_delay_s, table_response_hz=table_response_hz
        )
        loop = model(p)
        out.loops[c] = loop
        out.params[c] = loop.params
        out.margins[c] = loop_margins(loop, "fast")
        out.robust[c] = gain_delay_margins(loop)
        out.critical_delay_s[c] = critical_sensor_delay(growth, p, max_delay_s=max_delay)
        out.cor_limited_delay_s[c] = cor_limited_delay(cor, p, cor_limit, max_delay)
        out.cor_at_zero_delay[c] = cor(p.with_(sensor_delay_s=0.0))
    return out


# -- text ------------------------------------------------------------------------------


def _label(c: str) -> str:
    return "without compensation" if c == "none" else f"with {c}"


def _ms(x: float, spec: str = ".3g") -> str:
    return f"{x * 1e3:{spec}} ms"


def margins_verdict(result: SweepResult, point: PointMargins) -> str:
    """One plain sentence: for an undamped contact, that it is marginal at any
    delay and where the predicted CoR goes over the grid; for a damped one,
    the sensor delay each compensator keeps the loop stable below, at the
    operating point's table frequency."""
    comps = list(point.params)
    if point.undamped:
        top = {}
        for c in comps:
            cor = result.compensators[c].predicted_cor
            top[c] = float(np.nanmax(cor)) if np.isfinite(cor).any() else math.nan
        best = min(comps, key=lambda c: top[c] if math.isfinite(top[c]) else math.inf)
        cor = result.compensators[best].predicted_cor
        lo = float(np.nanmin(cor)) if np.isfinite(cor).any() else math.nan
        line = (
            f"margins: an undamped contact is marginal at any delay; {_label(best)} the predicted "
            f"CoR stays within {lo:.3f}-{top[best]:.3f} over the grid"
        )
        worst = "none" if "none" in comps else max(comps, key=lambda c: top[c])
        if worst != best:
            line += f", {_label(worst)} it reaches {top[worst]:.2f}"
        return line
    parts, never = [], []
    top = _ms(point.max_delay_s, "g")
    for c in comps:
        d = point.critical_delay_s[c]
        if d == 0.0:
            never.append(_label(c))
        elif math.isinf(d):
            parts.append(f"at every delay up to {top} {_label(c)}")
        else:
            parts.append(f"below {_ms(d)} {_label(c)}")
    head = f"margins: at table {point.table_response_hz:g} Hz the loop "
    if not parts:
        return head + f"is unstable even at zero delay {_join(never)}"
    line = head + f"is stable for sensor delays {_join(parts)}"
    if never:
        line += f", and unstable even at zero delay {_join(never)}"
    return line


def _join(parts: list[str]) -> str:
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _hz(w: float) -> str:
    return f"{w / (2 * math.pi):.3f} Hz"


def _gm_text(g: GainDelayMargins) -> str:
    if not g.closed_loop_stable and not g.gain_margin < 1.0:
        return "- (loop unstable)"
    if math.isinf(g.gain_margin):
        return "inf (no crossing)"
    return f"{g.gain_margin:.3g} ({g.gain_margin_db:+.1f} dB) @ {_hz(g.phase_crossover_rad_per_s)}"


def _pm_text(g: GainDelayMargins) -> str:
    if not math.isfinite(g.phase_margin_deg):
        return "- (no crossover)"
    return f"{g.phase_margin_deg:+.3g} deg @ {_hz(g.gain_crossover_rad_per_s)}"


def _dm_text(g: GainDelayMargins) -> str:
    return "-" if not math.isfinite(g.delay_margin_s) else f"{g.delay_margin_s * 1e3:+.3g} ms"


def _limited_text(point: PointMargins, c: str) -> str:
    x = point.cor_limited_delay_s[c]
    if x == 0.0 and point.cor_at_zero_delay[c] > point.cor_limit:
        return "exceeded at 0 ms"
    if math.isinf(x):
        return f"> {_ms(point.max_delay_s, 'g')}"
    return _ms(x)


def _crit_text(point: PointMargins, c: str) -> str:
    x = point.critical_delay_s[c]
    if x == 0.0:
        return "never"
    return f"> {_ms(point.max_delay_s, 'g')}" if math.isinf(x) else _ms(x)


def _rows(point: PointMargins) -> tuple[list[str], list[list[str]]]:
    head = ["compensator", "CoR", "energy/contact", f"CoR<={point.cor_limit:g} up to"]
    if not point.undamped:
        head.append("stable below")
    head += ["gain margin", "phase margin", "delay margin"]
    rows = []
    for c in point.params:
        m, g = point.margins[c], point.robust[c]
        row = [c, f"{m.predicted_cor:.5f}", f"{m.energy_growth_per_contact * 100:+.3g} %"]
        row.append(_limited_text(point, c))
        if not point.undamped:
            row.append(_crit_text(point, c))
        row += [_gm_text(g), _pm_text(g), _dm_text(g)]
        rows.append(row)
    return head, rows


def _point_title(point: PointMargins) -> str:
    return (
        f"at sensor delay {point.sensor_delay_s * 1e3:g} ms, table {point.table_response_hz:g} "
        f"Hz ({point.kind} model; loop broken at the spacecraft model's force input, L = -G):"
    )


def format_point(point: PointMargins) -> list[str]:
    """The operating point as console lines: a title, a table, what the
    margins mean."""
    head, rows = _rows(point)
    width = [max(len(r[k]) for r in [head, *rows]) for k in range(len(head))]
    lines = [_point_title(point)]
    for r in [head, *rows]:
        lines.append("  " + "  ".join(v.ljust(w) for v, w in zip(r, width, strict=True)).rstrip())
    notes = [
        "gain margin: the factor by which the force fed to the spacecraft model (or 1 / its "
        "mass) may grow before the loop is unstable. delay margin = phase margin / crossover: "
        "the extra delay of the whole force path the loop tolerates with the compensators' lead "
        "fixed (negative: lead missing); 'stable below' grows the sensor delay with the SDC "
        "lead following it, as a rig set up for that delay would.",
    ]
    if point.undamped:
        notes.append(
            "Undamped contact: with a perfect rig L = k / (m s^2) has a phase of -180 deg at "
            "every frequency and the contact is marginal at every gain, so there is no gain "
            "margin; phase and delay margin measure the rig's net lag at the contact crossover."
        )
    for note in notes:
        lines += textwrap.wrap(note, 100, initial_indent="  ", subsequent_indent="  ")
    return lines


def _range_ms(x: np.ndarray, grid_max_s: float) -> str:
    x = np.asarray(x, dtype=float)
    if x.size == 0 or np.isnan(x).all():
        return "-"
    lo, hi = float(np.nanmin(x)), float(np.nanmax(x))

    def one(v: float) -> str:
        return f">{grid_max_s * 1e3:g}" if math.isinf(v) else f"{v * 1e3:.3g}"

    return one(lo) if lo == hi else f"{one(lo)}-{one(hi)}"


def format_grid(
    result: SweepResult, sweep_wall_s: float, limits: dict, cor_limit: float, undamped: bool
) -> list[str]:
    """The grid as console lines: per compensator the CoR range, the largest
    energy growth per contact, the range over the table frequencies of the
    delay a CoR limit allows and, for a damped contact, the stable points and
    the critical delays."""
    kind = (
        f"sampled at {result.base.sample_rate_hz:g} Hz"
        if result.sampled
        else f"Pade order {result.pade_order}"
    )
    lines = [
        f"grid {result.sensor_delay_s.size} delays x {result.table_response_hz.size} table "
        f"frequencies, {kind}: {sweep_wall_s:.1f} s"
    ]
    dmax = float(np.max(result.sensor_delay_s))
    head = f"  {'compensator':12s} {'CoR min':>8s} {'CoR max':>8s} {'energy/contact max':>19s} "
    head += f"{f'CoR<={cor_limit:g} up to [ms]':>22s}"
    if not undamped:
        head += f" {'stable':>11s} {'crit. delay [ms]':>17s}"
    lines.append(head)
    for c, cs in result.compensators.items():
        cor = cs.predicted_cor[np.isfinite(cs.predicted_cor)]
        eg = float(np.nanmax(cs.energy_growth_per_contact))
        line = (
            f"  {c:12s} {cor.min():8.5f} {cor.max():8.5f} {f'{eg * 100:+.3g} %':>19s} "
            f"{_range_ms(limits[c]['cor_limited_delay_s'], dmax):>22s}"
        )
        if not undamped:
            stable = f"{int(cs.stable.sum())}/{cs.stable.size}"
            crit = cs.critical_delay_s
            line += (
                f" {stable:>11s} {_range_ms(crit, 0.25 / result.base.contact_frequency_hz):>17s}"
            )
        lines.append(line)
    notes = [
        f"CoR<={cor_limit:g} up to: over the grid's table frequencies, the largest sensor delay "
        f"with the predicted CoR within {cor_limit:g} (0: above it at zero delay already; "
        f">{dmax * 1e3:g}: within it over the whole grid)."
    ]
    if undamped:
        notes.append(
            "No point is stable and every critical delay is 0: an undamped contact is marginal "
            "at best; the CoR says how much energy a contact gains."
        )
    for note in notes:
        lines += textwrap.wrap(note, 100, initial_indent="  ", subsequent_indent="  ")
    if result.validation:
        err = result.max_validation_error()
        n_fail = sum(v.abs_error is None for v in result.validation)
        lines.append(
            f"validation: {len(result.validation)} simulations, max |CoR_linear - CoR_sim| "
            f"= {err:.5f}" + (f", {n_fail} failed" if n_fail else "")
            if err is not None
            else f"validation: all {n_fail} simulations failed"
        )
    return lines


def point_markdown(point: PointMargins) -> list[str]:
    """The operating point as a Markdown section of the report."""
    head, rows = _rows(point)
    L = [
        f"## At the operating point: sensor delay {point.sensor_delay_s * 1e3:g} ms, table "
        f"{point.table_response_hz:g} Hz",
        "",
        f"The loop is broken {BROKEN_AT}. Margins by python-control's `stability_margins` of "
        f"L = -G ({point.kind} model).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    L += ["| " + " | ".join(r) + " |" for r in rows]
    L += ["", f"- gain margin: {MEANING['gain_margin']};"]
    L += [f"- delay margin: {MEANING['delay_margin_s']};"]
    L += [f"- CoR <= {point.cor_limit:g} up to: {MEANING['cor_limited_delay_s']}."]
    if point.undamped:
        L += [
            "",
            "Undamped contact: a perfect rig leaves the contact poles on the imaginary axis at "
            "every gain (L = k / (m s^2), phase -180 deg at every frequency), so there is no gain "
            "margin (the gain margins python-control finds here, in the JSON, are where the phase "
            "wraps past -540 deg, of no meaning for a loop unstable at every gain); phase and "
            "delay margin measure the rig's net lag at the contact crossover.",
        ]
    L.append("")
    return L
