"""The linear loop exported for python-control (hybridtable.analysis.linear_export):
the documented recipe loads it, its poles and margins are the tool's, and its
state names say what the states are."""

from __future__ import annotations

import json
import math
import warnings

import control
import numpy as np
import pytest

from hybridtable.analysis.linear_export import (
    linear_model_document,
    load_linear_model,
    save_linear_model,
    state_labels,
)
from hybridtable.analysis.robustness import gain_delay_margins
from hybridtable.analysis.sampled import SampledLoopLinearizer
from hybridtable.errors import ParameterError
from hybridtable.studies.paper import table1_params


def _export(lin, params, path):
    sampled = params.sample_rate_hz is not None
    loop = (SampledLoopLinearizer(lin) if sampled else lin).open_loop(params)
    point = {"sensor_delay_s": params.sensor_delay_s, "table_response_hz": params.table_response_hz}
    doc = linear_model_document(loop, params.compensator, point, state_labels(params, 3, lin))
    return loop, save_linear_model(path, doc)


def _sorted(p):
    p = np.asarray(p, dtype=complex)
    return p[np.lexsort((p.imag, p.real))]


@pytest.mark.parametrize("suffix", [".json", ".npz"])
@pytest.mark.parametrize("rate", [None, 1000.0])
def test_python_control_loads_the_loop_with_the_tools_poles(lin, tmp_path, suffix, rate):
    p = table1_params("SDMDC").with_(sample_rate_hz=rate)
    loop, path = _export(lin, p, tmp_path / f"loop{suffix}")
    # The recipe of docs/margins.md, python-control and json / numpy only.
    d = json.load(open(path)) if suffix == ".json" else np.load(path)
    G = control.ss(d["A"], d["B"], d["C"], d["D"], float(d["dt"]))
    poles = control.feedback(G, 1, sign=1).poles()
    np.testing.assert_allclose(
        _sorted(poles), _sorted(loop.closed_loop_poles()), rtol=1e-9, atol=1e-9
    )
    assert G.dt == (0.0 if rate is None else pytest.approx(1e-3))
    # The margins of L = -G are the tool's (sampled: python-control's own
    # frequency grid misses the contact crossover, so give it a dense one).
    L = -G
    if rate is not None:
        L = control.frd(L, np.geomspace(0.05, math.pi * rate * (1 - 1e-9), 2001))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm, pm, _, _, wgc, _ = control.stability_margins(L, returnall=True)
    g = gain_delay_margins(loop)
    i = int(np.argmin(np.abs(np.asarray(wgc) - g.gain_crossover_rad_per_s)))
    assert np.asarray(pm)[i] == pytest.approx(g.phase_margin_deg, abs=1e-4)
    doc = load_linear_model(path)
    assert len(doc["state_names"]) == len(doc["state_units"]) == G.nstates
    assert doc["input_units"] == ["N"] and doc["output_units"] == ["N"]
    assert doc["compensator"] == "SDMDC"
    assert doc["operating_point"]["sensor_delay_s"] == pytest.approx(p.sensor_delay_s)
    assert doc["parameters"]["spacecraft_mass_kg"] == p.spacecraft_mass_kg


def test_the_state_names_say_what_the_states_are(lin):
    """Continuous: d p_des / dt = v_des, d v_des / dt = -u / m. Sampled at h:
    the spacecraft's Euler step, and the sensor a shift register of f_act."""
    p = table1_params("SDMDC")
    loop = lin.open_loop(p)
    names = [n for n, _, _ in state_labels(p, 3, lin)]
    units = dict((n, u) for n, u, _ in state_labels(p, 3, lin))
    i, j = names.index("p_des"), names.index("v_des")
    assert loop.A[i, j] == pytest.approx(1.0) and loop.B[j, 0] == pytest.approx(
        -1.0 / p.spacecraft_mass_kg
    )
    assert units["p_act"] == "m" and units["v_act"] == "m/s"
    k = names.index("p_act")
    assert loop.A[k, names.index("v_act")] == pytest.approx(1.0)
    h = 1e-3
    q = p.with_(sample_rate_hz=1000.0)
    sl = SampledLoopLinearizer(lin).open_loop(q)
    labels = state_labels(q, 3, lin)
    names = [n for n, _, _ in labels]
    assert names.count("f_act_k-5") == 1 and all(u == "N" for n, u, _ in labels if "f_act" in n)
    a, b = names.index("f_act_k-5"), names.index("f_act_k-4")
    assert sl.A[a, b] == pytest.approx(1.0)  # f_act[k-5] at the next tick is today's f_act[k-4]
    assert sl.A[names.index("p_des"), names.index("v_des")] == pytest.approx(h)


def test_only_json_and_npz(lin, tmp_path):
    p = table1_params("none")
    loop = lin.open_loop(p)
    doc = linear_model_document(loop, "none", {"sensor_delay_s": 0.005})
    with pytest.raises(ParameterError):
        save_linear_model(tmp_path / "loop.mat", doc)
    # Infinite parameters (an ideal table) stay valid JSON.
    q = p.with_(table_response_hz=math.inf)
    doc = linear_model_document(lin.open_loop(q), "none", {"table_response_hz": math.inf})
    path = save_linear_model(tmp_path / "ideal.json", doc)
    assert json.loads(path.read_text())["parameters"]["table_response_hz"] == "inf"
