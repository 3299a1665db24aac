"""The replay without a simulator: the physical part's laws at the ticks.

Where the table has an exact sampled form, the contact a ``force_law`` and
the sensor its ``readings``, :func:`hybridtable.measurement.replay.replay`
evaluates them tick by tick instead of simulating the discrete diagram. It
must be the same model, not a look-alike: every effect of the library (and
the nominal rig) gives the Drake replay's table motion, contact force and
reading bit for bit; a user's wrapped system (no law) still replays on the
diagram.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.effects.spec import ModelSpec
from hybridtable.measurement import replay as replay_module
from hybridtable.measurement.rig import RigPhysics
from hybridtable.measurement.run_reader import read_runs
from tests.examples import EXAMPLES

SIGNALS = ("p_act_m", "v_act_m_per_s", "f_act_n", "f_mea_n")

SPECS = {
    "nominal": ModelSpec(),
    "contact_damping": ModelSpec().with_contact(damping_n_s_per_m=300.0),
    "stiffness_error": ModelSpec().with_contact(stiffness_n_per_m=1.2e5),
    "power_law": ModelSpec().with_contact(exponent=1.5, reference_deflection_m=1e-3),
    "hunt_crossley": ModelSpec().with_contact(hunt_crossley_s_per_m=0.5),
    "coulomb_friction": ModelSpec().with_contact(friction_force_n=20.0),
    "series_compliance": ModelSpec().with_contact(series_compliance_m_per_n=2e-6, exponent=1.3),
    "fractional_delay": ModelSpec().with_sensor(extra_delay_s=0.0004),
    "whole_tick_delay": ModelSpec().with_sensor(extra_delay_s=0.002),
    "sensor_filter_delay_bias": ModelSpec().with_sensor(
        time_constant_s=0.001, extra_delay_s=0.0013, bias_n=-2.0
    ),
    "table_resonance": ModelSpec().with_table(frequency_hz=40.0, damping_ratio=0.05),
    "mount_resonance_filter_delay": ModelSpec().with_sensor(
        mount_frequency_hz=35.0,
        mount_damping_ratio=0.08,
        time_constant_s=0.001,
        extra_delay_s=0.0013,
    ),
}


@pytest.fixture(scope="module")
def run():
    return read_runs([str(EXAMPLES)])[0]


def _diagram_replay(monkeypatch, run, physics):
    with monkeypatch.context() as m:
        m.setattr(replay_module, "_law_replay", lambda *args: None)
        return replay_module.replay(run, physics)


@pytest.mark.parametrize("name", list(SPECS))
def test_the_law_replay_is_the_diagram_bit_for_bit(monkeypatch, run, name):
    physics = SPECS[name].physics()
    params = replay_module.rig_params(run.info, run.where("json"))
    laws = replay_module._law_replay(physics.apply(params), physics, run.p_des_m, run.v_des_m_per_s)
    assert laws is not None, f"{name}: every part states its law, no simulator needed"
    diagram = _diagram_replay(monkeypatch, run, physics)
    assert diagram.steps > 0  # the diagram path really simulated
    for signal in SIGNALS:
        np.testing.assert_array_equal(getattr(laws, signal), getattr(diagram, signal), signal)
    assert np.max(laws.f_act_n) > 100.0  # a real contact, not two zero records


def test_a_wrapped_system_replays_on_the_diagram(run):
    def wrap(params, system):  # a user's effect: a system with no stated law
        from pydrake.systems.framework import DiagramBuilder

        builder = DiagramBuilder()
        inner = builder.AddSystem(system)
        builder.ExportInput(inner.GetInputPort("motion"), "motion")
        builder.ExportOutput(inner.GetOutputPort("force"), "force")
        builder.ExportOutput(inner.GetOutputPort("force_rate"), "force_rate")
        return builder.Build()

    physics = ModelSpec().wrap("contact", wrap).physics()
    params = replay_module.rig_params(run.info, run.where("json"))
    assert replay_module._law_replay(params, physics, run.p_des_m, run.v_des_m_per_s) is None
    result = replay_module.replay(run, physics)
    nominal = replay_module.replay(run, RigPhysics())
    assert result.steps > 0
    np.testing.assert_array_equal(result.f_mea_n, nominal.f_mea_n)
