"""One run of the hybrid loop with the Stewart back-end (what ``simulate --table stewart`` does)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

from hybridtable.errors import ParameterError
from hybridtable.loop.params import HybridLoopParams
from hybridtable.loop.simulation import SimulationResult, run_loop, simulate
from hybridtable.stewart.backend import (
    build_stewart_loop,
    stewart_params_for_loop,
    write_meshcat_html,
)
from hybridtable.stewart.identify import TableResponse, identify_chirp, tune_table
from hybridtable.stewart.params import StewartParams

__all__ = ["DEFAULT_SAMPLE_RATE_HZ", "StewartRun", "stewart_loop_params", "simulate_stewart"]

#: Rig-computer rate used when a run asks for the continuous loop: the plant
#: is discrete, every discrete part then shares its period.
DEFAULT_SAMPLE_RATE_HZ = 1000.0


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
    """

    result: SimulationResult
    params: HybridLoopParams
    stewart: StewartParams
    step: TableResponse
    chirp: TableResponse | None
    second_order_cor: float
    wall_time_s: float

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


def stewart_loop_params(params: HybridLoopParams) -> HybridLoopParams:
    """``params`` as the Stewart loop runs them: sampled (at
    :data:`DEFAULT_SAMPLE_RATE_HZ` if they ask for a continuous loop)."""
    if params.sample_rate_hz is None:
        return params.with_(sample_rate_hz=DEFAULT_SAMPLE_RATE_HZ)
    return params


def simulate_stewart(
    params: HybridLoopParams,
    stewart: StewartParams | None = None,
    html: str | Path | None = None,
    chirp: bool = True,
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
        Record a Meshcat animation of the run to this self-contained HTML
        file (must not exist).
    chirp : bool
        Also identify the table from a chirp.
    run_kwargs
        Passed to :func:`hybridtable.loop.simulation.run_loop`.
    """
    params = stewart_loop_params(params)
    if math.isinf(params.table_response_hz):
        raise ParameterError(
            "the Stewart table has a finite response: give a finite table_response_hz"
        )
    html_path = None if html is None else Path(html)
    if html_path is not None and html_path.exists():
        raise ParameterError(f"refusing to overwrite {html_path}")
    if html_path is not None and not html_path.parent.is_dir():
        raise ParameterError(f"no directory {html_path.parent} for {html_path}")
    stewart = stewart_params_for_loop(params, stewart or StewartParams())
    tuned, step = tune_table(stewart, params.table_response_hz, params.table_damping_ratio)
    chirp_response = (
        identify_chirp(
            tuned, initial_guess=(step.response_frequency_hz, max(step.damping_ratio, 0.05))
        )
        if chirp
        else None
    )
    meshcat = None
    if html_path is not None:
        from pydrake.geometry import Meshcat, MeshcatParams

        meshcat = Meshcat(MeshcatParams(port=None))
        meshcat.StartRecording(set_visualizations_while_recording=False)
    loop = build_stewart_loop(params, tuned, meshcat=meshcat)
    t0 = time.perf_counter()
    result = run_loop(loop, **run_kwargs)
    wall = time.perf_counter() - t0
    if meshcat is not None:
        write_meshcat_html(meshcat, html_path)
    equivalent = params.with_(
        table_response_hz=step.response_frequency_hz, table_damping_ratio=step.damping_ratio
    )
    second_order_cor = simulate(equivalent).metrics.cor
    return StewartRun(result, params, tuned, step, chirp_response, second_order_cor, wall)
