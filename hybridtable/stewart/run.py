"""One run of the hybrid loop with the Stewart back-end (what ``simulate --table stewart`` does).

:func:`simulate_stewart` tunes the table to the loop's table response,
identifies it, runs the loop and logs what :mod:`hybridtable.stewart.view`
draws (:class:`StewartRun`). :func:`stewart_limits` says what the table
reaches at a sample rate (the fastest response, the docking-axis
workspace), so that a caller can refuse a run before any simulation and say
which parameter to change.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hybridtable.errors import ParameterError
from hybridtable.laws.contact import critical_damping_n_s_per_m
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import SimulationResult, run_loop, simulate
from hybridtable.stewart.backend import add_stewart_loop, stewart_params_for_loop
from hybridtable.stewart.identify import TableResponse, identify_chirp, tune_table
from hybridtable.stewart.params import StewartParams
from hybridtable.stewart.progress import SimulatedTimeProgress, add_progress_ticker
from hybridtable.stewart.view import MotionView, PoseRecorder, StewartMotion, open_meshcat

__all__ = [
    "DEFAULT_SAMPLE_RATE_HZ",
    "MAX_RESPONSE_PER_SAMPLE_RATE",
    "StewartLimits",
    "StewartRun",
    "check_stewart_loop",
    "simulate_stewart",
    "stewart_limits",
    "stewart_loop_params",
]

#: Rig-computer rate used when a run asks for the continuous loop: the plant
#: is discrete, every discrete part then shares its period.
DEFAULT_SAMPLE_RATE_HZ = 1000.0

#: The fastest table response the default platform is tuned to, per hertz of
#: sample rate: its leg servo (bandwidth ``0.08 / time_step_s``) reaches
#: identified responses up to ``0.055 * sample rate`` (55 Hz at 1 kHz, 110 Hz
#: at 2 kHz, measured; 60 Hz at 1 kHz fails after ~10 s of tuning).
MAX_RESPONSE_PER_SAMPLE_RATE = 0.05

#: Upper end of the chirp identification, Hz, or 80 % of the Nyquist rate if lower.
CHIRP_STOP_HZ = 60.0


@dataclass(frozen=True)
class StewartLimits:
    """What the Stewart table reaches in a loop sampled at ``sample_rate_hz``.

    Attributes
    ----------
    sample_rate_hz : float
        The loop's sample rate (the plant's time step is its period), Hz.
    max_response_hz : float
        Fastest table response it is tuned to, Hz
        (:data:`MAX_RESPONSE_PER_SAMPLE_RATE` times the rate).
    workspace_m : (float, float)
        Reachable docking-axis positions of the device from the contact
        point (penetration positive), m.
    """

    sample_rate_hz: float
    max_response_hz: float
    workspace_m: tuple[float, float]

    @staticmethod
    def min_sample_rate_hz(response_hz: float) -> float:
        """The lowest whole sample rate that reaches ``response_hz``, Hz."""
        return float(math.ceil(response_hz / MAX_RESPONSE_PER_SAMPLE_RATE - 1e-9))

    def max_initial_gap_m(self, params: HybridLoopParams) -> float:
        """The largest ``initial_gap_m`` whose starting table position (the
        gap plus the table's lag behind the approach ramp) is reachable, m."""
        ic = params.initial_conditions()
        behind = ic["p_des_m"] - min(ic["p_des_m"], ic["p_act_m"])
        return -self.workspace_m[0] - behind


def stewart_limits(params: HybridLoopParams, stewart: StewartParams | None = None) -> StewartLimits:
    """The limits of ``stewart`` (default ``StewartParams()``) at the loop's
    sample rate (:data:`DEFAULT_SAMPLE_RATE_HZ` for a continuous loop)."""
    rate = params.sample_rate_hz or DEFAULT_SAMPLE_RATE_HZ
    geometry = (stewart or StewartParams()).geometry
    return StewartLimits(
        sample_rate_hz=rate,
        max_response_hz=MAX_RESPONSE_PER_SAMPLE_RATE * rate,
        workspace_m=geometry.axis_workspace(),
    )


def check_stewart_loop(params: HybridLoopParams, stewart: StewartParams | None = None) -> None:
    """Refuse, before any simulation, a loop the Stewart table cannot run.

    The messages name the fields of ``params`` (a command translates them into
    its flags) and say what to change.

    Parameters
    ----------
    params
        The loop as asked for: a continuous loop (``sample_rate_hz`` None)
        runs sampled at :data:`DEFAULT_SAMPLE_RATE_HZ`.
    stewart
        The platform (default ``StewartParams()``).

    Raises
    ------
    ParameterError
        An infinite or too fast ``table_response_hz`` for the sample rate; an
        ``initial_gap_m`` that starts the table outside its
        workspace; a ``contact_damping_n_s_per_m`` at or above critical (the
        Hunt-Crossley contact has no equivalent of a contact that does not
        rebound).
    """
    rate = params.sample_rate_hz or DEFAULT_SAMPLE_RATE_HZ
    at_rate = f"sample_rate_hz {rate:g}" + (
        "" if params.sample_rate_hz is not None else " (its default)"
    )
    f = params.table_response_hz
    if math.isinf(f):
        raise ParameterError(
            "table_response_hz inf: the Stewart table has a finite response; give a finite "
            "table_response_hz"
        )
    if params.sample_rate_hz is None:
        params = params.with_(sample_rate_hz=rate)
    limits = stewart_limits(params, stewart)
    if f > limits.max_response_hz * (1.0 + 1e-12):
        needed = limits.min_sample_rate_hz(f)
        raise ParameterError(
            f"table_response_hz {f:g} is too fast for the Stewart table at {at_rate}: it "
            f"needs table_response_hz <= {limits.max_response_hz:g}, or sample_rate_hz >= "
            f"{needed:g}"
        )
    gap = limits.max_initial_gap_m(params)
    if params.initial_gap_m > gap:
        raise ParameterError(
            f"initial_gap_m {params.initial_gap_m:g} starts the Stewart table outside its "
            f"workspace: it reaches {-limits.workspace_m[0]:.4f} m below the contact point "
            f"(needs initial_gap_m <= {gap:.4f})"
        )
    k, c = params.contact_stiffness_n_per_m, params.contact_damping_n_s_per_m
    critical = critical_damping_n_s_per_m(k, params.spacecraft_mass_kg)
    if c >= critical:
        raise ParameterError(
            f"contact_damping_n_s_per_m {c:g} is at or above the contact's critical damping "
            f"({critical:.6g} N s/m with contact_stiffness_n_per_m {k:g} and "
            f"contact_frequency_hz {params.contact_frequency_hz:g}): such a contact does not "
            "rebound and the Stewart table's Hunt-Crossley contact has no equivalent; give a "
            "smaller contact_damping_n_s_per_m"
        )


@dataclass
class StewartRun:
    """A Stewart-loop run with the table's identification.

    Attributes
    ----------
    result : SimulationResult
        The loop's logged signals and contact metrics.
    params : HybridLoopParams
        The loop parameters run (sampled).
    stewart : StewartParams
        The table run (tuned).
    step, chirp : TableResponse
        The table's response identified from a step and (optionally) a chirp.
    second_order_cor : float
        CoR of the 1-D loop with the second-order table of the step
        identification (same loop parameters otherwise).
    wall_time_s : float
        Wall time of the loop simulation alone.
    motion : StewartMotion
        The plate's pose and the contact force at every step (what
        :meth:`view` draws).
    """

    result: SimulationResult
    params: HybridLoopParams
    stewart: StewartParams
    step: TableResponse
    chirp: TableResponse | None
    second_order_cor: float
    wall_time_s: float
    motion: StewartMotion | None = None

    @property
    def real_time_factor(self) -> float:
        """Simulated time / wall time of the loop simulation."""
        return float(self.result.time_s[-1]) / self.wall_time_s

    def summary(self) -> dict:
        """The table's identification and settings as a JSON-able dict."""
        kp, kd = self.stewart.servo_gains()
        return {
            "table": "stewart",
            "sample_rate_hz": self.params.sample_rate_hz,
            "identified_table": {
                "step": self.step.as_dict(),
                "chirp": None if self.chirp is None else self.chirp.as_dict(),
            },
            "stewart": {
                "time_step_s": self.stewart.time_step_s,
                "leg_stiffness_n_per_m": kp,
                "leg_damping_n_s_per_m": kd,
                "reference_response_hz": self.stewart.reference_response_hz,
                "reference_damping_ratio": self.stewart.reference_damping_ratio,
                "workspace_m": list(self.stewart.geometry.axis_workspace()),
            },
            "second_order_cor": self.second_order_cor,
            "loop_wall_time_s": self.wall_time_s,
            "real_time_factor": self.real_time_factor,
        }

    def view(
        self,
        meshcat=None,
        magnify: float | None = None,
        force_scale_n_per_m: float | None = None,
    ) -> MotionView:
        """A :class:`~hybridtable.stewart.view.MotionView` of the run in
        ``meshcat`` (default: a new server on localhost, see
        :func:`~hybridtable.stewart.view.open_meshcat`)."""
        if self.motion is None:
            raise ParameterError("this run logged no motion to draw")
        meshcat = open_meshcat() if meshcat is None else meshcat
        return MotionView(meshcat, self.stewart, self.motion, magnify, force_scale_n_per_m)

    def write_html(
        self,
        path: str | Path,
        magnify: float | None = None,
        realtime_rate: float = 1.0,
        overwrite: bool = False,
    ) -> MotionView:
        """Record the run (:meth:`view`, :meth:`MotionView.record`) and write
        it as a self-contained HTML file (about 2 MB; an existing file only
        with ``overwrite``); returns the view (its ``magnify`` and
        ``force_scale_n_per_m``)."""
        from hybridtable._files import write_text_atomic

        path = Path(path)
        if path.exists() and not overwrite:
            raise ParameterError(f"refusing to overwrite {path}")
        view = self.view(magnify=magnify)
        view.record(realtime_rate)
        write_text_atomic(path, view.html())
        return view


def stewart_loop_params(params: HybridLoopParams) -> HybridLoopParams:
    """``params`` as the Stewart loop runs them: sampled (at
    :data:`DEFAULT_SAMPLE_RATE_HZ` if they ask for a continuous loop)."""
    if params.sample_rate_hz is None:
        return params.with_(sample_rate_hz=DEFAULT_SAMPLE_RATE_HZ)
    return params


def _expected_loop_s(params: HybridLoopParams) -> float:
    """About how long the loop runs (approach, one contact half-period, the
    settling window of :func:`~hybridtable.loop.simulation.run_loop`), s."""
    table = params.plant.table
    v = params.initial_velocity_m_per_s
    approach = (params.initial_gap_m + table.ramp_lag_s * v) / v
    settle = params.sensor_delay_s + 5.0 / params.sample_rate_hz
    if not table.is_ideal:
        settle += min(
            5.0 / max(table.damping_ratio * table.omega_rad_per_s, 1e-9),
            20.0 / table.response_frequency_hz,
        )
    return approach + 0.5 / params.contact_frequency_hz + settle


def simulate_stewart(
    params: HybridLoopParams,
    stewart: StewartParams | None = None,
    html: str | Path | None = None,
    chirp: bool = True,
    progress: bool = False,
    **run_kwargs,
) -> StewartRun:
    """Tune the Stewart table to the loop's table response, identify it, and
    run the loop through one contact.

    Parameters
    ----------
    params : HybridLoopParams
        Loop parameters; ``table_response_hz`` / ``table_damping_ratio`` are
        the targets of the table's tuning (:func:`~hybridtable.stewart.identify.tune_table`).
        A continuous loop is run sampled at :data:`DEFAULT_SAMPLE_RATE_HZ`.
    stewart : StewartParams, optional
        The platform (default: ``StewartParams()``); its time step becomes
        the loop's sample period.
    html : path, optional
        Record a Meshcat animation of the run, magnified
        (:func:`~hybridtable.stewart.view.auto_magnify`), to this
        self-contained HTML file (must not exist; :meth:`StewartRun.write_html`
        for the options).
    chirp : bool
        Also identify the table from a chirp.
    progress : bool
        Show a progress bar over simulated time on stderr (when it is a
        terminal) for each simulation.
    run_kwargs
        Passed to :func:`hybridtable.loop.simulation.run_loop`.

    Raises
    ------
    ParameterError
        See :func:`check_stewart_loop`; or the table cannot be tuned.
    WorkspaceError
        The loop commands the table out of its docking-axis workspace.
    """
    check_stewart_loop(params, stewart)
    params = stewart_loop_params(params)
    html_path = None if html is None else Path(html)
    if html_path is not None and html_path.exists():
        raise ParameterError(f"refusing to overwrite {html_path}")
    stewart = stewart_params_for_loop(params, stewart or StewartParams())
    if stewart.reference_response_hz is not None:
        # The tuning starts from the target anyway; a default reference model
        # could be above the Nyquist rate of a slow loop.
        stewart = replace(
            stewart,
            reference_response_hz=params.table_response_hz,
            reference_damping_ratio=max(params.table_damping_ratio, 1e-3),
        )
    with SimulatedTimeProgress(disable=None if progress else True):
        tuned, step = tune_table(stewart, params.table_response_hz, params.table_damping_ratio)
        chirp_response = (
            identify_chirp(
                tuned,
                stop_hz=min(CHIRP_STOP_HZ, 0.4 * params.sample_rate_hz),
                initial_guess=(step.response_frequency_hz, max(step.damping_ratio, 0.05)),
            )
            if chirp
            else None
        )
        loop, recorder = _build_logged_loop(params, tuned)
        t0 = time.perf_counter()
        result = run_loop(loop, **run_kwargs)
        wall = time.perf_counter() - t0
    motion = _motion(recorder, result, tuned)
    equivalent = params.with_(
        table_response_hz=step.response_frequency_hz, table_damping_ratio=step.damping_ratio
    )
    second_order_cor = simulate(equivalent).metrics.cor
    run = StewartRun(result, params, tuned, step, chirp_response, second_order_cor, wall, motion)
    if html_path is not None:
        run.write_html(html_path)
    return run


def _build_logged_loop(params: HybridLoopParams, stewart: StewartParams):
    """The Stewart loop with a recorder of the plate's pose at every step (no
    extra simulator step) and, inside a progress block, its progress ticker."""
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    loop = add_stewart_loop(builder, params, stewart)
    recorder = builder.AddNamedSystem("plate_pose_recorder", PoseRecorder())
    builder.Connect(loop.table.GetOutputPort("plate_pose"), recorder.get_input_port())
    add_progress_ticker(builder, "Stewart loop", _expected_loop_s(params))
    loop.diagram = builder.Build()
    loop.diagram.set_name("hybrid_loop_stewart")
    return loop, recorder


def _motion(
    recorder: PoseRecorder, result: SimulationResult, stewart: StewartParams
) -> StewartMotion:
    """The plate's recorded pose with the sensed force at the same times."""
    t, pose = recorder.samples()
    force = np.interp(t, result.time_s, result.f_act_n)
    return StewartMotion(
        time_s=t,
        plate_quaternion=pose[:, :4],
        plate_position_m=pose[:, 4:],
        force_n=force,
        home_position_m=np.asarray(stewart.geometry.home_pose[:3], dtype=float),
    )
