"""Where the devices touch in a 6-DoF record: by the measured pose's
geometry, and the measured force from its level at rest.

The reader (:mod:`~hybridtable.six_dof.run6`: a record starts apart and holds
a contact) and the comparison (:mod:`~hybridtable.six_dof.compare6`: the
quiet ticks the noise is read from, the contact's phases) read the contact
the same way:

- :func:`touching`: the ticks the measured pose presses the devices together,
  the 1-D comparison's :func:`~hybridtable.measurement.phases.contact_mask` of
  the deepest penetration (a pad below the plate's face, the probe's head into
  the drogue's surface);
- :func:`force_from_rest`: each tick's measured force from its level before
  the first touch (the median of those ticks). An F/T sensor's offset (a tare
  that drifted, the ``force_bias`` effect) is its level at rest, not a
  contact.
"""

from __future__ import annotations

import numpy as np

from hybridtable.measurement.phases import contact_mask
from hybridtable.six_dof import drogue

__all__ = ["force_from_rest", "touching"]


def touching(contact, positions_m: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """The ticks the devices touch (bool, N) at the port's measured positions
    (N, 3; W, m) and attitudes (N, 3, 3; port frame to W) for ``contact`` (a
    :class:`~hybridtable.six_dof.devices.DockingContactParams`)."""
    if contact.is_cone:
        centres = positions_m + rotations @ contact.probe_centre_m
        depth = np.array([drogue.wall_depth_m(contact, x) for x in centres])
    else:
        pads = positions_m[:, 2:3] + np.einsum(
            "nj,ij->ni", rotations[:, 2, :], contact.pad_centres_m
        )
        depth = np.max(pads + contact.pad_radius_m, axis=1)
    return contact_mask(depth)


def force_from_rest(force_n: np.ndarray, touch: np.ndarray) -> np.ndarray:
    """The norm of each tick's measured force (N, 3; N) from its level at rest:
    the median of the ticks before the first touch of ``touch`` (every tick's
    if it starts touching or never touches)."""
    force_n = np.asarray(force_n, dtype=float)
    first = int(np.argmax(touch)) if np.any(touch) else len(force_n)
    rest = np.median(force_n[: first or len(force_n)], axis=0)
    return np.linalg.norm(force_n - rest, axis=1)
