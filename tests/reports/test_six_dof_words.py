"""simulate6's line on the modes linearized in contact names the mode that grows,
not a decaying one, even when it is not among the slowest it lists."""

from __future__ import annotations

import math
from types import SimpleNamespace

from hybridtable.reports.six_dof import format_docking
from hybridtable.six_dof.linear import ContactModes

METRICS = SimpleNamespace(
    cor_normal=1.0,
    energy_ratio=1.0,
    peak_force_n=1000.0,
    peak_moment_n_m=0.0,
    contact_duration_s=0.5,
    rotational_energy_j=0.0,
    lateral_velocity_m_per_s=0.0,
    captured=False,
)


def _modes(growth: tuple[float, ...], critical_delay_s: float = 0.004) -> ContactModes:
    return ContactModes(
        frequencies_hz=(1.0, 1.4, 1.7, 40.0),
        growth_rates_per_s=growth,
        damping_ratios=tuple(-g / (2 * math.pi) for g in growth),
        max_growth_rate_per_s=max(growth),
        stable=max(growth) <= 0.0,
        critical_delay_s=critical_delay_s,
        spectral_radius=1.0,
    )


def _modes_line(modes: ContactModes) -> str:
    text = format_docking("SDMDC", METRICS, None, modes, 1.0, 1.0)
    return next(line for line in text.splitlines() if line.startswith("linearized in contact"))


def test_the_growing_mode_is_named_when_it_is_not_among_the_slowest():
    line = _modes_line(_modes((-0.5, -0.2, -0.1, 3.25)))
    assert "a mode grows: 40.000 Hz at +3.2500/s, the fastest-growing" in line
    assert "slowest modes 1.000 Hz (-0.5000/s), 1.400 Hz (-0.2000/s), 1.700 Hz" in line
    assert "growth starts at a sensor delay of 4 ms" in line


def test_the_fastest_growing_of_two_growing_modes_is_named():
    line = _modes_line(_modes((0.0002, -0.2, 0.5, -1.0)))
    assert "a mode grows: 1.700 Hz at +0.5000/s" in line


def test_a_stable_loop_says_stable_and_no_critical_delay_up_to_the_scan():
    line = _modes_line(_modes((-0.5, -0.2, -0.1, -3.0), critical_delay_s=math.inf))
    assert line.startswith("linearized in contact: stable;")
    assert "none up to 50 ms" in line and "grows" not in line
