"""The resonant table: unit static gain and its structural mode."""

from __future__ import annotations

import math

import numpy as np

from hybridtable.systems.resonant_table import StructuralModeParams, resonant_table_matrices
from hybridtable.systems.table import TableParams


def test_resonant_table_has_unit_static_gain_and_its_mode():
    A, B, C, D = resonant_table_matrices(TableParams(30.0, 0.7), StructuralModeParams(80.0, 0.05))
    x = -np.linalg.solve(A, B @ [1.0, 0.0])  # static response to a unit command
    np.testing.assert_allclose((C @ x + D @ [1.0, 0.0])[:2], [1.0, 0.0], atol=1e-12)
    w = 2 * math.pi * 80.0
    eig = np.linalg.eigvals(A)
    assert np.min(np.abs(eig - complex(-0.05 * w, w * math.sqrt(1 - 0.05**2)))) < 1e-6 * w
