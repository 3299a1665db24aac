"""The paper's Table 1 scenario: the four compensators at k 1e5 N/m, f_con 1 Hz,
25 Hz table (zeta 0.8), 5 ms sensor delay, 0.1 m/s approach.

Usage: python diagrams/table1_compensators.py
"""

from hybridtable import COMPENSATORS, simulate
from hybridtable.studies.paper import load_tables, table1_params

if __name__ == "__main__":
    paper = load_tables()["table1_simulation"]["cor"]
    for name in COMPENSATORS:
        m = simulate(table1_params(name)).metrics
        print(f"{name:6s} CoR {m.cor:.5f} (paper {paper[name]:.4f})  peak {m.peak_force_n:7.1f} N")
