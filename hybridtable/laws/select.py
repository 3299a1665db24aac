"""A branch on a signal, written once for every scalar type a law runs on.

A law that switches (a contact that never pulls, a compensator gated by the
measured force) cannot use Python's ``if`` on a ``pydrake.symbolic`` value:
``x > 0`` is then a ``Formula``, not a ``bool``. :func:`select` is ``if`` for
numbers (``float``, ``AutoDiffXd``, numpy scalars: the comparison is a
``bool`` and only that branch is returned) and ``if_then_else`` for
expressions, so one definition of a law compiles into a Drake system and runs
as plain Python alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["select", "both"]


def _is_formula(x: Any) -> bool:
    return type(x).__name__ == "Formula"


def both(a: Any, b: Any) -> Any:
    """``a and b`` for ``bool`` conditions, ``logical_and`` for formulas."""
    if isinstance(a, bool | np.bool_) and isinstance(b, bool | np.bool_):
        return bool(a and b)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.logical_and(a, b)
    if _is_formula(a) or _is_formula(b):
        from pydrake.symbolic import logical_and

        return logical_and(a, b)
    return bool(a) and bool(b)


def select(condition: Any, then: Any, otherwise: Any) -> Any:
    """``then`` where ``condition`` holds, else ``otherwise``.

    Parameters
    ----------
    condition : bool, numpy bool or boolean array, or pydrake.symbolic.Formula
    then, otherwise : float, AutoDiffXd, ndarray or pydrake.symbolic.Expression
        (with a ``Formula``: scalar expressions; ``if_then_else`` takes no arrays)
    """
    if condition is True:  # the numbers' path first: it is the hot one
        return then
    if condition is False:
        return otherwise
    if isinstance(condition, np.bool_) or (
        isinstance(condition, np.ndarray) and condition.ndim == 0
    ):
        return then if bool(condition) else otherwise
    if isinstance(condition, np.ndarray):  # elementwise over arrays of samples
        return np.where(condition, then, otherwise)
    if _is_formula(condition):
        from pydrake.symbolic import if_then_else

        return if_then_else(condition, then, otherwise)
    return then if condition else otherwise
