"""Stability margins of the paper's Table 1 point, one line per compensator.

Usage: python analysis/table1_margins.py [--contact-damping-ratio Z] [--sample-rate-hz R]

The in-contact loop linearized by Drake (Pade delay, or the sampled-data model
of a rig computer at R Hz): predicted CoR, damping ratio, phase margin at the
contact crossover, effective delay, and the critical sensor delay and table
frequency. With an undamped contact (ratio 0) every compensator's critical
delay is 0: ``(1 + i w T) e^(-i w T)`` always lags, so only the energy growth
per contact tells them apart. Built only from library calls.
"""

import argparse

from hybridtable.analysis import (
    critical_sensor_delay,
    critical_table_frequency,
    growth_of,
    loop_margins,
)
from hybridtable.analysis.sweep import model_function
from hybridtable.compensators import COMPENSATORS
from hybridtable.studies.paper import table1_params


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--contact-damping-ratio", type=float, default=0.05, help="default 0.05")
    ap.add_argument("--sample-rate-hz", type=float, default=None, help="default: continuous")
    args = ap.parse_args()
    print(
        f"{'compensator':<12} {'CoR':>8} {'zeta':>8} {'PM [deg]':>9} {'tau_eff [ms]':>13}"
        f" {'T_crit [ms]':>12} {'f_crit [Hz]':>12}"
    )
    for name in COMPENSATORS:
        p = table1_params(name, sample_rate_hz=args.sample_rate_hz).with_contact_damping_ratio(
            args.contact_damping_ratio
        )
        model, _ = model_function(p)
        m = loop_margins(model(p))
        growth = growth_of(model)
        t_crit = critical_sensor_delay(growth, p)
        f_crit = critical_table_frequency(growth, p)
        print(
            f"{name:<12} {m.predicted_cor:8.5f} {m.damping_ratio:8.4f} {m.phase_margin_deg:9.2f}"
            f" {1e3 * m.effective_delay_s:13.3f} {1e3 * t_crit:12.3f} {f_crit:12.2f}"
        )


if __name__ == "__main__":
    main()
