"""The paper's 3-3 Stewart platform as a Drake MultibodyPlant back-end of the hybrid loop.

- :mod:`~hybridtable.stewart.geometry`: geometry, inverse / forward kinematics, workspace;
- :mod:`~hybridtable.stewart.params`: the back-end's parameters, servo gains, reference model;
- :mod:`~hybridtable.stewart.hunt_crossley`: Hunt–Crossley dissipation from a viscous damping;
- :mod:`~hybridtable.stewart.plant`: the MultibodyPlant (legs, plate, F/T sensor, contact);
- :mod:`~hybridtable.stewart.backend`: the table + contact back-end of the loop;
- :mod:`~hybridtable.stewart.identify`: second-order identification and tuning.
"""

from hybridtable.errors import WorkspaceError
from hybridtable.stewart.geometry import StewartGeometry
from hybridtable.stewart.params import StewartParams

__all__ = ["StewartGeometry", "StewartParams", "WorkspaceError"]
