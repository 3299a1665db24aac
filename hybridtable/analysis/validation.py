"""Linear predictions against the nonlinear simulation, and why they differ.

The predicted CoR ``exp(sigma pi / w_d)`` assumes the contact is one half
period of the linear loop's contact mode. The nonlinear simulation differs in
two ways, separated here for every point whose error exceeds a threshold:

- **transient**: the linear loop started from the state the simulation has
  when the table touches (table lag, empty delay line) is not on the contact
  mode, and the contact lasts while the *table* penetrates (``p_act > 0``),
  not a half period of the mode. ``cor_linear_transient`` runs the Drake
  linear model (bilateral contact, ungated compensator) from the simulation's
  onset state until ``p_act`` returns to zero;
  ``cor_linear - cor_linear_transient`` is this part.
- **gating and separation**: what only the nonlinear loop does, the
  compensator switched off while the measured force is at or below the dead
  band (the MDC term ``k (p_des - p_act)`` waits for the delayed force), the
  unilateral contact, and the delayed force still acting after separation;
  ``cor_linear_transient - cor_sim`` is this part.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.exact_delay import exact_margins
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.analysis.sweep import SweepResult, ValidationPoint
from hybridtable.loop.params import HybridLoopParams

if TYPE_CHECKING:
    from hybridtable.loop.simulation import SimulationResult

__all__ = [
    "EXPLAIN_ABOVE",
    "onset_state",
    "linear_contact_cor",
    "linear_contact_cor_sampled",
    "validation_indices",
    "validate_point",
    "validate_sweep",
]

#: Errors |CoR_linear - CoR_sim| above this get the transient / gating split.
EXPLAIN_ABOVE: float = 0.005


def onset_state(time_s, p_des_m, v_des_m_per_s, p_act_m, v_act_m_per_s) -> dict[str, float]:
    """Loop state where the table first penetrates (``p_act`` crosses 0 upward),
    interpolated linearly between the two samples around the crossing.

    Raises
    ------
    ValueError
        If ``p_act`` never becomes positive.
    """
    p_act = np.asarray(p_act_m, dtype=float)
    pos = np.flatnonzero(p_act > 0.0)
    if pos.size == 0:
        raise ValueError("the table never penetrates")
    k = int(pos[0])
    if k == 0:
        a, k0 = 0.0, 0
    else:
        k0 = k - 1
        a = -p_act[k0] / (p_act[k] - p_act[k0])
    out = {}
    for name, x in (
        ("time_s", time_s),
        ("p_des_m", p_des_m),
        ("v_des_m_per_s", v_des_m_per_s),
        ("p_act_m", p_act_m),
        ("v_act_m_per_s", v_act_m_per_s),
    ):
        x = np.asarray(x, dtype=float)
        out[name] = float(x[k0] + a * (x[k] - x[k0])) if k > 0 else float(x[0])
    return out


def linear_contact_cor(
    linearizer: ContactLoopLinearizer,
    params: HybridLoopParams,
    onset: dict[str, float],
    steps_per_half_period: int = 4000,
) -> float:
    """CoR of the continuous linear loop from a contact-onset state, measured
    when the table's penetration ``p_act`` returns to zero.

    The spacecraft and table states are set from ``onset``; the delay
    (Pade) states are zero, as the force was zero before the contact.
    """
    model = linearizer.open_loop(params)
    blocks = {b.name: b for b in linearizer.blocks(params)}
    sl = linearizer.state_slices(params)
    x = np.zeros(model.A.shape[0])
    sc, tb = blocks["spacecraft"], blocks["table"]
    x[sl["spacecraft"]] = np.linalg.solve(sc.C[:2], [onset["p_des_m"], onset["v_des_m_per_s"]])
    if tb.num_states:
        x[sl["table"]] = np.linalg.solve(tb.C[:2], [onset["p_act_m"], onset["v_act_m_per_s"]])

    def p_act(x: np.ndarray) -> float:
        cmd = sc.C @ x[sl["spacecraft"]]
        return float(tb.C[0] @ x[sl["table"]] + tb.D[0] @ cmd)

    def v_des(x: np.ndarray) -> float:
        return float(sc.C[1] @ x[sl["spacecraft"]])

    w = math.sqrt(params.contact_stiffness_n_per_m / params.spacecraft_mass_kg)
    dt = math.pi / w / steps_per_half_period
    E = expm(model.closed_loop_matrix() * dt)
    v_in = v_des(x)
    prev, p_prev = x, p_act(x)
    entered = p_prev > 0.0
    for _ in range(4 * steps_per_half_period):
        nxt = E @ prev
        p = p_act(nxt)
        if p > 0.0:
            entered = True
        elif entered:
            a = p_prev / (p_prev - p)
            v_out = v_des(prev) + a * (v_des(nxt) - v_des(prev))
            return abs(v_out) / abs(v_in)
        prev, p_prev = nxt, p
    return math.nan


def linear_contact_cor_sampled(
    linearizer: SampledLoopLinearizer,
    params: HybridLoopParams,
    time_s,
    p_des_m,
    v_des_m_per_s,
    p_act_m,
    v_act_m_per_s,
) -> float:
    """CoR of the sampled linear loop from the first tick at which the table
    penetrates, measured when ``p_act`` returns to zero (interpolated between
    ticks).

    The arrays are a sampled run in the ``hybridtable-run/1`` row semantics
    (row ``k``: ``p_act`` read at tick ``k``, spacecraft state after the
    tick's update). At the first tick ``k`` with ``p_act > 0`` the model
    starts from the spacecraft state before the update (row ``k - 1``), the
    table state of row ``k``, the command held since tick ``k - 1``, an empty
    delay line and lead memory (no force was measured before).

    Raises
    ------
    ValueError
        If the table never penetrates, or does at the first tick.
    """
    p_act = np.asarray(p_act_m, dtype=float)
    pos = np.flatnonzero(p_act > 0.0)
    if pos.size == 0 or pos[0] == 0:
        raise ValueError("no contact onset after the first tick")
    k = int(pos[0])
    model = linearizer.open_loop(params)
    blocks = {b.name: b for b in linearizer.blocks(params)}
    sl = linearizer.state_slices(params)
    sc, plant = blocks["spacecraft"], blocks["plant"]
    cmd = np.array([p_des_m[k - 1], v_des_m_per_s[k - 1]], dtype=float)
    x = np.zeros(model.A.shape[0])
    x[sl["spacecraft"]] = np.linalg.solve(sc.C[:2], cmd)
    n_tab = plant.num_states - 2
    xp = np.zeros(plant.num_states)
    xp[n_tab:] = cmd  # command held over the previous interval
    if n_tab:
        # Table state: solve the plant's p, v outputs for the table part.
        rhs = np.array([p_act[k], v_act_m_per_s[k]], dtype=float) - plant.C[:2, n_tab:] @ cmd
        xp[:n_tab] = np.linalg.solve(plant.C[:2, :n_tab], rhs)
    x[sl["plant"]] = xp
    A = model.closed_loop_matrix()

    def p_act_of(x: np.ndarray) -> float:
        return float(plant.C[0] @ x[sl["plant"]])

    def v_des_of(x: np.ndarray) -> float:
        return float(sc.C[1] @ x[sl["spacecraft"]])

    v_in = v_des_of(x)
    prev, p_prev = x, p_act_of(x)
    n_max = 4 * int(math.ceil(0.5 / params.contact_frequency_hz / params.sample_period_s)) + 10
    for _ in range(n_max):
        nxt = A @ prev
        p = p_act_of(nxt)
        if p <= 0.0:
            a = p_prev / (p_prev - p)
            return abs(v_des_of(prev) + a * (v_des_of(nxt) - v_des_of(prev))) / abs(v_in)
        prev, p_prev = nxt, p
    return math.nan


def validation_indices(nd: int, nt: int, n: int) -> list[tuple[int, int]]:
    """``n`` distinct indices spread over an ``nd x nt`` grid: the four
    corners, then a Halton sequence (bases 2 and 3)."""

    def halton(k: int, base: int) -> float:
        f, r = 1.0, 0.0
        while k > 0:
            f /= base
            r += f * (k % base)
            k //= base
        return r

    n = min(n, nd * nt)
    picked: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()

    def add(ij: tuple[int, int]) -> None:
        if len(picked) < n and ij not in seen:
            picked.append(ij)
            seen.add(ij)

    for ij in ((0, 0), (nd - 1, nt - 1), (0, nt - 1), (nd - 1, 0)):
        add(ij)
    k = 1
    while len(picked) < n:
        add((min(int(halton(k, 2) * nd), nd - 1), min(int(halton(k, 3) * nt), nt - 1)))
        k += 1
    return picked


def validate_point(
    params: HybridLoopParams,
    cor_linear: float,
    linearizer: ContactLoopLinearizer | None = None,
    exact: bool = True,
    explain_above: float = EXPLAIN_ABOVE,
    ij: tuple[int, int] = (-1, -1),
    simulate_fn: Callable[[HybridLoopParams], SimulationResult] | None = None,
) -> ValidationPoint:
    """Simulate ``params`` (nonlinear loop) and compare with ``cor_linear``;
    split errors above ``explain_above`` into transient and gating parts.

    ``simulate_fn(params)`` replaces :func:`hybridtable.loop.simulation.simulate`
    (e.g. a rig model's loop, whose physics ``params`` stand for in the
    linear model)."""
    from hybridtable.errors import SimulationError
    from hybridtable.loop.simulation import simulate

    lin = linearizer or ContactLoopLinearizer()
    sampled = params.sample_rate_hz is not None
    common = dict(
        compensator=params.compensator,
        i=ij[0],
        j=ij[1],
        sensor_delay_s=params.sensor_delay_s,
        table_response_hz=params.table_response_hz,
        cor_linear=float(cor_linear),
    )
    cor_exact = None
    if exact and not sampled:
        try:
            cor_exact = exact_margins(lin, params).predicted_cor
        except RuntimeError:
            cor_exact = None
    try:
        sim = simulate(params) if simulate_fn is None else simulate_fn(params)
    except SimulationError as err:
        return ValidationPoint(
            **common, cor_sim=None, abs_error=None, cor_exact_delay=cor_exact, error=str(err)
        )
    cor_sim = float(sim.metrics.cor)
    err = abs(cor_linear - cor_sim)
    transient = cause = None
    if err > explain_above:
        runs = (sim.time_s, sim.p_des_m, sim.v_des_m_per_s, sim.p_act_m, sim.v_act_m_per_s)
        try:
            if sampled:
                transient = linear_contact_cor_sampled(SampledLoopLinearizer(lin), params, *runs)
            else:
                transient = linear_contact_cor(lin, params, onset_state(*runs))
        except ValueError:
            transient = None
        if transient is not None and math.isfinite(transient):
            part_transient = abs(cor_linear - transient)
            part_gating = abs(transient - cor_sim)
            cause = "transient" if part_transient >= part_gating else "gating and separation"
    return ValidationPoint(
        **common,
        cor_sim=cor_sim,
        abs_error=err,
        cor_exact_delay=cor_exact,
        cor_linear_transient=transient,
        cause=cause,
    )


def validate_sweep(
    result: SweepResult,
    n_points: int,
    compensators: Sequence[str] | None = None,
    exact: bool = True,
    explain_above: float = EXPLAIN_ABOVE,
    progress: bool = False,
    simulate_fn: Callable[[HybridLoopParams], SimulationResult] | None = None,
) -> list[ValidationPoint]:
    """Validate ``n_points`` grid points (:func:`validation_indices`) for each
    compensator; appends to ``result.validation`` and returns the new points.
    A failed simulation (divergence, no separation) is kept with ``error``.

    With a ``result.transform`` the linear figures are those of the
    transformed parameters and ``simulate_fn`` (called with the grid point's
    parameters, before the transform; default: ``simulate`` of the
    transformed ones) runs the nonlinear loop."""
    comps = list(compensators or result.compensators)
    idx = validation_indices(result.sensor_delay_s.size, result.table_response_hz.size, n_points)
    lin = ContactLoopLinearizer(result.pade_order or 3)
    jobs = [(c, i, j) for (i, j) in idx for c in comps]
    if progress:
        from tqdm import tqdm

        jobs = tqdm(jobs, desc="validate", unit="sim", leave=False, file=sys.stderr)
    points = []
    for c, i, j in jobs:
        p = result.base.with_(
            compensator=c,
            sensor_delay_s=float(result.sensor_delay_s[i]),
            table_response_hz=float(result.table_response_hz[j]),
        )
        cor = float(result.compensators[c].predicted_cor[i, j])
        if result.transform is None:
            points.append(validate_point(p, cor, lin, exact, explain_above, (i, j)))
            continue
        run = None if simulate_fn is None else (lambda _q, p=p: simulate_fn(p))
        q = result.transform(p)
        point = validate_point(q, cor, lin, exact, explain_above, (i, j), simulate_fn=run)
        points.append(replace(point, sensor_delay_s=p.sensor_delay_s))
    result.validation.extend(points)
    return points
