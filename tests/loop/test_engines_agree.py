"""The two engines of one hybrid-loop run agree on every law they both model.

The Drake diagram (:func:`hybridtable.loop.simulation.simulate`, the model of
record) and the exact discrete fast engine
(:func:`hybridtable.loop.fast.simulate_fast`) must give the same contact
metrics, not only at the paper's Table 1/2 points (``tests/loop/test_fast.py``)
but for each law the loop is made of: each compensator kind (none, SDC, MDC,
SDMDC), a lead other than the delay, the MDC's believed damping and a believed
stiffness other than the true one, contact damping, a force deadband,
``clamp_nonnegative``, ``contact_gate="table_position"``, the ideal and a real
table, a continuous and a sampled rig computer (1000, 2000 and 500 Hz, the
delay a whole number of ticks), no sensor delay, and another mass, contact
frequency and approach velocity. One case per law, named after it, so that a
disagreement names the law the engines part on.

Why the engines may differ at all (``hybridtable/loop/fast.py``): the fast
engine is exact; the diagram integrates the continuous states between ticks
(RK3, accuracy 1e-8), and it records every integrator step of a continuous
loop where the fast engine records the ticks. Hence the tolerances, each
chosen from these documented differences and from the measured worst case
(``python -m tests.loop.test_engines_agree`` prints the table):

CoR (``v_in`` and ``v_out`` are read where no force acts, so only the
diagram's integrator error separates them):

- ``COR_TOL_EXACT = 1e-12`` -- ideal table with a held force (a sensor delay,
  or a sampled loop): between ticks the force on the spacecraft is constant,
  its trajectory a polynomial RK3 integrates exactly; only rounding remains
  (measured <= 3.4e-15).
- ``COR_TOL_SMOOTH = 1e-8`` -- a real table (or a contact force) integrated
  between ticks, no switch of the force law inside a tick: the integrator's
  error-controlled error (measured <= 1.5e-10 continuous, <= 9.7e-10 sampled:
  a sampled loop is not tighter here, the diagram integrates its table under
  the held command with steps up to a whole tick of 1 ms; the MDC term, which
  feeds back the table's error, cancels most of it: <= 1.6e-10).
- ``COR_TOL_SWITCHING = 1e-6`` -- the force law switches inside a tick (no
  delay: the gate follows the contact; the MDC term with
  ``contact_gate="table_position"`` or with ``clamp_nonnegative``): the fast
  engine locates the switch on the exact trajectory, the diagram's integrator
  steps over it (measured <= 4.7e-8; the clamped SDMDC, 1.2e-10).

Energy gained ``E = m v_in^2 (CoR^2 - 1) / 2`` with ``v_in`` identical in both
(asserted exactly): ``|dE| <= E0 (2 CoR + dCoR) dCoR < 3 E0 tol_CoR``,
``E0 = m v_in^2 / 2``.

Peak actual force: the force is smooth at its maximum, so recording it a
fraction of a tick off changes it by about ``(w_con h)^2 / 8`` of the peak
(2e-7 at the continuous points here), plus the integrator's error (measured
<= 1.5e-7 of ``F0 = v sqrt(k m)``): ``PEAK_FORCE_TOL = 1e-6 F0``.

Peak compensated force: in a continuous loop the held part of ``f_comp`` is
fixed over a tick and its MDC term ``k_b (p_des - p_act) + c_b (v_des -
v_act)`` moves; the diagram sees its maximum inside a tick, the fast engine at
the ticks. The bound is ``PEAK_FORCE_TOL`` plus that term's largest change
over one tick, read off the diagram's record (measured up to 7.8e-4 F0 on the
damped SDMDC, whose lead spike at the touch swings ``c_b (v_des - v_act)``;
the bound there is 1.3e-3 F0). Sampled loops are recorded at the same ticks
by both: ``PEAK_FORCE_TOL`` alone.

Contact duration: by a tick ``h`` (documented). The ideal-table points here
touch at ``t = 51 h``, exactly on a tick, where rounding decides the sign of
the penetration (-2e-19 m in the diagram, > 0 in the fast engine): the touch
tick counts as in contact in one record only, which moves the trapezoidal
duration by one whole tick (measured 1 + 2e-13 ticks; with the touch off the
ticks, e.g. a gap of 1.01 mm, the durations agree exactly), hence
``h (1 + 1e-6)``.

Largest kinetic-energy excess ``energy_created`` (``max v^2 / v_in^2 - 1``
over the record): the maximum is ``v_out`` (the CoR's share, ``2 CoR dCoR``)
or a point inside the contact where the force crosses zero, smoothly (both
records within the integrator's error) or by a switch of the law (located by
the fast engine, stepped over by the diagram, as for the CoR): ``3 tol_CoR``
(measured <= 2.9e-7 against 3e-6 on a switching loop, <= 2.3e-9 against 3e-8
on a smooth one).

Each case takes 0.1-0.35 s on the diagram and a few ms on the fast engine.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from hybridtable.errors import ParameterError, SimulationError
from hybridtable.loop.builder import build_hybrid_loop
from hybridtable.loop.fast import record_fast, simulate_fast
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import (
    check_interval_s,
    expected_duration_s,
    run_loop,
    simulate,
)
from hybridtable.studies.paper import paper_params, table1_params
from hybridtable.systems.sensor import continuous_delay_period

COR_TOL_EXACT = 1e-12
COR_TOL_SMOOTH = 1e-8
COR_TOL_SWITCHING = 1e-6
PEAK_FORCE_TOL = 1e-6  # of F0 = v sqrt(k m)
DURATION_TICKS = 1.0 + 1e-6


def _t1(compensator: str, **changes) -> HybridLoopParams:
    """Table 1's point (k = 1e5 N/m, 1 Hz, 5 ms, 25 Hz table) with ``changes``."""
    return table1_params(compensator).with_(**changes)


def _damping(zeta: float, p: HybridLoopParams | None = None) -> float:
    """Damping of ratio ``zeta`` of the contact of ``p`` (Table 1's by default), N s/m."""
    p = p or table1_params("none")
    return 2.0 * zeta * math.sqrt(p.contact_stiffness_n_per_m * p.spacecraft_mass_kg)


K = 1e5  # Table 1's contact stiffness, N/m
INF = math.inf

#: id (the law it holds) -> parameters.
CASES: dict[str, HybridLoopParams] = {
    # Continuous rig computer, Table 1's point: each compensator kind.
    "cont-none": _t1("none"),
    "cont-SDC": _t1("SDC"),
    "cont-MDC": _t1("MDC"),
    "cont-SDMDC": _t1("SDMDC"),
    "cont-SDC-lead-3ms": _t1("SDC", lead_time_s=0.003),
    # What the MDC believes.
    "cont-MDC-damped-contact-believed-true": _t1("MDC", contact_damping_n_s_per_m=_damping(0.05)),
    "cont-MDC-believed-damping-undamped-contact": _t1(
        "MDC", compensator_damping_n_s_per_m=_damping(0.05)
    ),
    "cont-SDMDC-believed-stiffness-0.8k": _t1("SDMDC", compensator_stiffness_n_per_m=0.8 * K),
    "cont-MDC-believed-1.2k-no-damping-damped-contact": _t1(
        "MDC",
        compensator_stiffness_n_per_m=1.2 * K,
        compensator_damping_n_s_per_m=0.0,
        contact_damping_n_s_per_m=_damping(0.05),
    ),
    # The contact's damping.
    "cont-none-contact-damping": _t1("none", contact_damping_n_s_per_m=_damping(0.1)),
    "cont-SDMDC-contact-damping": _t1("SDMDC", contact_damping_n_s_per_m=_damping(0.1)),
    # The compensator's gate and clamp.
    "cont-SDMDC-deadband": _t1("SDMDC", force_deadband_n=50.0),
    "cont-SDC-deadband": _t1("SDC", force_deadband_n=20.0),
    "cont-SDMDC-clamp": _t1("SDMDC", clamp_nonnegative=True),
    "cont-SDMDC-gate-table-position": _t1("SDMDC", contact_gate="table_position"),
    "cont-MDC-gate-table-position-clamp": _t1(
        "MDC", contact_gate="table_position", clamp_nonnegative=True
    ),
    # The table.
    "cont-none-ideal-table": _t1("none", table_response_hz=INF),
    "cont-SDC-ideal-table": _t1("SDC", table_response_hz=INF),
    "cont-SDMDC-table-50Hz-zeta0.5": _t1("SDMDC", table_response_hz=50.0, table_damping_ratio=0.5),
    # No sensor delay: the gate follows the contact inside a tick.
    "cont-SDMDC-zero-delay": _t1("SDMDC", sensor_delay_s=0.0),
    "cont-none-zero-delay-ideal-table": _t1("none", sensor_delay_s=0.0, table_response_hz=INF),
    # Another contact frequency, mass (3 k at 1 Hz) and approach velocity.
    "cont-SDMDC-contact-3Hz": paper_params("SDMDC", contact_frequency_hz=3.0),
    "cont-SDC-mass-3x": paper_params("SDC", contact_stiffness_n_per_m=3 * K),
    "cont-none-approach-0.3": paper_params("none", initial_velocity_m_per_s=0.3),
    # Sampled rig computer: each compensator kind at 1000 Hz (5 ms = 5 ticks).
    "s1000-none": _t1("none", sample_rate_hz=1000.0),
    "s1000-SDC": _t1("SDC", sample_rate_hz=1000.0),
    "s1000-MDC": _t1("MDC", sample_rate_hz=1000.0),
    "s1000-SDMDC": _t1("SDMDC", sample_rate_hz=1000.0),
    # Other rates: 2000 Hz (10 ticks), 500 Hz with 6 ms (3 ticks).
    "s2000-SDMDC": _t1("SDMDC", sample_rate_hz=2000.0),
    "s500-SDMDC-delay-6ms": _t1("SDMDC", sample_rate_hz=500.0, sensor_delay_s=0.006),
    "s1000-SDC-lead-2ms-ideal-table": _t1(
        "SDC", sample_rate_hz=1000.0, lead_time_s=0.002, table_response_hz=INF
    ),
    "s1000-SDMDC-zero-delay": _t1("SDMDC", sample_rate_hz=1000.0, sensor_delay_s=0.0),
    "s1000-SDMDC-clamp-gate-table-position-deadband": _t1(
        "SDMDC",
        sample_rate_hz=1000.0,
        clamp_nonnegative=True,
        contact_gate="table_position",
        force_deadband_n=50.0,
    ),
    "s1000-MDC-damped-contact-believed-0.8k": _t1(
        "MDC",
        sample_rate_hz=1000.0,
        compensator_stiffness_n_per_m=0.8 * K,
        contact_damping_n_s_per_m=_damping(0.1),
    ),
}


def computer_period_s(p: HybridLoopParams) -> float:
    """The rig computer's tick ``h`` as the diagram's builder sets it: the sample
    period, the delay line's ``T / (N + 1/2)``, or the integration step."""
    if p.sample_rate_hz is not None:
        return p.sample_period_s
    if p.sensor_delay_s > 0.0:
        return continuous_delay_period(p.sensor_delay_s, p.step_s)[0]
    return p.step_s


def _mdc_acts(p: HybridLoopParams) -> bool:
    """The MDC term is in the law (an ideal table has ``p_des - p_act = 0``)."""
    return p.compensator_params().uses_motion_correction and not p.plant.table.is_ideal


def cor_tolerance(p: HybridLoopParams) -> tuple[float, str]:
    """The CoR tolerance of ``p`` and its class (see the module docstring)."""
    if p.plant.table.is_ideal and (p.sample_rate_hz is not None or p.sensor_delay_s > 0.0):
        return COR_TOL_EXACT, "exact"
    switches = p.sensor_delay_s == 0.0 or (
        _mdc_acts(p) and (p.clamp_nonnegative or p.contact_gate == "table_position")
    )
    if p.sample_rate_hz is None and switches:
        return COR_TOL_SWITCHING, "switching"
    return COR_TOL_SMOOTH, "smooth"


def _mdc_change_within_a_tick(p: HybridLoopParams, r, h: float) -> float:
    """Largest change of the MDC term over one tick, from the diagram's record (N)."""
    if p.sample_rate_hz is not None or not _mdc_acts(p):
        return 0.0
    cp = p.compensator_params()
    term = cp.stiffness_n_per_m * (r.p_des_m - r.p_act_m) + cp.damping_n_s_per_m * (
        r.v_des_m_per_s - r.v_act_m_per_s
    )
    dt = np.diff(r.time_s)
    keep = dt > 1e-6 * h  # the record keeps events a rounding apart
    return float(np.max(np.abs(np.diff(term)[keep]) / dt[keep]) * h)


def compare(p: HybridLoopParams) -> dict[str, float]:
    """Run both engines on ``p``: their differences, the bounds, the run times."""
    t0 = time.perf_counter()
    r = simulate(p)
    t1 = time.perf_counter()
    fast = simulate_fast(p)
    t2 = time.perf_counter()
    d = r.metrics
    h = computer_period_s(p)
    m, v0 = p.spacecraft_mass_kg, abs(d.v_in_m_per_s)
    e0 = 0.5 * m * v0**2
    f0 = p.initial_velocity_m_per_s * math.sqrt(p.contact_stiffness_n_per_m * m)
    tol, kind = cor_tolerance(p)
    peak_comp_tol = PEAK_FORCE_TOL * f0 + _mdc_change_within_a_tick(p, r, h)
    return {
        "diagram": d,
        "fast": fast,
        "cor": d.cor,
        "kind": kind,
        "cor_tol": tol,
        "d_cor": abs(d.cor - fast.cor),
        "energy_tol": 3.0 * tol * e0,
        "d_energy": abs(d.energy_gain_j - fast.energy_gain_j),
        "e0": e0,
        "peak_tol": PEAK_FORCE_TOL * f0,
        "d_peak": abs(d.peak_force_n - fast.peak_force_n),
        "peak_comp_tol": peak_comp_tol,
        "d_peak_comp": abs(d.peak_compensated_force_n - fast.peak_compensated_force_n),
        "f0": f0,
        "h": h,
        "duration_tol": DURATION_TICKS * h,
        "d_duration": abs(d.contact_duration_s - fast.contact_duration_s),
        "created_tol": 3.0 * tol,
        "d_created": abs(d.energy_created - fast.energy_created),
        "t_diagram": t1 - t0,
        "t_fast": t2 - t1,
    }


@pytest.mark.parametrize("params", list(CASES.values()), ids=list(CASES))
def test_engines_agree(params):
    c = compare(params)
    d, fast = c["diagram"], c["fast"]
    # Free flight before the contact: both read the approach velocity itself.
    assert fast.v_in_m_per_s == d.v_in_m_per_s
    assert c["d_cor"] <= c["cor_tol"], (
        f"CoR {d.cor!r} (diagram) vs {fast.cor!r} (fast): {c['d_cor']:.3g} > "
        f"{c['cor_tol']:g} ({c['kind']})"
    )
    assert c["d_energy"] <= c["energy_tol"], (
        f"energy gained differs by {c['d_energy'] / c['e0']:.3g} E0"
    )
    assert c["d_peak"] <= c["peak_tol"], f"peak force differs by {c['d_peak'] / c['f0']:.3g} F0"
    assert c["d_peak_comp"] <= c["peak_comp_tol"], (
        f"peak compensated force differs by {c['d_peak_comp'] / c['f0']:.3g} F0 > "
        f"{c['peak_comp_tol'] / c['f0']:.3g} F0"
    )
    assert c["d_duration"] <= c["duration_tol"], (
        f"contact duration differs by {c['d_duration'] / c['h']:.6f} ticks"
    )
    assert c["d_created"] <= c["created_tol"], (
        f"energy created differs by {c['d_created']:.3g} > {c['created_tol']:.3g}"
    )


#: A sampled loop's record (:func:`~hybridtable.loop.fast.record_fast`, a
#: recorded run's closed loop) against the diagram's, row by row, for a record's
#: length (``stop_at_separation=False``): each signal within ``RECORD_TOL`` of its
#: largest magnitude, the diagram's table integrated to 1e-8 (measured <= 8.2e-8,
#: the table's velocity; every other signal <= 1.1e-8); an ideal table holds no
#: integrated state and the rows agree bit for bit. A delay of 3.5 ticks reads
#: between two samples (the sensor's taps).
RECORD_TOL = 1e-6
RECORD_CASES = {
    name: CASES[name]
    for name in (
        "s1000-SDMDC",
        "s500-SDMDC-delay-6ms",
        "s1000-SDMDC-clamp-gate-table-position-deadband",
        "s1000-SDC-lead-2ms-ideal-table",
    )
} | {"s1000-SDC-delay-3.5ms": _t1("SDC", sample_rate_hz=1000.0, sensor_delay_s=0.0035)}


@pytest.mark.parametrize("params", list(RECORD_CASES.values()), ids=list(RECORD_CASES))
def test_records_agree_row_by_row(params):
    h = params.sample_period_s
    n = int(expected_duration_s(params) / h) + 100  # the contact and a tail after it
    diagram = run_loop(build_hybrid_loop(params), t_max_s=(n + 0.5) * h, stop_at_separation=False)
    fast = record_fast(params, n)
    assert len(diagram.time_s) == n and fast.steps == n
    assert np.array_equal(fast.time_s, diagram.time_s)
    tol = 0.0 if params.plant.table.is_ideal else RECORD_TOL
    for name, x in fast.signals().items():
        y = getattr(diagram, name)
        assert np.max(np.abs(x - y)) <= tol * np.max(np.abs(y)), name
    assert abs(fast.metrics.cor - diagram.metrics.cor) <= COR_TOL_SMOOTH


def test_record_refuses_a_continuous_computer_and_reports_no_contact():
    with pytest.raises(ParameterError, match="continuous rig computer"):
        record_fast(_t1("SDMDC"), 100)
    with pytest.raises(ParameterError, match="at least 1"):
        record_fast(_t1("SDMDC", sample_rate_hz=1000.0), 0)
    with pytest.raises(SimulationError, match="no contact"):
        record_fast(_t1("SDMDC", sample_rate_hz=1000.0), 10)  # 10 ticks of the approach


def test_a_record_that_ends_just_after_the_touch_has_a_contact():
    """The stop rule looks every ten ticks or more; a touch after its last look
    still counts, as the diagram's last look at the record's end sees it (no
    sensor delay: the model feels the touch at once)."""
    params = _t1("SDMDC", sample_rate_hz=1000.0, sensor_delay_s=0.0)
    h = params.sample_period_s
    touch = int(np.argmax(record_fast(params, 200).f_act_n > 0.0))
    ticks = touch + 2
    chunk = check_interval_s(params, h)  # the rule looks at chunk, 2 chunk, ...
    assert chunk < touch * h and ticks * h < 2.0 * chunk  # no look between touch and end
    fast = record_fast(params, ticks)
    diagram = run_loop(
        build_hybrid_loop(params), t_max_s=(ticks + 0.5) * h, stop_at_separation=False
    )
    assert fast.f_act_n[-1] > 0.0 and diagram.f_act_n[-1] > 0.0
    assert fast.metrics.v_in_m_per_s == diagram.metrics.v_in_m_per_s


def _table() -> None:
    """Print every case's differences against its tolerances (the measurement
    the tolerances come from)."""
    head = (
        f"{'case':50s} {'class':9s} {'CoR':>9s} {'|dCoR|':>9s} {'tol':>7s} {'|dE|/E0':>9s} "
        f"{'|dFpk|/F0':>9s} {'|dFcpk|/F0':>9s} {'bound/F0':>9s} {'|dT|/h':>7s} "
        f"{'|dEc|':>9s} {'Ec tol':>8s} {'t_diag':>6s} {'t_fast':>6s}"
    )
    print(head)
    total, worst = 0.0, {}
    for name, p in CASES.items():
        c = compare(p)
        total += c["t_diagram"] + c["t_fast"]
        worst[c["kind"]] = max(worst.get(c["kind"], 0.0), c["d_cor"])
        print(
            f"{name:50s} {c['kind']:9s} {c['cor']:9.6f} {c['d_cor']:9.2e} {c['cor_tol']:7.0e} "
            f"{c['d_energy'] / c['e0']:9.2e} {c['d_peak'] / c['f0']:9.2e} "
            f"{c['d_peak_comp'] / c['f0']:9.2e} {c['peak_comp_tol'] / c['f0']:9.2e} "
            f"{c['d_duration'] / c['h']:7.3f} {c['d_created']:9.2e} {c['created_tol']:8.1e} "
            f"{c['t_diagram']:6.3f} {c['t_fast']:6.3f}",
            flush=True,
        )
    print("worst |dCoR| by class:", {k: f"{v:.2e}" for k, v in worst.items()})
    print(f"total {total:.1f} s over {len(CASES)} cases")


if __name__ == "__main__":
    _table()
