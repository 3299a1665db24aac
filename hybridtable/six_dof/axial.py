"""A 6-DoF run on the docking axis as the 1-D run it is (``hybridtable-run/1``).

On axis (the port's axis through the centre of mass, no misalignment, no
lateral miss) the 6-DoF loop is the 1-D loop: the table's motion, the
contact and the spacecraft's stay on the docking axis. :func:`axial_run`
projects a recorded 6-DoF run on it: ``p = pz`` (the pad ring's top touches
the plate's face at ``pz = 0``; ``p > 0`` is penetration, as in the 1-D
format), ``f = -fz`` (the compression force pushes the spacecraft back along
``-z``), ``v_des = vz_des``, and the 1-D run's JSON from the scenario, with
the table's state at t = 0 the 6-DoF loop starts from (tracking the approach's
ramp, :func:`~hybridtable.six_dof.builder.set_initial_table`) as the 1-D
format's extra key ``table_initial_state``. The 1-D
commands (``compare``, ``diagnose``, the audit) then read it as any 1-D run,
which checks that the two loops are one.
"""

from __future__ import annotations

import math

from hybridtable.errors import ParameterError
from hybridtable.measurement.recorder import FORMAT_COMPENSATORS
from hybridtable.measurement.rig import TABLE_START_KEY
from hybridtable.measurement.run_format import Run, RunInfo
from hybridtable.six_dof.builder import initial_port_state
from hybridtable.six_dof.params import DockingLoopParams
from hybridtable.six_dof.run6 import Run6
from hybridtable.six_dof.spacecraft import RigidSpacecraft

__all__ = ["axial_run"]


def axial_run(run: Run6) -> Run:
    """The 1-D run of an on-axis 6-DoF run (see the module).

    Raises
    ------
    ParameterError
        If the scenario is off axis, its table is ideal (the 1-D format states
        a second-order table), or its compensator is not one of the 1-D
        format's.
    """
    p = run.params
    off = []
    if any(x != 0.0 for x in p.spacecraft.lateral_offset_m):
        off.append("lateral_offset_m")
    if any(x != 0.0 for x in p.approach.misalignment_rad):
        off.append("misalignment_deg")
    if any(x != 0.0 for x in p.approach.lateral_miss_m):
        off.append("lateral_miss_m")
    if any(x != 0.0 for x in p.approach.angular_rate_rad_per_s):
        off.append("angular_rate_rad_per_s")
    if p.contact.is_cone:
        off.append('geometry = "cone"')
    if off:
        raise ParameterError(
            f"run {run.run_id} is not on the docking axis ({', '.join(off)}): only an on-axis "
            "run is a 1-D run"
        )
    if not math.isfinite(p.table_response_hz):
        raise ParameterError(
            f"run {run.run_id}: an ideal table (response_hz = inf) has no 1-D run format "
            "(it states a second-order table)"
        )
    if p.compensator not in FORMAT_COMPENSATORS:
        raise ParameterError(
            f"run {run.run_id}: compensator {p.compensator} is not one of the 1-D format's "
            f"({', '.join(FORMAT_COMPENSATORS)})"
        )
    info = RunInfo(
        run_id=run.run_id,
        sample_rate_hz=p.sample_rate_hz,
        spacecraft_mass_kg=p.spacecraft.mass_kg,
        contact_stiffness_n_per_m=p.contact.contact_stiffness_n_per_m,
        sensor_delay_s=p.sensor_delay_s,
        table_natural_frequency_hz=p.table_response_hz,
        table_damping_ratio=p.table_damping_ratio,
        compensator=p.compensator,
        lead_time_s=p.effective_lead_time_s,
        initial_gap_m=p.approach.initial_gap_m,
        initial_velocity_m_per_s=p.approach.initial_velocity_m_per_s,
        force_deadband_n=p.force_deadband_n,
        extra={TABLE_START_KEY: _table_start(p)},
    )
    b = run.blocks
    return Run(
        info,
        run.time_s.copy(),
        b["p_des"][:, 2].copy(),
        b["p_act"][:, 2].copy(),
        -b["f_mea"][:, 2],
        -b["f_comp"][:, 2],
        b["v_des"][:, 2].copy(),
        csv_path=run.csv_path,
        json_path=run.json_path,
    )


def _table_start(params: DockingLoopParams) -> dict[str, float]:
    """The table's position and velocity along the axis at t = 0, as the 6-DoF
    loop starts it: the approach's command less the table's ramp lag."""
    command, _ = initial_port_state(
        params, RigidSpacecraft(params.spacecraft, params.sample_period_s)
    )
    lag = params.plant.table.response.ramp_lag_s
    return {
        "position_m": float(command[2] - lag * command[8]),
        "velocity_m_per_s": float(command[8]),
    }
