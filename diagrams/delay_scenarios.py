"""The paper's Figs. 3-5 scenarios, uncompensated: sensor delay 1/3/5 ms with an
ideal table, table response 100/50/25 Hz with no delay, and both together.

Usage: python diagrams/delay_scenarios.py
"""

import math

from hybridtable import simulate
from hybridtable.studies.paper import cor_estimate, paper_params

SCENARIOS = {
    "Fig. 3, T_fms 1 ms": dict(sensor_delay_s=0.001, table_response_hz=math.inf),
    "Fig. 3, T_fms 3 ms": dict(sensor_delay_s=0.003, table_response_hz=math.inf),
    "Fig. 3, T_fms 5 ms": dict(sensor_delay_s=0.005, table_response_hz=math.inf),
    "Fig. 4, f_resp 100 Hz": dict(sensor_delay_s=0.0, table_response_hz=100.0),
    "Fig. 4, f_resp 50 Hz": dict(sensor_delay_s=0.0, table_response_hz=50.0),
    "Fig. 4, f_resp 25 Hz": dict(sensor_delay_s=0.0, table_response_hz=25.0),
    "Fig. 5, 5 ms + 25 Hz": dict(sensor_delay_s=0.005, table_response_hz=25.0),
}

if __name__ == "__main__":
    for label, kwargs in SCENARIOS.items():
        p = paper_params(**kwargs)
        cor = simulate(p).metrics.cor
        print(f"{label:24s} CoR {cor:.5f}  estimate exp(pi^2 f_con tau_eff) {cor_estimate(p):.5f}")
