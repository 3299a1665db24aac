"""The 6-DoF model against a recorded 6-DoF run, component by component, in
noise units.

:func:`compare_run6` replays the run's commands through the model's table,
contact and sensor (:func:`~hybridtable.six_dof.replay6.replay_run6`) and
compares every measured component with the replay's: the force and moment the
F/T sensor read, the table's position and attitude (the rotation vector of
its quaternion). Each residual's RMS is divided by the component's noise
level (:func:`noise_level`), and the largest ``|residual| / noise`` is placed
in time and in the contact's phase (approach, contact, after). It also runs
the scenario's whole loop (:func:`~hybridtable.six_dof.simulation.simulate6`,
without the noise) for as many ticks as the record: the closed loop's
components, normal CoR and energy ratio against the record's.

The verdict reads the replay: the model explains the run when every
component's RMS error is at most :data:`EXPLAINED_SIGMA` noise levels; else
it names the component that misses most and where. The closed loop is
reported beside it, not judged: the F/T noise fed back through the
compensator moves the lateral friction of a sliding contact by far more than
the noise (measured: 276 N RMS across the face for 2 N of F/T noise on
``offset.toml`` with SDMDC), so a closed loop cannot be held to the noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridtable.measurement.phases import quiet_ticks, settle_ticks
from hybridtable.measurement.stats import force_noise_rms, position_noise_rms
from hybridtable.six_dof.physics6 import DockingPhysics
from hybridtable.six_dof.pose import rotation_vectors_of_quaternions
from hybridtable.six_dof.replay6 import replay_run6
from hybridtable.six_dof.run6 import Run6, noise_levels, run6_of_docking
from hybridtable.six_dof.simulation import peak_force_n, simulate6
from hybridtable.six_dof.touch import force_from_rest
from hybridtable.systems.table import TableParams

__all__ = [
    "EXPLAINED_SIGMA",
    "COMPONENTS",
    "ComponentError",
    "Comparison6",
    "compare_run6",
    "replay_residuals",
    "measured_block",
    "noise_level",
    "noise_levels_of",
    "phases",
]

#: The largest RMS error (in noise levels) of a component the model explains.
EXPLAINED_SIGMA = 3.0

#: Compared components: (name, block, column, unit).
COMPONENTS: tuple[tuple[str, str, int, str], ...] = (
    *((f"f{a}_mea", "f_mea", i, "N") for i, a in enumerate("xyz")),
    *((f"m{a}_mea", "m_mea", i, "N m") for i, a in enumerate("xyz")),
    *((f"p{a}_act", "p_act", i, "m") for i, a in enumerate("xyz")),
    *((f"theta{a}_act", "theta_act", i, "rad") for i, a in enumerate("xyz")),
)

#: Floors of the noise levels, as fractions of the contact's own scales (a
#: noise-free record's resolution: 0.016 N and 0.16 um on Table 1's contact).
_FLOOR = 1e-5


@dataclass(frozen=True)
class ComponentError:
    """One component's closed-loop error.

    Attributes
    ----------
    name, unit : str
    rms_error : float
        RMS of measured minus model, in the unit.
    noise : float
        The component's noise level (std), in the unit.
    error_sigma : float
        ``rms_error / noise``.
    worst_time_s : float
        Where ``|residual| / noise`` is largest.
    worst_phase : str
        ``approach``, ``contact`` or ``after`` at that time.
    """

    name: str
    unit: str
    rms_error: float
    noise: float
    error_sigma: float
    worst_time_s: float
    worst_phase: str

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class Comparison6:
    """A 6-DoF run against the model's closed loop (see the module)."""

    run_id: str
    components: list[ComponentError]
    closed_loop: list[ComponentError]
    cor_measured: float
    cor_model: float
    energy_ratio_measured: float
    energy_ratio_model: float
    contact_s: tuple[float, float]
    n_ticks: int
    model_wall_time_s: float
    notes: list[str] = field(default_factory=list)
    #: The run and the replay's series by block (for figures; not in the JSON).
    run: Run6 | None = None
    replayed: dict[str, np.ndarray] | None = None

    @property
    def worst(self) -> ComponentError:
        return max(self.components, key=lambda c: c.error_sigma)

    @property
    def explained(self) -> bool:
        return self.worst.error_sigma <= EXPLAINED_SIGMA

    def verdict(self) -> str:
        """One line: explained or not, with the evidence."""
        w = self.worst
        cor = (
            f"CoR along the normal {self.cor_measured:.4f} measured, {self.cor_model:.4f} modelled"
        )
        if self.explained:
            return (
                f"{self.run_id}: the model explains the run: every component within "
                f"{EXPLAINED_SIGMA:g} noise levels (largest {w.name} {w.error_sigma:.2f}); {cor}."
            )
        return (
            f"{self.run_id}: the model misses the run: {w.name} is {w.error_sigma:.3g} noise "
            f"levels off (RMS), most in the {w.worst_phase} at t = {w.worst_time_s:.4g} s; {cor}."
        )

    def to_dict(self) -> dict:
        return {
            "run_id": self.run_id,
            "explained": self.explained,
            "explained_sigma": EXPLAINED_SIGMA,
            "verdict": self.verdict(),
            "worst": self.worst.name,
            "cor_measured": self.cor_measured,
            "cor_model": self.cor_model,
            "cor_error": self.cor_model - self.cor_measured,
            "energy_ratio_measured": self.energy_ratio_measured,
            "energy_ratio_model": self.energy_ratio_model,
            "contact_s": list(self.contact_s),
            "n_ticks": self.n_ticks,
            "model_wall_time_s": self.model_wall_time_s,
            "components": [c.to_dict() for c in self.components],
            "closed_loop": [c.to_dict() for c in self.closed_loop],
            "notes": list(self.notes),
        }


def _length_m(run: Run6) -> float:
    """The contact's lever: the pad ring's radius, the drogue's mouth's."""
    c = run.params.contact
    return float(c.mouth_radius_m if c.is_cone else c.ring_radius_m)


def noise_level(run: Run6, block: str) -> np.ndarray:
    """Each column's noise std of a measured block over the ticks out of
    contact (:func:`_quiet`: before the touch, and after the release unless
    there are enough before it; at least 20 of them), by the 1-D comparison's
    estimators: a wrench's pooled std about each
    quiet stretch's mean (:func:`~hybridtable.measurement.stats.force_noise_rms`),
    a pose's from third differences
    (:func:`~hybridtable.measurement.stats.position_noise_rms`); with fewer
    quiet ticks, the robust white-noise estimate of
    :func:`~hybridtable.six_dof.run6.noise_levels` over every tick; floored at :data:`_FLOOR` of its scale: the undamped head-on peak
    force, that force over the contact's lever, the peak deflection ``v0 /
    omega`` and that over the lever (a record without noise is compared at
    the floor)."""
    return noise_levels_of(run)[block]


def noise_levels_of(run: Run6) -> dict[str, np.ndarray]:
    """:func:`noise_level` of every measured block of :data:`COMPONENTS`
    (the ticks out of contact found once)."""
    p = run.params
    force = peak_force_n(p)
    deflection = p.approach.initial_velocity_m_per_s / (2.0 * math.pi * p.contact_frequency_hz)
    lever = _length_m(run)
    scales = {
        "f_mea": force,
        "m_mea": force * lever,
        "p_act": deflection,
        "theta_act": deflection / lever,
    }
    quiet_wrench, quiet_pose = _quiet(run)
    out = {}
    for block, scale in scales.items():
        values = _block(run, block)
        level = noise_levels(values)  # robust, over every tick: the fallback
        wrench = block in ("f_mea", "m_mea")
        quiet = quiet_wrench if wrench else quiet_pose
        if np.count_nonzero(quiet) >= _QUIET_TICKS:  # the 1-D comparison's estimators
            estimate = force_noise_rms if wrench else position_noise_rms
            quiet_level = np.array([estimate(c, quiet)[0] for c in values.T])
            level = np.where(np.isfinite(quiet_level), quiet_level, level)
        out[block] = np.maximum(level, _FLOOR * scale)
    return out


#: Ticks out of contact the noise is estimated from (fewer: every tick).
_QUIET_TICKS = 20


#: Quiet ticks before the first touch enough for the wrench's noise alone
#: (fewer: every quiet stretch, as the 1-D comparison).
_BEFORE_TICKS = 50


def _quiet(run: Run6) -> tuple[np.ndarray, np.ndarray]:
    """The ticks out of contact (:attr:`~hybridtable.six_dof.run6.Run6.contact_ticks`), as the 1-D comparison
    takes them (:func:`~hybridtable.measurement.phases.quiet_ticks`): the
    wrench's and the pose's (the short one if fewer than
    :data:`_QUIET_TICKS`). With at least :data:`_BEFORE_TICKS` quiet ticks
    before the first touch the wrench's are those alone: the sensor has seen
    no contact yet, while after the release whatever dynamics it has (a
    mount's ringing, a filter's tail) would pass for noise and hide itself."""
    p = run.params
    table = TableParams(p.table_response_hz, p.table_damping_ratio)
    settle = settle_ticks(table.settling_time_s, p.sample_period_s, run.n)
    wrench, pose, short = quiet_ticks(run.contact_ticks, p.delay_ticks, settle)
    first = int(np.argmin(wrench)) if not np.all(wrench) else run.n
    if first >= _BEFORE_TICKS:
        wrench[first:] = False
    return wrench, pose if np.count_nonzero(pose) >= _QUIET_TICKS else short


def measured_block(run: Run6, block: str) -> np.ndarray:
    """A measured block of :data:`COMPONENTS` (``theta_act``: the rotation
    vector of the measured attitude)."""
    return _block(run, block)


def _block(run: Run6, block: str) -> np.ndarray:
    if block == "theta_act":
        return run.pose("act")[:, 3:]
    return run.blocks[block]


def phases(run: Run6) -> tuple[np.ndarray, tuple[float, float]]:
    """Each tick's phase (0 approach, 1 contact, 2 after) and the contact's
    first and last time, from the measured force (from its level at rest,
    :func:`~hybridtable.six_dof.touch.force_from_rest`: above five noise
    levels and the dead band)."""
    force = force_from_rest(run.blocks["f_mea"], run.contact_ticks)
    level = 5.0 * float(np.linalg.norm(noise_level(run, "f_mea"))) + run.params.force_deadband_n
    touching = np.flatnonzero(force > level)
    phase = np.zeros(run.n, dtype=int)
    if touching.size:
        phase[touching[0] : touching[-1] + 1] = 1
        phase[touching[-1] + 1 :] = 2
        return phase, (float(run.time_s[touching[0]]), float(run.time_s[touching[-1]]))
    return phase, (math.nan, math.nan)


_PHASES = ("approach", "contact", "after")


def _errors(run: Run6, predicted: dict[str, np.ndarray], phase: np.ndarray) -> list:
    n = min(run.n, *(len(v) for v in predicted.values()))
    out = []
    levels = noise_levels_of(run)
    for name, block, j, unit in COMPONENTS:
        residual = _block(run, block)[:n, j] - predicted[block][:n, j]
        sigma = float(levels[block][j])
        scaled = np.abs(residual) / sigma
        k = int(np.argmax(scaled))
        rms = float(np.sqrt(np.mean(residual**2)))
        out.append(
            ComponentError(
                name, unit, rms, sigma, rms / sigma, float(run.time_s[k]), _PHASES[phase[k]]
            )
        )
    return out


def _replayed(run: Run6, physics: DockingPhysics | None) -> dict[str, np.ndarray]:
    replay = replay_run6(run, physics)
    return {
        "f_mea": replay.measured_wrench[:, 3:],
        "m_mea": replay.measured_wrench[:, :3],
        "p_act": replay.table_state[:, :3],
        "theta_act": replay.table_state[:, 3:6],
    }


def replay_residuals(
    run: Run6, physics: DockingPhysics | None = None, levels: dict | None = None
) -> np.ndarray:
    """Every component's replay residual at every tick, in its noise levels
    (``levels``: the run's :func:`noise_levels_of`, found once by a caller
    that replays it many times), one component after the other
    (:data:`COMPONENTS`; the fit's residual)."""
    predicted = _replayed(run, physics)
    levels = noise_levels_of(run) if levels is None else levels
    out = []
    for _, block, j, _ in COMPONENTS:
        sigma = float(levels[block][j])
        out.append((_block(run, block)[:, j] - predicted[block][: run.n, j]) / sigma)
    return np.concatenate(out)


def compare_run6(run: Run6, physics: DockingPhysics | None = None) -> Comparison6:
    """The run against the model's replay and closed loop (see the module),
    the rig's physical part the scenario's or ``physics`` (with effects).

    Raises
    ------
    SimulationError
        If the model's replay or loop fails or diverges, or cannot run the
        record's length.
    """
    params = run.params
    h = params.sample_period_s
    phase, contact = phases(run)
    replayed = _replayed(run, physics)
    model_params = params.without_noise(duration_s=run.n * h)
    simulated = simulate6(model_params, physics=physics)
    model = run6_of_docking(simulated, f"{run.run_id}-model", run.scenario)
    looped = {b: _block(model, b) for b in ("f_mea", "m_mea", "p_act")}
    looped["theta_act"] = rotation_vectors_of_quaternions(model.blocks["q_act"])
    notes = []
    if model.n < run.n:
        notes.append(f"the model's loop ran {model.n} of the record's {run.n} ticks")
    measured_metrics = run.metrics()
    model_metrics = model.metrics()
    return Comparison6(
        run.run_id,
        _errors(run, replayed, phase),
        _errors(run, looped, phase),
        measured_metrics.cor_normal,
        model_metrics.cor_normal,
        measured_metrics.energy_ratio,
        model_metrics.energy_ratio,
        contact,
        run.n,
        simulated.wall_time_s,
        notes,
        run,
        replayed,
    )
