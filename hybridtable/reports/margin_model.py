"""``margins --model``: the rig's operating point with and without its model file.

:func:`model_operating_point` sets, at the rig's own operating point, the
nominal model's predicted CoR against the model's, and the model's against a
simulation of the whole model; :func:`model_verdict` and
:func:`format_model_point` say it in words (the console opens with the verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

from hybridtable.analysis.margins import loop_margins
from hybridtable.analysis.sweep import ValidationPoint, model_function
from hybridtable.analysis.validation import EXPLAIN_ABOVE, validate_point
from hybridtable.loop.params import HybridLoopParams

__all__ = ["ModelPoint", "model_operating_point", "model_verdict", "format_model_point"]


def _fmt(x, spec: str = ".5f") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec)


@dataclass
class ModelPoint:
    """The rig's operating point with and without the model, per compensator:
    ``params`` (nominal physics), the linear figures (``nominal``, ``model``),
    the linear CoR against the nonlinear loop (``nominal_sim``, ``model_sim``:
    the whole model), what the linear models leave out (``left_out``, words)
    and the linear loop's parameters the model changes (name -> (nominal, model))."""

    params: dict[str, HybridLoopParams]
    nominal: dict[str, dict]
    model: dict[str, dict]
    nominal_sim: dict[str, ValidationPoint]
    model_sim: dict[str, ValidationPoint]
    left_out: list[str]
    linear_changes: dict[str, tuple]

    def to_dict(self) -> dict:
        return {
            c: {
                "cor_nominal": self.nominal[c]["predicted_cor"],
                "cor_model": self.model[c]["predicted_cor"],
                "cor_model_simulated": self.model_sim[c].cor_sim,
                "cor_nominal_simulated": self.nominal_sim[c].cor_sim,
                "stable_nominal": self.nominal[c]["stable"],
                "stable_model": self.model[c]["stable"],
                "model_simulation": self.model_sim[c].to_dict(),
            }
            for c in self.params
        }


def model_operating_point(
    model, base: HybridLoopParams, compensators, pade_order: int = 3
) -> ModelPoint:
    """Linear figures of the nominal model and of ``model`` at the model's nominal
    delay and table frequency (the rest from ``base``), each against its nonlinear
    loop (``validate_point``; the model's: ``simulate_model``)."""
    from hybridtable.studies.model_compensators import model_transform, simulate_model

    point = base.with_(
        sensor_delay_s=model.nominal.sensor_delay_s,
        table_response_hz=model.nominal.table_natural_frequency_hz,
    )
    fn, lin = model_function(point, pade_order)
    transform = model_transform(model)
    left = list(model.linear_params(point.with_(sample_rate_hz=None))[1])
    lin_point, exact = transform(point), transform(point.with_(sample_rate_hz=None))
    if lin_point.sensor_delay_s != exact.sensor_delay_s:
        left.append(
            f"the sensor delay's fraction of a tick ({exact.sensor_delay_s * 1e3:.4g} ms taken "
            f"as {lin_point.sensor_delay_s * 1e3:.4g} ms, whole ticks of the sampled model)"
        )
    linear = lin_point.quantities()
    changes = {k: (v, linear[k]) for k, v in point.quantities().items() if v != linear[k]}
    out = ModelPoint({}, {}, {}, {}, {}, left, changes)
    for c in compensators:
        p = point.with_(compensator=c)
        q = transform(p)
        out.params[c] = p
        out.nominal[c] = loop_margins(fn(p), pm_method="fast").to_dict()
        out.model[c] = loop_margins(fn(q), pm_method="fast").to_dict()
        out.nominal_sim[c] = validate_point(p, out.nominal[c]["predicted_cor"], lin)
        sim = partial(lambda p, _q: simulate_model(model, p), p)
        out.model_sim[c] = validate_point(q, out.model[c]["predicted_cor"], lin, simulate_fn=sim)
    return out


def model_verdict(point: ModelPoint, model) -> str:
    """One plain line: where the model moves the predicted CoR, and with
    which compensators the modelled rig is stable at its operating point."""
    comps = list(point.params)
    p0 = point.params[comps[0]]
    delta = {c: point.model[c]["predicted_cor"] - point.nominal[c]["predicted_cor"] for c in comps}
    if all(d < 0 for d in delta.values()):
        moves = "lowers the predicted CoR of every compensator"
    elif all(d > 0 for d in delta.values()):
        moves = "raises the predicted CoR of every compensator"
    elif all(abs(d) < 5e-5 for d in delta.values()):
        moves = "leaves the predicted CoR where the nominal model has it"
    else:
        moves = "moves the predicted CoR (" + ", ".join(f"{c} {delta[c]:+.4f}" for c in comps) + ")"
    show = model.nominal.compensator if model.nominal.compensator in comps else comps[-1]
    unstable = [c for c in comps if not point.model[c]["stable"]]
    stable = ", ".join(c for c in comps if c not in unstable) or "no compensator"
    line = (
        f"The model {moves} at the rig's operating point ({p0.sensor_delay_s * 1e3:g} ms, table "
        f"{p0.table_response_hz:g} Hz; {show} {point.nominal[show]['predicted_cor']:.4f} -> "
        f"{point.model[show]['predicted_cor']:.4f}): the loop is stable with {stable}"
        + (f" and unstable with {', '.join(unstable)}" if unstable else "")
    )
    if point.left_out:
        line += f"; the linear model leaves {len(point.left_out)} part(s) of the model out"
    return line


def format_model_point(point: ModelPoint, model, path: str) -> list[str]:
    """The verdict and the operating point, as text lines."""
    comps = list(point.params)
    p0 = point.params[comps[0]]
    kind = f"sampled at {p0.sample_rate_hz:g} Hz" if p0.sample_rate_hz else "continuous"
    lead, changed = p0.lead_time_s, point.linear_changes.items()
    lines = [
        model_verdict(point, model),
        f"model {path}: {model.describe()}",
        f"operating point: sensor delay {p0.sensor_delay_s * 1e3:g} ms, table "
        f"{p0.table_response_hz:g} Hz / {p0.table_damping_ratio:g}, k "
        f"{p0.contact_stiffness_n_per_m:g} N/m, m {p0.spacecraft_mass_kg:g} kg, lead "
        + ("= delay" if lead is None else f"{lead * 1e3:g} ms")
        + f", approach {p0.initial_velocity_m_per_s:g} m/s, {kind}",
        "predicted CoR, nominal -> model (linear); simulated (nonlinear loop: nominal, whole "
        "model; the model's simulated minus linear CoR):",
    ]
    for c in comps:
        sim, nom = point.model_sim[c], point.nominal_sim[c].cor_sim
        simulated = "simulated: nominal " + ("failed" if nom is None else f"{nom:.4f}")
        if sim.cor_sim is None:
            simulated += f", model failed ({sim.error})"
        else:
            simulated += f", model {sim.cor_sim:.4f} ({sim.cor_sim - sim.cor_linear:+.4f}"
            cause = sim.cause or ""
            if cause and point.left_out:
                cause = "what the linear model leaves out, " + cause
            simulated += f": {cause})" if sim.abs_error > EXPLAIN_ABOVE and cause else ")"
        lines.append(
            f"  {c}: nominal {point.nominal[c]['predicted_cor']:.4f} -> model "
            f"{point.model[c]['predicted_cor']:.4f}; {simulated}"
        )
    lines.append(
        "linear loop: "
        + (
            ", ".join(f"{k} {_fmt(a, 'g')} -> {_fmt(b, 'g')}" for k, (a, b) in changed)
            or "the nominal one"
        )
        + "; left out: "
        + ("; ".join(point.left_out) or "nothing (every effect is in it)")
    )
    return lines
