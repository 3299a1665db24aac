"""Margins over a (delay, table frequency) grid and validation against the
simulation (hybridtable.analysis.sweep, hybridtable.analysis.validation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.analysis.blockwise import ContactLoopLinearizer
from hybridtable.analysis.margins import loop_margins
from hybridtable.analysis.validation import (
    linear_contact_cor,
    onset_state,
    validate_point,
    validation_indices,
)
from hybridtable.errors import ParameterError
from hybridtable.loop.simulation import simulate
from hybridtable.studies.paper import paper_params
from hybridtable.sweeps.margins_grid import sweep_margins
from tests.analysis.support import damped


def test_grid_values_are_the_point_analysis_and_curves_bound_the_stable_region():
    base = damped(paper_params(), 0.05)
    delays = np.array([0.0, 0.004, 0.012])
    tables = np.array([10.0, 25.0, math.inf])
    r = sweep_margins(base, delays, tables, ("none", "MDC"))
    assert r.verification_error is not None and r.verification_error < 1e-8
    lin = ContactLoopLinearizer(3)
    for c, cs in r.compensators.items():
        assert cs.predicted_cor.shape == (3, 3)
        for i, T in enumerate(delays):
            for j, f in enumerate(tables):
                p = base.with_(compensator=c, sensor_delay_s=T, table_response_hz=f)
                m = loop_margins(lin.open_loop(p))
                assert cs.predicted_cor[i, j] == pytest.approx(m.predicted_cor, rel=1e-12)
                assert cs.phase_margin_deg[i, j] == pytest.approx(m.phase_margin_deg, abs=1e-8)
                # The curves agree with the grid's stability.
                if np.isfinite(cs.critical_delay_s[j]):
                    assert cs.stable[i, j] == (T < cs.critical_delay_s[j])
                if cs.critical_table_hz[i] not in (0.0, math.inf):
                    assert cs.stable[i, j] == (f > cs.critical_table_hz[i])


def test_json_layout_indexes_delay_then_table():
    r = sweep_margins(paper_params(), [0.0, 0.01], [20.0, 50.0, 100.0], ("SDC",), critical=False)
    d = r.to_json_dict()
    assert d["grid"]["sensor_delay_s"] == [0.0, 0.01]
    cor = d["compensators"]["SDC"]["predicted_cor"]
    assert len(cor) == 2 and len(cor[0]) == 3
    # CoR grows with the delay and falls with the table frequency.
    assert cor[1][0] > cor[0][0] and cor[0][0] > cor[0][2]


def test_unsupported_compensator_is_refused():
    with pytest.raises(ParameterError):
        sweep_margins(paper_params(), [0.0], [25.0], ("sdmdc-online",))


def test_validation_indices_are_distinct_and_spread():
    idx = validation_indices(40, 40, 24)
    assert len(set(idx)) == 24
    i, j = np.array(idx).T
    assert {0, 39} <= set(i) and {0, 39} <= set(j)
    # Every quarter of the grid gets points.
    for a in (0, 20):
        for b in (0, 20):
            assert np.sum((i >= a) & (i < a + 20) & (j >= b) & (j < b + 20)) >= 3
    assert validation_indices(2, 2, 10) == [(0, 0), (1, 1), (0, 1), (1, 0)]


def test_linear_transient_from_onset_reproduces_gate_free_case():
    # MDC, no delay, slow table: the only nonlinearity the simulation has is
    # the contact window (gate opens and closes with p_act > 0, as the linear
    # run from the onset does), so both CoRs agree although the modal
    # prediction (exactly 1) does not.
    lin = ContactLoopLinearizer(3)
    p = paper_params(compensator="MDC", sensor_delay_s=0.0, table_response_hz=5.0)
    sim = simulate(p)
    onset = onset_state(sim.time_s, sim.p_des_m, sim.v_des_m_per_s, sim.p_act_m, sim.v_act_m_per_s)
    assert onset["p_act_m"] == pytest.approx(0.0, abs=1e-12)
    cor_t = linear_contact_cor(lin, p, onset)
    assert cor_t == pytest.approx(sim.metrics.cor, abs=2e-4)
    assert abs(sim.metrics.cor - 1.0) > 2e-3
    v = validate_point(p, loop_margins(lin.open_loop(p)).predicted_cor, lin, explain_above=0.001)
    assert v.cause == "transient"
    assert v.cor_linear_transient == pytest.approx(cor_t, rel=1e-12)


def test_sampled_linear_transient_matches_gate_free_sampled_run():
    # No compensation and no delay: the sampled loop's only nonlinearity is the
    # unilateral contact, which the run from the first penetrating tick to the
    # return of p_act to zero reproduces.
    from hybridtable.analysis.sampled import SampledLoopLinearizer
    from hybridtable.analysis.validation import linear_contact_cor_sampled

    for table_hz in (math.inf, 25.0):
        p = paper_params(sensor_delay_s=0.0, table_response_hz=table_hz, sample_rate_hz=1000.0)
        sim = simulate(p)
        runs = (sim.time_s, sim.p_des_m, sim.v_des_m_per_s, sim.p_act_m, sim.v_act_m_per_s)
        cor_t = linear_contact_cor_sampled(SampledLoopLinearizer(), p, *runs)
        assert cor_t == pytest.approx(sim.metrics.cor, abs=5e-5)
    assert sim.metrics.cor > 1.05  # the sampled slow table does pump energy
