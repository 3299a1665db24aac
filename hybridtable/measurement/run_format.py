"""The ``hybridtable-run/1`` format of recorded rig runs: its columns, keys and objects.

A run is a CSV time series (:data:`RUN_COLUMNS`) and a JSON file of nominal
parameters (:data:`RUN_KEYS`) with the same stem; the format is described in
``docs/run-format.md``. A validated run is a :class:`Run` (the time series)
holding a :class:`RunInfo` (the parameters); the files are read and checked by
:mod:`hybridtable.measurement.run_reader`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "FORMAT",
    "RUN_COLUMNS",
    "RUN_KEYS",
    "SAMPLE_RATE_TOLERANCE",
    "RunInfo",
    "Run",
    "MIN_ROWS",
]


#: Value of the JSON ``format`` key.
FORMAT = "hybridtable-run/1"

#: CSV columns of the format, in the format's order, with their units.
RUN_COLUMNS: dict[str, str] = {
    "time_s": "s",
    "p_des_m": "m",
    "p_act_m": "m",
    "f_mea_n": "N",
    "f_comp_n": "N",
    "v_des_m_per_s": "m/s",
}

#: JSON keys of the format: name -> type, ``"number"`` or ``"string"``. A
#: number must lie in its plausible range (:data:`hybridtable.limits.LIMITS`,
#: under the same name).
RUN_KEYS: dict[str, str] = {
    "format": "string",
    "run_id": "string",
    "sample_rate_hz": "number",
    "spacecraft_mass_kg": "number",
    "contact_stiffness_n_per_m": "number",
    "sensor_delay_s": "number",
    "table_natural_frequency_hz": "number",
    "table_damping_ratio": "number",
    "compensator": "string",
    "lead_time_s": "number",
    "initial_gap_m": "number",
    "initial_velocity_m_per_s": "number",
    "force_deadband_n": "number",
}

#: Largest relative deviation of one time step from the sample period (and of
#: the period seen in ``time_s`` from ``1 / sample_rate_hz``) taken as timing
#: jitter or rounding rather than a defect.
SAMPLE_RATE_TOLERANCE = 0.01

#: Fewest rows a run may have (a time step needs two).
MIN_ROWS = 3


@dataclass(frozen=True)
class RunInfo:
    """The JSON part of a run: the nominal parameters the rig ran with (SI)."""

    run_id: str
    sample_rate_hz: float
    spacecraft_mass_kg: float
    contact_stiffness_n_per_m: float
    sensor_delay_s: float
    table_natural_frequency_hz: float
    table_damping_ratio: float
    compensator: str
    lead_time_s: float
    initial_gap_m: float
    initial_velocity_m_per_s: float
    force_deadband_n: float
    format: str = FORMAT
    #: Keys of the JSON file that the format does not define (kept, unused).
    extra: dict = field(default_factory=dict)

    @property
    def sample_period_s(self) -> float:
        """1 / sample_rate_hz."""
        return 1.0 / self.sample_rate_hz

    def to_dict(self) -> dict:
        """The format's keys and values."""
        return {name: getattr(self, name) for name in RUN_KEYS}


@dataclass
class Run:
    """One recorded run: its parameters and its time series (SI units).

    Row ``k`` holds tick ``k`` of the rig computer (see the format).
    """

    info: RunInfo
    time_s: np.ndarray
    p_des_m: np.ndarray
    p_act_m: np.ndarray
    f_mea_n: np.ndarray
    f_comp_n: np.ndarray
    v_des_m_per_s: np.ndarray
    csv_path: Path | None = None
    json_path: Path | None = None
    #: Which part of the files this run is, if not all of them (a contact
    #: event of a long log, :mod:`hybridtable.measurement.events`).
    part: str | None = None
    #: The log's columns that were not read (a rig's own log,
    #: :mod:`hybridtable.measurement.log_layout`).
    skipped_columns: tuple[str, ...] = ()

    @property
    def run_id(self) -> str:
        return self.info.run_id

    @property
    def n(self) -> int:
        """Number of ticks."""
        return len(self.time_s)

    @property
    def sample_period_s(self) -> float:
        return self.info.sample_period_s

    @property
    def duration_s(self) -> float:
        """Time of the last tick."""
        return float(self.time_s[-1])

    def columns(self) -> dict[str, np.ndarray]:
        """The time series by format column name."""
        return {name: getattr(self, name) for name in RUN_COLUMNS}

    def where(self, what: str) -> str:
        """A file name for messages about this run (``what`` = "csv" or "json")."""
        path = self.csv_path if what == "csv" else self.json_path
        where = str(path) if path is not None else f"run {self.run_id}"
        return where if self.part is None else f"{where} ({self.part})"
