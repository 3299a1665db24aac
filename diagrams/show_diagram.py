"""Write the hybrid loop's Drake diagram as Graphviz (render with `dot -Tpng`).

Usage: python diagrams/show_diagram.py [OUT.dot]
"""

import sys

from hybridtable import build_hybrid_loop
from hybridtable.studies.paper import table1_params

if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "hybrid_loop.dot"
    loop = build_hybrid_loop(table1_params("SDMDC"))
    with open(out, "x") as fh:  # never overwrite a user's file
        fh.write(loop.diagram.GetGraphvizString(max_depth=2))
    print(f"wrote {out}")
