"""The physically plausible range of every parameter and recorded channel, SI
units, and the default operating point (:data:`TABLE1_DEFAULTS`).

One table (:data:`LIMITS`) read by everything that takes a number from a user:
the parameter dataclasses (:class:`~hybridtable.loop.params.HybridLoopParams`),
the run reader (the JSON keys of ``hybridtable-run/1``), the record's channel
checks, and the command-line flags (their ``--help`` prints the range). A
value outside its range is refused with one line naming the field, the value
and the range, e.g. ``spacecraft_mass_kg = 1e-06 kg is outside its plausible
range 0.001 to 1e+07 kg``, never handed to a simulation that would run
forever or return nonsense.

The ranges are wide: every rig and docking test we know of lies well inside
them (spacecraft from a 1 kg test article to a 420 t station, contacts from a
soft bumper to a steel probe, tables from 0.1 Hz to 10 kHz). A value inside its
range may still make one particular simulation too stiff or too long; the
simulation budget (:mod:`hybridtable.loop.budget`) refuses that case with its
own message.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from hybridtable.errors import ParameterError

__all__ = ["Limit", "LIMITS", "TABLE1_DEFAULTS", "limit_of", "check_plausible", "limit_words"]


@dataclass(frozen=True)
class Limit:
    """The plausible range ``[low, high]`` of one quantity (both ends included).

    ``ideal_inf``: ``math.inf`` is accepted too, as an ideal element (an ideal
    table has an infinite response frequency). ``smallest_nonzero``: with
    ``low == 0``, the values between 0 and it are refused (a delay of 1e-300 s
    is no delay a model can hold: give 0).
    """

    low: float
    high: float
    unit: str
    ideal_inf: bool = False
    smallest_nonzero: float | None = None

    def contains(self, value: float) -> bool:
        """True if ``value`` lies in the range (``inf`` where ideal)."""
        if self.ideal_inf and value == math.inf:
            return True
        if self.smallest_nonzero is not None and 0.0 < abs(value) < self.smallest_nonzero:
            return False
        return math.isfinite(value) and self.low <= value <= self.high

    def words(self, unit: bool = True) -> str:
        """The range in words: ``"0.001 to 1e+07 kg"``, ``"0.1 to 1e+04 Hz, or inf"``
        (without the unit if ``unit`` is false)."""
        unit = "" if self.unit == "1" or not unit else f" {self.unit}"
        if self.smallest_nonzero is not None:
            text = f"0, or {self.smallest_nonzero:g} to {self.high:g}{unit}"
        else:
            text = f"{self.low:g} to {self.high:g}{unit}"
        return text + (", or inf" if self.ideal_inf else "")


#: name -> its plausible range. Parameter names are the dataclass fields and
#: JSON keys; channel names the run format's columns.
LIMITS: dict[str, Limit] = {
    # the spacecraft and the contact
    "spacecraft_mass_kg": Limit(1e-3, 1e7, "kg"),
    "contact_stiffness_n_per_m": Limit(1.0, 1e10, "N/m"),
    "contact_damping_n_s_per_m": Limit(0.0, 1e8, "N s/m"),
    "contact_damping_ratio": Limit(0.0, 10.0, "1"),
    "contact_frequency_hz": Limit(1e-3, 1e4, "Hz"),
    "initial_velocity_m_per_s": Limit(1e-4, 10.0, "m/s"),
    "initial_gap_m": Limit(0.0, 10.0, "m"),
    # the table and the sensor
    "table_response_hz": Limit(0.1, 1e4, "Hz", ideal_inf=True),
    "table_natural_frequency_hz": Limit(0.1, 1e4, "Hz"),
    "table_damping_ratio": Limit(0.0, 10.0, "1"),
    "sensor_delay_s": Limit(0.0, 1.0, "s", smallest_nonzero=1e-6),
    # the rig computer and its compensator
    "sample_rate_hz": Limit(1.0, 1e6, "Hz"),
    "lead_time_s": Limit(0.0, 1.0, "s", smallest_nonzero=1e-6),
    "compensator_stiffness_n_per_m": Limit(1.0, 1e10, "N/m"),
    "compensator_damping_n_s_per_m": Limit(0.0, 1e8, "N s/m"),
    "force_deadband_n": Limit(0.0, 1e6, "N"),
    "compensator_stiffness_ratio": Limit(1e-3, 1e3, "1"),
    # what the rig computer reads: noise standard deviations
    "force_noise_n": Limit(0.0, 1e6, "N"),
    "position_noise_m": Limit(0.0, 1.0, "m"),
    # the continuous model's integration step
    "time_step_s": Limit(1e-9, 1.0, "s"),
    # recorded channels (hybridtable-run/1): a docking axis of at most tens of
    # metres, forces below a giganewton, speeds below a kilometre per second
    "p_des_m": Limit(-100.0, 100.0, "m"),
    "p_act_m": Limit(-100.0, 100.0, "m"),
    "f_mea_n": Limit(-1e9, 1e9, "N"),
    "f_comp_n": Limit(-1e9, 1e9, "N"),
    "v_des_m_per_s": Limit(-1e3, 1e3, "m/s"),
}


#: The value of a loop quantity a user leaves out: the seed paper's Table 1
#: operating point (Sec. III.A), stated once for the paper's studies, the
#: command-line defaults, a sweep's base, and a CoR table's unstated conditions.
TABLE1_DEFAULTS: dict[str, float] = {
    "contact_stiffness_n_per_m": 1e5,
    "contact_frequency_hz": 1.0,
    "initial_velocity_m_per_s": 0.1,
    "table_response_hz": 25.0,
    "table_damping_ratio": 0.8,
    "sensor_delay_s": 0.005,
}


def limit_of(name: str) -> Limit:
    """The :class:`Limit` of ``name`` (``KeyError`` names the known ones)."""
    try:
        return LIMITS[name]
    except KeyError:
        raise KeyError(f"no plausible range for {name!r} (known: {', '.join(LIMITS)})") from None


def limit_words(name: str) -> str:
    """The range of ``name`` in words (:meth:`Limit.words`)."""
    return limit_of(name).words()


def check_plausible(name: str, value: float, where: str | None = None) -> float:
    """Return ``value`` as a float if it lies in the plausible range of ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`LIMITS`.
    value : float
        The value to check.
    where : str, optional
        What holds the value (a file and key), put before the message.

    Raises
    ------
    ParameterError
        For a value that is not a number, NaN, or outside the range, in one
        line naming ``name``, the value and the range.
    """
    limit = limit_of(name)
    prefix = f"{where}: " if where else ""
    if isinstance(value, bool):
        raise ParameterError(f"{prefix}{name} must be a number (got {value!r})")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{prefix}{name} must be a number (got {value!r})") from None
    if not limit.contains(x):
        unit = "" if limit.unit == "1" else f" {limit.unit}"
        raise ParameterError(
            f"{prefix}{name} = {x:g}{unit} is outside its plausible range {limit.words()}"
        )
    return x
