"""The 1-D effects along the normal that the six-axis rig now carries (the
pads' own law: ``contact_damping``, ``nonlinear_stiffness``,
``series_compliance``, ``coulomb_friction``; the table's structural mode,
``table_resonance``): a fit finds what the independent 6-DoF generator hid
(``tests/generators/rig6.py``, written from docs/run6-format.md alone, its own
pad law and its own exponential of the servo and the mode, in its own closed
loop), within four of its standard errors, down to the noise (on a hidden
``hunt_crossley``, a law Drake's point contact carries, the same run's
chi2 / n after the fit is 1.24: the noise levels' own scatter)."""

from __future__ import annotations

import pytest

from hybridtable.effects.registry import get_effect
from tests.generators import run6_logs as g6

#: Whole closed loops and fits.
pytestmark = pytest.mark.slow

CASES = {
    "contact_damping": {"damping_n_s_per_m": 600.0},
    "nonlinear_stiffness": {"exponent": 1.3, "reference_stiffness_n_per_m": 1.1e5},
    "series_compliance": {"series_compliance_m_per_n": 2.0e-6},
    "coulomb_friction": {"friction_force_n": 40.0},
    "table_resonance": {"frequency_hz": 30.0, "damping_ratio": 0.05},
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_fit_finds_what_the_six_axis_generator_hid(tmp_path, name):
    from hybridtable.six_dof.fit6 import fit_runs6
    from hybridtable.six_dof.run6 import read_run6

    truth = CASES[name]
    scen = g6.scenario(compensator={"name": "SDC"})
    scen["approach"]["misalignment_deg"] = [0.5, -1.0]  # off the axis: the pads unequal
    rows = g6.generate_run6(
        scen,
        seed=5,
        force_noise_n=2.0,
        moment_noise_n_m=0.5,
        position_noise_m=2e-6,
        attitude_noise_rad=1e-6,
        hidden={name: truth},
        table_start="tick0",
    )
    csv, _ = g6.write_run6(tmp_path, name, scen, rows)
    fit = fit_runs6([read_run6(csv)], [(get_effect(name), {})])
    # the hidden effect is seen, and explained to the noise (each component's
    # noise level comes from some tens of quiet ticks: the pose's within a few
    # tens of per cent, so chi2 / n of a right model lies near 1.0-1.25)
    assert fit.chi2_before / fit.n_residuals > 2.0
    assert fit.chi2_after / fit.n_residuals < 1.3
    for parameter, value in truth.items():
        std = fit.std[name][parameter]
        found = fit.values[name][parameter]
        assert std is not None and abs(found - value) < 4.0 * std, (parameter, found, std)
