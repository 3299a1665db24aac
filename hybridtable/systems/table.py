"""The motion table's response: a linear second-order model (paper, Sec. II).

``p_act'' = w^2 (p_des - p_act) - 2 zeta w p_act'`` with ``w = 2 pi f_resp``.
An infinite response frequency gives the ideal table, ``p_act = p_des``.

The table is one of the two swappable back-ends of the hybrid loop. Any back-end
has the same ports: input ``commanded_state`` (2) and output ``motion`` (3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LinearSystem, MatrixGain

from hybridtable._components import Block, Component
from hybridtable._validation import check_nonnegative, check_positive_or_inf
from hybridtable.laws.compiled import compiled_available, njit_cached
from hybridtable.laws.table import held_tick, second_order_matrices

__all__ = [
    "TableParams",
    "SecondOrderTable",
    "SampledTable",
    "table_matrices",
    "table_step_response",
]


@dataclass(frozen=True)
class TableParams:
    """Parameters of the second-order table model.

    Parameters
    ----------
    response_frequency_hz : float
        Undamped natural frequency f_resp of the table, > 0; ``math.inf`` for
        an ideal table that follows its command exactly.
    damping_ratio : float
        Damping ratio zeta_resp, >= 0.
    """

    response_frequency_hz: float = 25.0
    damping_ratio: float = 0.8

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "response_frequency_hz",
            check_positive_or_inf("response_frequency_hz", self.response_frequency_hz),
        )
        object.__setattr__(
            self, "damping_ratio", check_nonnegative("damping_ratio", self.damping_ratio)
        )

    @property
    def is_ideal(self) -> bool:
        """True for an infinitely fast table."""
        return math.isinf(self.response_frequency_hz)

    @property
    def omega_rad_per_s(self) -> float:
        """Undamped natural frequency in rad/s."""
        return 2.0 * math.pi * self.response_frequency_hz

    @property
    def settling_time_s(self) -> float:
        """Five time constants of the decay envelope, ``5 / (zeta omega)`` [s]: 0 for
        an ideal table, ``inf`` for an undamped one (it never settles)."""
        if self.is_ideal:
            return 0.0
        decay = self.damping_ratio * self.omega_rad_per_s
        return 5.0 / decay if decay > 0.0 else math.inf

    @property
    def ramp_lag_s(self) -> float:
        """Steady-state lag of the table behind a ramp command, 2 zeta / omega."""
        return 0.0 if self.is_ideal else 2.0 * self.damping_ratio / self.omega_rad_per_s


def table_matrices(params: TableParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space (A, B, C, D) of the table; state ``[p_act, v_act]``.

    Input ``[p_des, v_des]`` (only ``p_des`` drives a second-order table);
    output ``[p_act, v_act, a_act]``.
    """
    if params.is_ideal:
        raise ValueError("an ideal table has no state")
    A, b = second_order_matrices(params.response_frequency_hz, params.damping_ratio)
    B = np.hstack([b, np.zeros((2, 1))])
    C = np.vstack([np.eye(2), A[1]])
    D = np.vstack([np.zeros((2, 2)), B[1]])
    return A, B, C, D


def table_step_response(params: TableParams, t_s: np.ndarray) -> np.ndarray:
    """Closed-form unit-step response p_act(t) of the table, from rest at 0."""
    t = np.asarray(t_s, dtype=float)
    if params.is_ideal:
        return np.ones_like(t)
    w = params.omega_rad_per_s
    z = params.damping_ratio
    if z < 1.0:
        wd = w * math.sqrt(1.0 - z * z)
        return 1.0 - np.exp(-z * w * t) * (np.cos(wd * t) + z * w / wd * np.sin(wd * t))
    if z == 1.0:
        return 1.0 - np.exp(-w * t) * (1.0 + w * t)
    r = math.sqrt(z * z - 1.0)
    s1, s2 = -w * (z - r), -w * (z + r)
    return 1.0 + (s2 * np.exp(s1 * t) - s1 * np.exp(s2 * t)) / (s1 - s2)


class SecondOrderTable(Component):
    """The table response model as a Drake system (a ``LinearSystem`` inside).

    Ports
    -----
    Input ``commanded_state`` (size 2: m, m/s)
        ``[p_des, v_des]`` from the spacecraft model. The second-order model
        follows ``p_des`` only; the ideal table follows both.
    Output ``motion`` (size 3: m, m/s, m/s^2)
        ``[p_act, v_act, a_act]`` of the table (the active contact device).
        An ideal table reports ``a_act = 0``: its true acceleration is the
        spacecraft's, which would close an algebraic loop; only the force rate
        of a damped contact uses it.

    The state of a second-order table is ``[p_act, v_act]``.
    """

    def __init__(self, params: TableParams) -> None:
        Component.__init__(self)
        self.params = params
        self._build("ideal_table" if params.is_ideal else "second_order_table")

    def _add(self, builder: DiagramBuilder, name: str) -> Block:
        if self.params.is_ideal:
            inner = builder.AddNamedSystem(
                name, MatrixGain(np.vstack([np.eye(2), np.zeros((1, 2))]))
            )
        else:
            inner = builder.AddNamedSystem(name, LinearSystem(*table_matrices(self.params)))
        return Block(
            self,
            {"commanded_state": [inner.get_input_port()]},
            {"motion": inner.get_output_port()},
            None if self.params.is_ideal else inner,
        )

    def sampled(self, period_s: float) -> SampledTable | None:
        """This table at the ticks of a held command (:class:`SampledTable`);
        None for the ideal table (no state to discretize)."""
        if self.params.is_ideal:
            return None
        return SampledTable(table_matrices(self.params), period_s)

    def _write_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        context.SetContinuousState(np.array([position_m, velocity_m_per_s]))

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Set ``[p_act, v_act]`` (no-op for the ideal table)."""
        Component.set_initial_state(self, context, position_m, velocity_m_per_s)


def _ordered_dot(row: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``X @ row`` with the products summed in index order (as Eigen does for a
    small matrix), elementwise over the rows of ``X``."""
    total = row[0] * X[:, 0]
    for j in range(1, len(row)):
        total = total + row[j] * X[:, j]
    return total


def _held_states(A, B, x0, U, X) -> None:
    """``X[k] = x[k]`` for ``x[k+1] = A x[k] + B U[k]`` from ``x0``: each row's
    products summed in index order, ``A x`` and ``B u`` added last (as Eigen
    does). Written once for both runners: plain Python on lists, and the same
    function compiled by numba on arrays (no ``fastmath``: the same operations
    in the same order, so the two agree bit for bit)."""
    n = len(A)
    m = len(B[0])
    x = [x0[i] for i in range(n)]
    y = [0.0] * n
    for k in range(len(U)):
        u = U[k]
        for i in range(n):
            X[k][i] = x[i]
        for i in range(n):
            a = A[i]
            b = B[i]
            s = a[0] * x[0]
            for j in range(1, n):
                s = s + a[j] * x[j]
            t = b[0] * u[0]
            for j in range(1, m):
                t = t + b[j] * u[j]
            y[i] = s + t
        for i in range(n):
            x[i] = y[i]


#: Responses a process computes in Python before it compiles :func:`_held_states`
#: (compiling costs about a second, once per machine: numba keeps the machine
#: code; a replay of a few thousand ticks takes ~15 ms in Python, ~0.2 ms
#: compiled: ``diagnose`` makes hundreds, ``compare`` a few).
COMPILE_AFTER_RESPONSES = 40

_responses = 0
_compiled_states = None


def _states_at_ticks(A: np.ndarray, B: np.ndarray, x0: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The states ``x[k]`` (N, n) of ``x[k+1] = A x[k] + B U[k]`` from ``x0``
    (:func:`_held_states`: Python for a process's first
    :data:`COMPILE_AFTER_RESPONSES` calls, then compiled by numba if importable)."""
    global _responses, _compiled_states
    _responses += 1
    if _compiled_states is None and _responses > COMPILE_AFTER_RESPONSES:
        _compiled_states = compiled_available() and njit_cached(_held_states)
    N, n = len(U), A.shape[0]
    if _compiled_states:
        X = np.empty((N, n))
        _compiled_states(A, B, np.asarray(x0, dtype=float), U, X)
        return X
    X = [[0.0] * n for _ in range(N)]
    _held_states(A.tolist(), B.tolist(), list(x0), U.tolist(), X)
    return np.array(X, dtype=float).reshape(N, n)


class SampledTable(Diagram):
    """A linear table's exact response to a command held over ticks, at the ticks.

    The continuous ``LinearSystem`` (A, B, C, D) is discretized by
    :func:`~hybridtable.laws.table.held_tick` (the zero-order-hold exact solution:
    ``x[k+1] = e^{A h} x[k] + int_0^h e^{A s} ds B u[k]``), so a replay needs no
    integrator and has no integration error.

    Ports
    -----
    Input ``commanded_state`` (size 2: m, m/s)
        The command *sent at* each tick: the discrete update at tick ``k``
        reads it and holds it to tick ``k + 1``. Connect the command itself,
        not a ``ZeroOrderHold`` (whose output at ``t_k`` is still the previous
        command).
    Output ``motion`` (size 3: m, m/s, m/s^2)
        ``C x[k] + D u[k]`` at tick ``k``, as the continuous table's at ``t_k``.

    Parameters
    ----------
    linear : (A, B, C, D)
        The continuous table; its state is ``pairs`` copies of ``[p, v]``.
    period_s : float
        Tick period ``h`` (s).
    """

    def __init__(self, linear, period_s: float) -> None:
        Diagram.__init__(self)
        A, B, C, D = (np.asarray(m, dtype=float) for m in linear)
        self._pairs = A.shape[0] // 2
        builder = DiagramBuilder()
        self._linear = builder.AddNamedSystem(
            "sampled_table", LinearSystem(*held_tick(A, B, period_s), C, D, period_s)
        )
        builder.ExportInput(self._linear.get_input_port(), "commanded_state")
        builder.ExportOutput(self._linear.get_output_port(), "motion")
        builder.BuildInto(self)

    def initial_state(self, position_m: float, velocity_m_per_s: float) -> np.ndarray:
        """The state with every ``[p, v]`` pair at ``position_m``, ``velocity_m_per_s``."""
        return np.tile([position_m, velocity_m_per_s], self._pairs)

    def set_initial_state(self, context, position_m: float, velocity_m_per_s: float) -> None:
        """Every ``[p, v]`` pair of the state at ``position_m``, ``velocity_m_per_s``."""
        x = self.initial_state(position_m, velocity_m_per_s)
        self.GetSubsystemContext(self._linear, context).SetDiscreteState(x)

    def respond(
        self, commands: np.ndarray, position_m: float, velocity_m_per_s: float
    ) -> np.ndarray:
        """The motion at the ticks (N, 3) for the commands (N, 2) held from each
        tick to the next, from the initial state: ``y[k] = C x[k] + D u[k]``,
        ``x[k+1] = A x[k] + B u[k]`` with this system's own matrices (what the
        Drake system computes, without a simulator)."""
        lin = self._linear
        A, B, C, D = (np.asarray(m, dtype=float) for m in (lin.A(), lin.B(), lin.C(), lin.D()))
        u = np.ascontiguousarray(commands, dtype=float)
        X = _states_at_ticks(A, B, self.initial_state(position_m, velocity_m_per_s), u)
        # Outputs, vectorized over the ticks with the same sums in the same order.
        return np.column_stack(
            [_ordered_dot(c, X) + _ordered_dot(d, u) for c, d in zip(C, D, strict=True)]
        )
