"""The Table 1 scenario on a rig whose computer runs at a sample rate
(zero-order-held command, sampled sensor, semi-implicit Euler spacecraft),
against the continuous loop.

Usage: python diagrams/sampled_rig.py [RATE_HZ ...]
"""

import sys

from hybridtable import COMPENSATORS, simulate
from hybridtable.studies.paper import table1_params

if __name__ == "__main__":
    rates = [float(a) for a in sys.argv[1:]] or [1000.0, 5000.0]
    for name in COMPENSATORS:
        cont = simulate(table1_params(name)).metrics.cor
        sampled = [simulate(table1_params(name, sample_rate_hz=r)).metrics.cor for r in rates]
        cells = "  ".join(f"{r:g} Hz: {c:.5f}" for r, c in zip(rates, sampled, strict=True))
        print(f"{name:6s} continuous {cont:.5f}  {cells}")
