"""Parameters of the 6-DoF loop: bad values get a clear error naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.errors import ParameterError
from hybridtable.six_dof.compensator import WrenchCompensator
from hybridtable.six_dof.params import (
    ApproachParams,
    DockingContactParams,
    RigidBodyParams,
    inertia_matrix,
)
from hybridtable.six_dof.registry import register_wrench_compensator, wrench_compensator_names
from hybridtable.six_dof.simulation import simulate6
from tests.six_dof.conftest import docking_params


@pytest.mark.parametrize(
    "value,words",
    [
        ((1.0, 1.0, 3.0), "triangle inequality"),
        ((1.0, 0.0, 1.0), "must all be > 0"),
        (((1, 0.5, 0), (0, 1, 0), (0, 0, 1)), "symmetric"),
        ((1.0, 2.0), "3 numbers or a 3x3"),
        ((1.0, float("nan"), 1.0), "finite"),
    ],
)
def test_unphysical_inertia_is_refused(value, words):
    with pytest.raises(ParameterError, match=words):
        RigidBodyParams(1000.0, value)


def test_a_rotated_box_inertia_is_accepted():
    """A box's inertia in a rotated frame: symmetric, not diagonal, physical."""
    c, s = np.cos(0.3), np.sin(0.3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    inertia = R @ np.diag([100.0, 200.0, 250.0]) @ R.T
    np.testing.assert_allclose(inertia_matrix("inertia_kg_m2", inertia), inertia)


@pytest.mark.parametrize(
    "build,field",
    [
        (lambda: DockingContactParams(-1.0), "contact_stiffness_n_per_m"),
        (lambda: DockingContactParams(1e5, pad_radius_m=0.5), "pad_radius_m"),
        (lambda: DockingContactParams(1e5, pad_count=2.5), "pad_count"),
        (lambda: ApproachParams(-0.1), "initial_velocity_m_per_s"),
        (lambda: ApproachParams(0.1, 0.001, (0.0, 0.7)), "misalignment_rad"),
        (lambda: ApproachParams(0.1, 0.001, (0.0, 0.0), (0.0, 1.2, 0.0)), "angular_rate"),
        (lambda: ApproachParams(0.1, 0.001, (0.0, 0.0), (0.0, 0.1)), "angular_rate"),
        (lambda: RigidBodyParams(0.0), "mass_kg"),
        (lambda: docking_params(sensor_delay_s=-0.001), "sensor_delay_s"),
        (lambda: docking_params(compensator="PID"), "compensator"),
        (lambda: docking_params(stiffness_model="given"), "compensator_stiffness_matrix"),
        (lambda: docking_params(compensator_stiffness_matrix=np.eye(5)), "6x6"),
    ],
)
def test_bad_values_name_their_field(build, field):
    with pytest.raises(ParameterError, match=field):
        build()


def test_a_plugin_wrench_compensator_registers_itself_and_runs():
    """A plug-in: SDC at half the lead, registered by name, then chosen like
    the paper's four; its CoR lies between none's and SDC's."""

    def half_lead(params, stiffness):
        return WrenchCompensator(params.sample_period_s, 0.5 * params.effective_lead_time_s)

    register_wrench_compensator("half-lead", half_lead, replace=True)
    assert "half-lead" in wrench_compensator_names()
    with pytest.raises(ValueError):
        register_wrench_compensator("SDC", half_lead)
    cor = {
        name: simulate6(
            docking_params(sensor_delay_s=0.005, compensator=name, table_response_hz=25.0)
        ).metrics.cor_normal
        for name in ("none", "half-lead", "SDC")
    }
    assert cor["SDC"] < cor["half-lead"] < cor["none"]


def test_a_plugins_margins_are_those_of_the_linear_law_it_declares_or_none():
    """A plug-in's linearized loop is the paper's law it declares; without
    one it has no linear model (never the "none" loop's margins by default)."""
    from hybridtable.errors import ParameterError
    from hybridtable.six_dof.linear import contact_modes, tick_matrix
    from hybridtable.six_dof.registry import LinearLaw, linear_law

    def plain_sdc(params, stiffness):
        return WrenchCompensator(params.sample_period_s, params.effective_lead_time_s)

    register_wrench_compensator("plain-sdc", plain_sdc, replace=True)
    assert linear_law("plain-sdc") is None
    p = docking_params(sensor_delay_s=0.005, compensator="plain-sdc", table_response_hz=25.0)
    K, C = np.eye(6) * 1e4, np.eye(6)
    with pytest.raises(ParameterError, match="plain-sdc"):
        tick_matrix(p, K, C)
    register_wrench_compensator("plain-sdc", plain_sdc, replace=True, linear=LinearLaw("SDC"))
    sdc = p.with_(compensator="SDC")
    np.testing.assert_array_equal(tick_matrix(p, K, C), tick_matrix(sdc, K, C))
    assert contact_modes(p).max_growth_rate_per_s == contact_modes(sdc).max_growth_rate_per_s
    with pytest.raises(ParameterError, match="law"):
        LinearLaw("PID")
    # an entry point's factory declares it as an attribute
    plain_sdc.linear = LinearLaw("SDC")
    register_wrench_compensator("plain-sdc", plain_sdc, replace=True)
    assert linear_law("plain-sdc") == LinearLaw("SDC")


@pytest.mark.parametrize(
    "group,module",
    [
        ("hybridtable.wrench_compensators", "hybridtable.six_dof.params"),
        ("hybridtable.compensators", "hybridtable.loop.params"),
    ],
)
def test_a_plugin_that_imports_the_parameters_loads(tmp_path, group, module):
    """A compensator plug-in (an installed entry point) whose module imports
    the loop's parameters: the parameters' defaults are built on use, not at
    import, so the registry's load of the plug-in does not meet a half-loaded
    module (it did for the 6-DoF loop: every simulate6 failed)."""
    import subprocess
    import sys

    (tmp_path / "ht_plug.py").write_text(
        f"from {module} import *  # a plug-in typing its factory\n"
        "def make(*args):\n    raise NotImplementedError\n"
    )
    info = tmp_path / "ht_plug-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: ht-plug\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{group}]\nplug = ht_plug:make\n")
    names = (
        "from hybridtable.six_dof.registry import wrench_compensator_names as names"
        if "wrench" in group
        else "from hybridtable.compensators.registry import compensator_names as names"
    )
    code = f"import {module}\n{names}\nprint('plug' in names())"
    env = {**__import__("os").environ, "PYTHONPATH": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr[-1500:]
    assert out.stdout.strip() == "True"


def test_a_config_of_the_wrong_kind_is_named():
    from hybridtable.six_dof.params import DockingRig

    with pytest.raises(ParameterError, match="compensator must be a WrenchCompensatorConfig"):
        DockingRig(compensator="SDC")
    with pytest.raises(ParameterError, match=r"e\.g\. spacecraft="):
        docking_params().with_(plant=docking_params().spacecraft)
