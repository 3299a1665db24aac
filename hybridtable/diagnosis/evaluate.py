"""Evaluation of a candidate model on the runs: replay and closed-loop residuals,
prewhitened with each run's noise model (:class:`Evaluator`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from hybridtable.diagnosis.settings import (
    CHANNELS,
    CLOSED_LOOP_FLOOR,
    FAILED_RESIDUAL,
    FIT_ACCURACY,
    NUMERICAL_FLOOR,
)
from hybridtable.effects.spec import ModelSpec, RigScale
from hybridtable.errors import MeasurementError, SimulationError
from hybridtable.measurement.noise_model import NoiseModel, run_noise, whiten
from hybridtable.measurement.phases import delayed_labels, phase_labels, settle_ticks
from hybridtable.measurement.replay import replay
from hybridtable.measurement.rig import rig_params, simulate_rig
from hybridtable.measurement.run_format import Run
from hybridtable.systems.blocks import RecordedOffset, chain_output

__all__ = [
    "RunData",
    "prepare_runs",
    "Evaluation",
    "Evaluator",
]


# -- data ----------------------------------------------------------------------
@dataclass
class RunData:
    """A run with what diagnose needs of it."""

    run: Run
    delay_ticks: int
    labels: np.ndarray
    f_labels: np.ndarray
    noise: dict[str, NoiseModel]
    notes: list[str] = field(default_factory=list)
    #: Numerical resolution of each channel (:data:`NUMERICAL_FLOOR`).
    floors: dict[str, float] = field(default_factory=dict)

    @property
    def run_id(self) -> str:
        return self.run.run_id


def prepare_runs(runs: Sequence[Run]) -> list[RunData]:
    """Check the runs and estimate their noise.

    Raises
    ------
    MeasurementError
        If a run makes no model (its JSON), holds no contact, has too few
        no-contact ticks to estimate the force noise, or if the runs are of
        rigs with other sample rates.
    """
    if not runs:
        raise MeasurementError("no runs to diagnose")
    rates = {r.info.sample_rate_hz for r in runs}
    if len(rates) > 1:
        raise MeasurementError(
            "runs of different sample rates "
            f"({', '.join(f'{x:g}' for x in sorted(rates))} Hz): diagnose one rig at a time"
        )
    out = []
    for run in runs:
        params = rig_params(run.info, run.where("json"))
        try:
            labels = phase_labels(run.p_act_m)
        except ValueError as err:
            raise MeasurementError(f"{run.where('csv')}: {err}") from None
        m = round(params.sensor_delay_s / run.sample_period_s)  # to the nearest tick
        table = params.plant.table
        h = run.sample_period_s
        settle = max(2, settle_ticks(table.settling_time_s, h, run.n))
        noise, notes = run_noise(run, m, settle)
        if "f_mea_n" not in noise:
            raise MeasurementError(
                f"{run.where('csv')}: fewer than 20 ticks without contact; "
                "cannot estimate the force noise"
            )
        floors = {
            "f_mea_n": NUMERICAL_FLOOR * max(float(np.abs(run.f_mea_n).max()), 1.0),
            "p_act_m": NUMERICAL_FLOOR * max(float(np.ptp(run.p_act_m)), 1e-6),
        }
        for c, floor in floors.items():
            if not noise[c].sigma > floor:
                noise[c] = NoiseModel(floor, 0.0, noise[c].samples)
                notes.append(f"{c}: no noise found; its floor is set to {floor:.3g}")
        out.append(RunData(run, m, labels, delayed_labels(labels, m), noise, notes, floors))
    return out


# -- evaluation of a model -----------------------------------------------------
@dataclass
class Evaluation:
    """A model's predictions and residuals on one run (replay channels, or
    the closed loop's ``v_des``)."""

    prediction: dict[str, np.ndarray]
    residual: dict[str, np.ndarray]
    whitened: dict[str, np.ndarray]
    failed: bool = False
    #: Smallest variance of a channel's whitened residual credited to a
    #: model: the numerical resolution (negligible against any real noise).
    floor: dict[str, float] = field(default_factory=dict)

    def rss(self) -> dict[str, float]:
        return {c: float(w @ w) for c, w in self.whitened.items()}


class Evaluator:
    """Predicts runs with a :class:`~hybridtable.effects.effect.ModelSpec`.

    ``stage="replay"``: the replay's ``f_mea`` and ``p_act``, whitened with
    the runs' noise. ``stage="closed_loop"``: the closed loop's ``v_des``,
    whitened by first differences (the velocity integrates the force) and
    an AR(1) model of that (:attr:`closed_loop_noise`).
    """

    def __init__(
        self,
        data: Sequence[RunData],
        scale: RigScale,
        accuracy: float = FIT_ACCURACY,
    ) -> None:
        self.data = list(data)
        self.scale = scale
        self.accuracy = accuracy
        #: Force-reading noise added to the closed loop's sensor, per run
        #: (:meth:`inject_noise`).
        self.injected_noise: list[np.ndarray | None] = [None] * len(self.data)
        #: Noise of the closed loop's differenced v_des residual, per run
        #: (:meth:`calibrate_closed_loop`).
        self.closed_loop_noise: list[NoiseModel] = [NoiseModel(1.0, 0.0, 0)] * len(self.data)
        #: What each run's computer used where its JSON differs (run_id ->
        #: :data:`~hybridtable.measurement.rig.COMPUTER_PARAMS` values, from an
        #: audit): the closed loop's computer does the same.
        self.computer: dict[str, dict] = {}
        self.simulations = 0

    def evaluate(self, spec: ModelSpec, i: int, stage: str = "replay") -> Evaluation:
        d = self.data[i]
        run = d.run
        self.simulations += 1
        physics = spec.physics()
        if stage == "replay":
            try:
                rep = replay(run, physics, accuracy=self.accuracy)
                pred = {
                    "f_mea_n": rep.f_mea_n,
                    "p_act_m": rep.p_act_m,
                    "f_act_n": rep.f_act_n,
                }
            except SimulationError:
                return self._failed(i, stage)
            res = {c: getattr(run, c) - pred[c] for c in CHANNELS}
            white = {c: whiten(res[c], d.noise[c]) for c in CHANNELS}
            floor = {c: (d.floors.get(c, 0.0) / d.noise[c].innovation_sigma) ** 2 for c in CHANNELS}
            return Evaluation(pred, res, white, floor=floor)
        noise = self.injected_noise[i]
        if noise is not None:
            h = run.sample_period_s
            physics = spec.wrap(
                "sensor",
                lambda p, sensor: chain_output(sensor, RecordedOffset(h, noise), "measured_force"),
            ).physics()
        if self.computer.get(run.run_id):
            physics = replace(physics, computer=self.computer[run.run_id])
        try:
            cl = simulate_rig(spec.closed_loop_run(run), physics, accuracy=self.accuracy)
        except SimulationError:
            return self._failed(i, stage)
        v = cl.v_des_m_per_s
        res = {"v_des_m_per_s": run.v_des_m_per_s - v}
        noise = self.closed_loop_noise[i]
        w = whiten(np.diff(res["v_des_m_per_s"], prepend=0.0), noise)
        floor = (self._closed_loop_floor(i) / noise.innovation_sigma) ** 2
        return Evaluation(
            {"v_des_m_per_s": v, "f_comp_n": cl.f_comp_n},
            res,
            {"v_des_m_per_s": w},
            floor={"v_des_m_per_s": floor},
        )

    def _closed_loop_floor(self, i: int) -> float:
        """Below a thousandth of the force noise (:data:`CLOSED_LOOP_FLOOR`),
        velocity errors per tick are numerical (integration, rounding)."""
        run = self.data[i].run
        sigma_f = self.data[i].noise["f_mea_n"].sigma
        return CLOSED_LOOP_FLOOR * sigma_f * run.sample_period_s / run.info.spacecraft_mass_kg

    def inject_noise(self, replay_base: Mapping[int, Evaluation]) -> None:
        """Feed the closed loop's compensator the noise the rig's computer
        read: the ``f_mea`` residual of a replay model (the record's reading
        minus the model's). With the command of the record, the closed loop
        then reproduces the record's reading whatever the error of the
        physics model, so the closed loop tests the computer's side (e.g.
        the spacecraft mass) alone; the table position's noise, which the
        MDC reads, is not injected."""
        for i, ev in replay_base.items():
            self.injected_noise[i] = np.asarray(ev.residual["f_mea_n"], dtype=float).copy()

    def calibrate_closed_loop(self, base: Mapping[int, Evaluation]) -> None:
        """Fix the closed loop's whitening from a base model's residuals: an
        AR(1) model of the differenced ``v_des`` residual of each run (the
        velocity integrates the compensated force, whose noise the rig's
        sensors colour)."""
        for i, ev in base.items():
            d = np.diff(ev.residual["v_des_m_per_s"], prepend=0.0)
            floor = self._closed_loop_floor(i)
            s0 = float(d @ d)
            sigma = math.sqrt(s0 / len(d))
            if sigma <= floor:
                self.closed_loop_noise[i] = NoiseModel(floor, 0.0, len(d))
                continue
            phi = float(np.clip(float(d[1:] @ d[:-1]) / s0, -0.95, 0.95))
            self.closed_loop_noise[i] = NoiseModel(sigma, phi, len(d))

    def _failed(self, i: int, stage: str) -> Evaluation:
        n = self.data[i].run.n
        chans = CHANNELS if stage == "replay" else {"v_des_m_per_s": "m/s"}
        big = np.full(n, FAILED_RESIDUAL)
        return Evaluation(
            {c: np.full(n, np.nan) for c in chans},
            {c: big for c in chans},
            {c: big for c in chans},
            failed=True,
        )
