"""The fast path of one hybrid-loop run: the diagram's rig computer as an exact discrete update.

The Drake diagram (:func:`hybridtable.loop.simulation.simulate`) stays the model
of record; :func:`simulate_fast` reproduces its contact metrics, in a few
milliseconds, for the parameters :func:`fast_unsupported` accepts.

Why it is exact: the rig computer is discrete with period ``h`` (the delay
line's ``h = T / (N + 1/2)``, or the sample period). Between two ticks the
measured force and the lead's stored sample are held, and the continuous states
(spacecraft ``p_des, v_des`` of a continuous loop, table ``p_act, v_act``)
obey linear ODEs: the contact force enters the loop only through the delay
line's samples. A tick is one matrix exponential of ``[p_des, v_des, p_act,
v_act, u]`` (``u``: the held force term), computed once per run. Where the
force law switches inside a tick (no delay: the gate follows the contact;
``contact_gate="table_position"`` or ``clamp_nonnegative`` with the MDC term)
the switching instant is found on the exact trajectory (Brent's method).

What tick ``k`` reads (Drake's discrete updates at ``t_k`` all read the
context before any of them; the first tick is ``t = 0``): in a continuous loop
the delay line samples ``F[k] = f_act(t_k)`` and outputs ``F[k - N]`` until
``t_k+1``, the lead's stored sample is ``F[k - N - 1]`` (no delay: ``f_act(t)``
itself, and ``f_act(t_k)``); in a sampled loop (delay ``M`` ticks) the
compensator reads ``F[k - M]``, the table at ``t_k`` and the command ``s_k``,
and the spacecraft steps (semi-implicit Euler) to ``s_k+1``, which the table
follows, held, until ``t_k+1``.

The record differs from the diagram's: the diagram logs every integrator step
of a continuous loop, the fast path the ticks (before their update, as the
diagram does there). The CoR is the same up to the diagram integrator's error
(``v_in`` and ``v_out`` are read where no force acts); the peak forces may
differ by the force's change within a tick, the contact duration by a tick.
The stop rule of :func:`~hybridtable.loop.simulation.run_loop` is evaluated at
the first tick at or after each of its check times. :func:`record_fast` gives
a sampled loop's rows for a record's length (``simulate_rig``'s closed loop).

Why one module: the continuous and the sampled runner are one engine; they
share the compensator's law and gains (``_law``), the computer's period and
the stop rule checked at ticks, which split apart would be private names
imported across modules.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import replace

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

from hybridtable.compensators.paper import COMPENSATORS, compensation_law
from hybridtable.errors import ParameterError, SimulationError
from hybridtable.laws.compensation import CompensationLaw, backward_difference, compensate
from hybridtable.laws.separation import SeparationRule
from hybridtable.laws.spacecraft import computer_step
from hybridtable.laws.table import second_order_matrices, second_order_tick
from hybridtable.loop.budget import check_budget
from hybridtable.loop.builder import LOG_ROWS
from hybridtable.loop.metrics import ContactMetrics, contact_metrics
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import (
    SimulationResult,
    default_t_max_s,
    expected_duration_s,
    result_from_rows,
    separation_rule,
)
from hybridtable.loop.ticks import (
    CONTACT,
    MDC,
    OFF,
    ON,
    bound,
    compensator_function,
    compile_loops,
    contact_function,
    mode_function,
    tick_law,
    tick_loop,
)
from hybridtable.systems.sensor import continuous_delay_period, sample_taps

__all__ = ["fast_unsupported", "prepare_fast", "record_fast", "simulate_fast"]


def fast_unsupported(params: HybridLoopParams) -> str | None:
    """Why :func:`simulate_fast` cannot reproduce the diagram for ``params``, or None.

    Returns
    -------
    str or None
        None when the fast path applies; otherwise one plain phrase naming the
        feature it does not model (e.g. ``"the passivity guard"``).
    """
    if params.compensator not in COMPENSATORS:
        return (
            f"a plug-in compensator ({params.compensator!r}); the fast path models the "
            "paper's none, SDC, MDC and SDMDC only"
        )
    if params.passivity:
        return "the passivity guard (its energy observer is not a linear update)"
    return None


class _StopRule(SeparationRule):
    """The diagram's :class:`~hybridtable.laws.separation.SeparationRule`, checked
    at the first tick at or after each of its check times."""

    def __init__(self, *args, period_s: float, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.eps = 1e-6 * period_s
        self.touched = False

    @property
    def due(self) -> float:
        """The first tick at or after this time is the next check [s]."""
        return self.next_check_s - self.eps

    def check_tick(self, ticks: int, f_act: float, f_mea: float, f_comp: float) -> bool:
        """The rule at the check time; True when the run ends here. The
        diagram's integrator takes at least a step per tick: the same step budget."""
        forces = (f_act, f_mea, f_comp)
        return self.check(
            ticks,
            abs(f_comp),
            active=f_act > 0.0 or f_mea > self.deadband or f_comp != 0.0,
            touched=self.touched,
            finite=all(math.isfinite(x) for x in forces),
            forces_n=forces,
        )


def _law(params: HybridLoopParams) -> tuple[CompensationLaw, float, float | None]:
    """The compensator's law and its MDC gains ``(k, c)`` (``c`` None: no rate
    term); an ideal table has no response error, so no MDC term."""
    cp = params.compensator_params()
    law = compensation_law(cp)
    if params.plant.table.is_ideal:  # p_des - p_act = 0
        law = replace(law, motion_correction=False)
    c = cp.damping_n_s_per_m
    return law, cp.stiffness_n_per_m, (c if c > 0.0 else None)


def _rows(law: CompensationLaw, h: float, k: float, c: float | None, basis: np.ndarray):
    """The law between its switches as rows over ``basis`` signals: the law
    evaluated once on unit vectors (it is linear there), so the ticks need no
    call. ``basis`` rows: the measured force, its previous sample, ``p_des``,
    ``v_des``, ``p_act``, ``v_act``. Returns the rows with and without the MDC
    term."""
    f, prev, p, v, pa, va = basis
    rate = backward_difference(f, prev, h)
    with_mdc = compensate(law.linear(), f, rate, p - pa, v - va, k, c)
    without = compensate(law.linear(motion_correction=False), f, rate)
    return with_mdc, without


def _unrolled(coefficients):
    """``z -> E z`` for the first four rows of ``E`` (its last row keeps ``u``), given
    as 20 numbers row by row (scalar Python: no array overhead on a 5-vector)."""
    a0, a1, a2, a3, a4, b0, b1, b2, b3, b4, c0, c1, c2, c3, c4, d0, d1, d2, d3, d4 = coefficients

    def step(p, v, pa, va, u):
        return (
            a0 * p + a1 * v + a2 * pa + a3 * va + a4 * u,
            b0 * p + b1 * v + b2 * pa + b3 * va + b4 * u,
            c0 * p + c1 * v + c2 * pa + c3 * va + c4 * u,
            d0 * p + d1 * v + d2 * pa + d3 * va + d4 * u,
        )

    return step


class _Continuous:
    """The continuous loop between ticks: modes, their exact steps, their switches."""

    def __init__(self, params: HybridLoopParams, h: float) -> None:
        self.h = h
        self.ideal = params.plant.table.is_ideal
        self.k, self.c = params.contact_stiffness_n_per_m, params.contact_damping_n_s_per_m
        self.undelayed = params.sensor_delay_s == 0.0
        law, kc, cc = _law(params)
        self.law, self.by_force, self.clamp = (
            law,
            law.gate == "measured_force",
            law.clamp_nonnegative,
        )
        self.mdc = law.motion_correction and (kc > 0.0 or cc is not None)
        # The law between switches over [f_mea, previous sample, p, v, p_act, v_act]:
        # the held part u = lead_f f_mea + lead_prev prev, the MDC row over z.
        with_mdc, without = _rows(law, h, kc, cc, np.eye(6))
        self.lead_f, self.lead_prev = float(without[0]), float(without[1])
        self.g_mdc = np.append(with_mdc[2:], 0.0) if self.mdc else np.zeros(5)
        a = np.zeros((4, 4))
        a[0, 1] = 1.0
        if self.ideal:  # the table is the spacecraft: rows 2, 3 copy rows 0, 1
            a[2:] = a[:2]
        else:  # the table's law, driven by p_des
            a_table, b_table = second_order_matrices(
                params.table_response_hz, params.table_damping_ratio
            )
            a[2:, 2:], a[2:, 0] = a_table, b_table[:, 0]
        self.a = a
        self.b = np.array([0.0, -1.0 / params.spacecraft_mass_kg, 0.0, 0.0])
        self.g_raw = np.array([0.0, 0.0, self.k, self.c, 0.0])  # k p_act + c v_act
        self.cache: dict[int, tuple] = {}
        # The switching functions (functional of z, offset) whose signs set the mode.
        sig = []
        if self.undelayed or not self.by_force:
            sig.append((np.array([0.0, 0.0, 1.0, 0.0, 0.0]), 0.0))
        db = law.force_deadband_n
        if self.undelayed:
            sig += [(self.g_raw, 0.0)] + ([(self.g_raw, -db)] if db > 0.0 else [])
        if self.clamp:
            sig += [(self.force_row(m), 0.0) for m in self.modes_on()]
        self.sigmas = sig
        self.switches = self.undelayed or (self.mdc and (self.clamp or not self.by_force))
        self._mode = mode_function(law.gate, law.motion_correction)
        self._law = tick_law(self)
        self._rows = [(0.0,) * 5] * 8  # the force of each mode over z
        for mode in self.modes_on():
            self._rows[mode] = tuple(self.force_row(mode).tolist())

    def modes_on(self) -> list[int]:
        """The modes with a force (contact term only without delay, MDC term if any)."""
        contacts = dict.fromkeys((0, CONTACT if self.undelayed else 0))
        mdcs = dict.fromkeys((0, MDC if self.mdc else 0))
        return [ON + c + m for c in contacts for m in mdcs]

    def force_row(self, mode: int) -> np.ndarray:
        """The compensated force of ``mode`` as a functional of ``z`` (N)."""
        row = np.zeros(5)
        if mode & ON:
            row[4] = 1.0
            if mode & CONTACT:  # no delay: the measured force is the contact's
                row += self.lead_f * self.g_raw
            if mode & MDC:
                row += self.g_mdc
        return row

    def matrix(self, mode) -> np.ndarray:
        m = np.zeros((5, 5))
        m[:4, :4] = self.a
        m[:4, :] += np.outer(self.b, self.force_row(mode))
        if self.ideal:
            m[2:4] = m[0:2]
        return m

    def exp(self, mode, tau: float) -> np.ndarray:
        e = expm(self.matrix(mode) * tau)
        if self.ideal:
            e[2:4] = e[0:2]  # keeps p_act == p_des bit for bit
        return e

    def step(self, mode: int):
        """The exact step over h of ``mode``, cached: the first four rows of its ``E``
        as 20 numbers (the tick loop's table) and ``z -> E z`` (a switch's tick)."""
        if mode not in self.cache:
            coefficients = tuple(float(x) for x in self.exp(mode, self.h)[:4].ravel())
            self.cache[mode] = (coefficients, _unrolled(coefficients))
        return self.cache[mode]

    def tables(self, compiled: bool):
        """The tick loop's steps over h and force rows of the modes it can reach,
        indexed by the mode (zeros elsewhere); arrays for a compiled loop. A held
        loop reaches only "off" and the force with its MDC term, if any."""
        modes = self.modes_on() if self.switches else [ON + (MDC if self.mdc else 0)]
        steps = [(0.0,) * 20] * 8
        for mode in (OFF, *modes):
            steps[mode] = self.step(mode)[0]
        return (np.array(steps), np.array(self._rows)) if compiled else (steps, self._rows)

    def mode_of(self, z, gate: bool) -> int:
        """The force law's mode at ``z`` (``gate``: the held reading is above the
        deadband): :func:`~hybridtable.loop.ticks.mode_function`, the tick loop's."""
        return self._mode(*z, gate, self._rows, self._law)

    def interval(self, z, mode, gate: bool):
        """State after one tick from ``z`` in ``mode``, with every switch located; and
        the mode at the end."""
        z1 = (*self.step(mode)[1](*z), z[4])
        if not self.switches or self.mode_of(z1, gate) == mode:
            return z1, mode
        rem, x = self.h, np.array(z)
        for _ in range(8):  # a few switches per tick at most; then the rest in one mode
            tau = self.first_switch(x, rem, mode, gate)
            x = self.exp(mode, tau) @ x
            rem -= tau
            mode = self.mode_of(tuple(x.tolist()), gate)
            if rem <= 0.0:
                return tuple(x.tolist()), mode
            end = self.exp(mode, rem) @ x
            if self.mode_of(tuple(end.tolist()), gate) == mode:
                return tuple(end.tolist()), mode
        return tuple(end.tolist()), self.mode_of(tuple(end.tolist()), gate)

    def first_switch(self, x, rem: float, mode, gate: bool) -> float:
        """The first instant in ``(0, rem]`` after which the mode is not ``mode`` (s)."""
        ends = self.exp(mode, rem) @ x
        roots = []
        for g, c0 in self.sigmas:
            s0, s1 = g @ x + c0, g @ ends + c0
            if (s0 > 0.0) != (s1 > 0.0) or (s0 >= 0.0) != (s1 >= 0.0):
                roots.append(
                    brentq(
                        lambda t, g=g, c0=c0: g @ (self.exp(mode, t) @ x) + c0, 0.0, rem, xtol=1e-15
                    )
                )
        step = 1e-12 * self.h
        for r in sorted(roots):
            tau = min(rem, r + step)
            if self.mode_of(tuple((self.exp(mode, tau) @ x).tolist()), gate) != mode:
                return tau
        return rem


def _computer_period(params: HybridLoopParams) -> tuple[float, int | tuple[int, float]]:
    """The rig computer's period ``h`` (s) and the delay in ticks (the delay line's ``N``
    of a continuous loop; the taps ``(M, alpha)`` of a sampled one), as the diagram's
    builder sets them."""
    if params.sample_rate_hz is not None:
        h = params.sample_period_s
        return h, sample_taps(params.sensor_delay_s, h)
    if params.sensor_delay_s > 0.0:
        return continuous_delay_period(params.sensor_delay_s, params.step_s)
    return params.step_s, 0


def _initial_state(params: HybridLoopParams, loop: _Continuous) -> tuple[float, ...]:
    """``(p_des, v_des, p_act, v_act)`` at ``t = 0`` (an ideal table is the spacecraft)."""
    ic = params.initial_conditions()
    p, v = ic["p_des_m"], ic["v_des_m_per_s"]
    pa, va = (p, v) if loop.ideal else (ic["p_act_m"], ic["v_act_m_per_s"])
    return p, v, pa, va


#: Ticks of records a continuous run starts with room for (a CoR table's row
#: takes 3,000 to 5,000), half as much again each time it needs more: a block of
#: 128 kB or more is mapped and unmapped by the allocator on every run (Table 4's
#: rows took 1.11 ms a run with 1 MB blocks, 0.63 ms with these).
RECORD_ROOM = 1 << 13


def _run_continuous(params: HybridLoopParams, h: float, n: int, rule: _StopRule):
    """Tick log ``(v, f_act, f_comp)`` of a continuous loop (before each tick's update):
    :func:`~hybridtable.loop.ticks.tick_loop` between the stop rule's checks, and
    :meth:`_Continuous.interval` where the force law switches inside a tick."""
    loop = _Continuous(params, h)
    ticks, compiled = tick_loop(loop.law.gate, loop.law.motion_correction)
    steps, rows = loop.tables(compiled)
    law = loop._law
    state = (*_initial_state(params, loop), 0.0)  # u: no held force before t = 0
    mode = loop.mode_of(state, False)
    room = RECORD_ROOM
    new = (lambda m: np.zeros(m)) if compiled else (lambda m: [0.0] * m)
    F, vs, fas, fcs = new(n + 2 + room), new(room), new(room), new(room)
    k, checked, touched = 0, False, False
    while True:
        state, mode, touched, k, f_act, f_comp, why, gate = ticks(
            state, mode, touched, steps, rows, law, F, vs, fas, fcs, k, n, h, rule.due, checked
        )
        checked = False
        if why == 1:  # half as much room again, the records kept
            more = max(len(vs) // 2, 1)
            F, vs, fas, fcs = (_grown(x, more, compiled) for x in (F, vs, fas, fcs))
        elif why == 2:  # the mode switches inside tick k: located on the exact trajectory
            state, mode = loop.interval(state, mode, gate)
            k += 1
        else:
            rule.touched = touched
            f_mea = f_act if loop.undelayed else F[k + 1]
            if rule.check_tick(k, f_act, f_mea, f_comp):
                vs[k], fas[k], fcs[k] = state[1], f_act, f_comp
                return vs[: k + 1], fas[: k + 1], fcs[: k + 1]
            checked = True


def _grown(x, m: int, compiled: bool):
    """``x`` with room for ``m`` more numbers (zeros)."""
    return np.concatenate([x, np.zeros(m)]) if compiled else x + [0.0] * m


def _run_sampled(
    params: HybridLoopParams,
    h: float,
    taps: tuple[int, float],
    rule: _StopRule,
    ticks: int | None = None,
):
    """Row log ``(v, f_act, f_comp)`` of a sampled loop (row k: what tick k read and
    computed, and the spacecraft state after its update); the reading is the
    sampled sensor's (:meth:`~hybridtable.systems.sensor.ForceSensorDelay.readings`).
    With ``ticks``: exactly that many rows, whatever the stop rule says (it still
    judges divergence and the budget), each ``(p_des, v_des, p_act, v_act, f_act,
    f_mea, f_comp)``."""
    n_delay, alpha = taps
    law, kc, cc = _law(params)
    k_con, c_con = params.contact_stiffness_n_per_m, params.contact_damping_n_s_per_m
    contact = bound(contact_function(), k_con, c_con)
    switches = (law.has_lead, law.motion_correction, law.gate, law.clamp_nonnegative)
    compensator = bound(
        compensator_function(*switches, cc is not None),
        *(law.lead_time_s, h, law.force_deadband_n, kc, 0.0 if cc is None else cc),
    )
    A, B = computer_step(params.spacecraft_mass_kg, h, params.rig.integrator)  # one tick
    (a00, a01), (a10, a11) = A.tolist()
    b0, b1 = B[:, 0].tolist()
    table = params.plant.table
    ideal = table.is_ideal
    ic = params.initial_conditions()
    p, v, pa, va = ic["p_des_m"], ic["v_des_m_per_s"], ic["p_act_m"], ic["v_act_m_per_s"]
    if not ideal:  # the table over one tick under a held command
        phi, gamma = second_order_tick(table.response_frequency_hz, table.damping_ratio, h)
        (e00, e01), (e10, e11) = phi.tolist()
        e02, e12 = gamma.tolist()
    F = [0.0] * (n_delay + 1)  # F[j] = f_act(t_j) at index j + n_delay + 1
    prev = 0.0
    vs, fas, fcs, rows = [], [], [], []
    k, due = 0, rule.due
    while True:
        if ideal:
            pa, va = p, v
        f_act = contact(pa, va)
        if f_act > 0.0:
            rule.touched = True
        F.append(f_act)
        f_mea = F[k + 1] if not alpha else (1 - alpha) * F[k + 1] + alpha * F[k]
        f_comp = compensator(f_mea, prev, p, v, pa, va)
        if k * h >= due:
            if rule.check_tick(k, f_act, f_mea, f_comp) and ticks is None:
                return vs, fas, fcs
            due = rule.due
        prev = f_mea
        p, v = a00 * p + a01 * v + b0 * f_comp, a10 * p + a11 * v + b1 * f_comp
        if ticks is None:
            vs.append(v)
            fas.append(f_act)
            fcs.append(f_comp)
        else:  # the table as tick k read it, before its update
            rows.append((p, v, pa, va, f_act, f_mea, f_comp))
        if not ideal:
            pa, va = e00 * pa + e01 * va + e02 * p, e10 * pa + e11 * va + e12 * p
        k += 1
        if k == ticks:  # the diagram's last check, at the record's end
            rule.check_tick(k, f_act, f_mea, f_comp)
            return rows


def prepare_fast(runs: Iterable[HybridLoopParams]) -> int:
    """Compile now the tick loops these runs need (a process about to fork the
    workers that run them compiles once for all: :func:`~hybridtable.loop.ticks.compile_loops`).
    Returns how many loops were compiled."""
    variants = []
    for params in runs:
        if fast_unsupported(params) is None:
            law = _law(params)[0]
            variants.append((law.gate, law.motion_correction))
    return compile_loops(variants)


def simulate_fast(params: HybridLoopParams) -> ContactMetrics:
    """Contact metrics of one run of the hybrid loop, by the exact discrete update.

    Same stop rule, ``t_max``, budget and errors as
    :func:`~hybridtable.loop.simulation.run_loop` on the diagram of ``params``.

    Raises
    ------
    ParameterError
        If :func:`fast_unsupported` names a reason (use the diagram).
    DivergenceError
        If the compensated force passes ``DIVERGED_FORCE_RATIO`` times ``v sqrt(k m)``.
    SimulationError
        If no contact happens, the contact does not end within ``t_max``, or the run
        is over the simulation budget.
    """
    why = fast_unsupported(params)
    if why is not None:
        raise ParameterError(f"the fast path cannot run these parameters: {why}")
    h, n = _computer_period(params)
    check_budget(params, min(default_t_max_s(params), expected_duration_s(params)), h)
    rule = separation_rule(params, h, kind=_StopRule, period_s=h)
    run = _run_sampled if params.sample_rate_hz is not None else _run_continuous
    vs, fas, fcs = run(params, h, n, rule)
    rule.verdict()
    t = np.arange(len(vs)) * h
    try:
        return contact_metrics(t, vs, fas, fcs, params.spacecraft_mass_kg)
    except ValueError as err:
        raise SimulationError(f"{err} within the {t[-1]:.3g} s simulated") from None


#: The rows of :func:`record_fast`, in the order :func:`_run_sampled` gives them:
#: the loop's log without the table's acceleration.
_RECORD_ROWS = tuple(name for name in LOG_ROWS if name != "a_act_m_per_s2")


def record_fast(params: HybridLoopParams, ticks: int) -> SimulationResult:
    """The first ``ticks`` rows of a sampled loop's run, by the exact discrete update.

    What :func:`~hybridtable.loop.simulation.run_loop` records on the diagram of
    ``params`` with ``t_max_s = (ticks + 1/2) h`` and ``stop_at_separation=False``
    (a recorded run's length), row ``k`` as
    :func:`~hybridtable.loop.simulation.collect_result` gives it: what tick ``k``
    read and computed, the spacecraft state after its update. The table is exact
    at the ticks, where the diagram integrates it between them (the rows differ by
    the integrator's error). ``steps`` counts the ticks.

    Raises
    ------
    ParameterError
        If :func:`fast_unsupported` names a reason, or the rig computer is continuous.
    DivergenceError
        As :func:`simulate_fast`.
    SimulationError
        If no contact happens, or the record is over the simulation budget.
    """
    if ticks < 1:
        raise ParameterError(f"record_fast: ticks must be at least 1, got {ticks}")
    why = fast_unsupported(params)
    if why is None and params.sample_rate_hz is None:
        why = "a continuous rig computer (a record has the ticks of a sampled one)"
    if why is not None:
        raise ParameterError(f"the fast path cannot record these parameters: {why}")
    h, taps = _computer_period(params)
    t_max = (ticks + 0.5) * h
    check_budget(params, t_max, h, integrated=False)
    rule = separation_rule(params, h, t_max, False, kind=_StopRule, period_s=h)
    rows = np.array(_run_sampled(params, h, taps, rule, ticks), dtype=float)
    rows = rows.reshape(ticks, len(_RECORD_ROWS))
    rule.verdict()
    rows = dict(zip(_RECORD_ROWS, rows.T, strict=True))
    return result_from_rows(params, h * np.arange(ticks), rows, ticks)
