"""State-space interconnection of linearized blocks.

Each block is a linear system ``x' = A x + B v, w = C x + D v`` (``x[k+1]`` for
a discrete block) whose input and output channels have names such as
``"table.motion[0]"``. An :class:`Interconnection` wires block inputs to block
outputs and assembles one state-space model, as Drake's ``DiagramBuilder``
wires systems and ``control.interconnect`` wires python-control systems, but
with the wiring resolved once so that the same structure is re-assembled
cheaply for thousands of parameter points.

With ``v`` every block input, ``w`` every block output, ``v = M w + N u`` the
wiring (``u`` the external inputs) and ``y = P w`` the external outputs::

    w = (I - D M)^-1 (C x + D N u)

so ``A_cl = A + B M W C``, ``B_cl = B (M W D N + N)``, ``C_cl = P W C`` and
``D_cl = P W D N`` with ``W = (I - D M)^-1``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from hybridtable.errors import InterconnectionError

__all__ = ["StateSpaceBlock", "Interconnection", "InterconnectionError", "state_slices"]


@dataclass(frozen=True)
class StateSpaceBlock:
    """A linear block with named channels.

    Parameters
    ----------
    name : str
        Block name (the Drake system's name).
    A, B, C, D : numpy.ndarray
        State-space matrices; ``A`` may be 0 x 0 (a static gain).
    inputs, outputs : tuple of str
        Names of the input and output channels, one per column of ``B``/``D``
        and one per row of ``C``/``D``.
    dt : float
        0 for a continuous block, else its sample period in s.
    """

    name: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    dt: float = 0.0

    def __post_init__(self) -> None:
        n = self.A.shape[0]
        if self.A.shape != (n, n) or self.B.shape != (n, len(self.inputs)):
            raise InterconnectionError(f"block {self.name}: A/B shapes do not match its inputs")
        if self.C.shape != (len(self.outputs), n) or self.D.shape != (
            len(self.outputs),
            len(self.inputs),
        ):
            raise InterconnectionError(f"block {self.name}: C/D shapes do not match its outputs")

    @property
    def num_states(self) -> int:
        return self.A.shape[0]

    def with_matrices(
        self, A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray
    ) -> StateSpaceBlock:
        """The same channels with other matrices."""
        return StateSpaceBlock(self.name, A, B, C, D, self.inputs, self.outputs, self.dt)

    def transfer(self, s: complex | np.ndarray) -> np.ndarray:
        """Transfer matrix ``C (s I - A)^-1 B + D`` at one or several complex
        points (``z`` for a discrete block); shape ``(..., outputs, inputs)``."""
        s = np.asarray(s, dtype=complex)
        n = self.num_states
        if n == 0:
            return np.broadcast_to(self.D, s.shape + self.D.shape).astype(complex)
        eye = np.eye(n)
        M = s[..., None, None] * eye - self.A
        X = np.linalg.solve(M, np.broadcast_to(self.B, s.shape + self.B.shape))
        return self.C @ X + self.D


def state_slices(blocks: Sequence[StateSpaceBlock]) -> dict[str, slice]:
    """Where each block's states sit in the stacked state of ``blocks``
    (the state order of an :class:`Interconnection` of them)."""
    out, i = {}, 0
    for b in blocks:
        out[b.name] = slice(i, i + b.num_states)
        i += b.num_states
    return out


def _block_diag(mats: Sequence[np.ndarray]) -> np.ndarray:
    """Block-diagonal matrix; blocks may have zero rows or columns."""
    rows = sum(m.shape[0] for m in mats)
    cols = sum(m.shape[1] for m in mats)
    out = np.zeros((rows, cols))
    r = c = 0
    for m in mats:
        out[r : r + m.shape[0], c : c + m.shape[1]] = m
        r += m.shape[0]
        c += m.shape[1]
    return out


class Interconnection:
    """Wiring of named blocks, resolved once, assembled many times.

    Parameters
    ----------
    blocks : sequence of (name, inputs, outputs)
        Block names with their input and output channel names, in the order
        the blocks' states are stacked.
    connections : mapping
        ``input channel -> output channel`` for every internally fed input.
    external_inputs : sequence of str
        Input channels driven from outside (the model's inputs, in order).
    external_outputs : sequence of str
        Output channels that are the model's outputs, in order.
    zero_inputs : sequence of str
        Input channels deliberately left at zero (unused ports).

    Raises
    ------
    InterconnectionError
        If a channel is unknown, an input is wired twice, or left unwired.
    """

    def __init__(
        self,
        blocks: Sequence[tuple[str, Sequence[str], Sequence[str]]],
        connections: Mapping[str, str],
        external_inputs: Sequence[str],
        external_outputs: Sequence[str],
        zero_inputs: Sequence[str] = (),
    ) -> None:
        self.block_names = tuple(b[0] for b in blocks)
        self._inputs = [tuple(b[1]) for b in blocks]
        self._outputs = [tuple(b[2]) for b in blocks]
        in_index = {c: i for i, c in enumerate(c for chans in self._inputs for c in chans)}
        out_index = {c: i for i, c in enumerate(c for chans in self._outputs for c in chans)}
        if len(in_index) != sum(map(len, self._inputs)) or len(out_index) != sum(
            map(len, self._outputs)
        ):
            raise InterconnectionError("channel names must be unique")
        nv, nw, nu = len(in_index), len(out_index), len(external_inputs)
        M = np.zeros((nv, nw))
        N = np.zeros((nv, nu))
        P = np.zeros((len(external_outputs), nw))
        fed: set[str] = set()

        def inp(name: str) -> int:
            if name not in in_index:
                raise InterconnectionError(f"unknown input channel {name!r}")
            if name in fed:
                raise InterconnectionError(f"input channel {name!r} is wired twice")
            fed.add(name)
            return in_index[name]

        def out(name: str) -> int:
            if name not in out_index:
                raise InterconnectionError(f"unknown output channel {name!r}")
            return out_index[name]

        for dst, src in connections.items():
            M[inp(dst), out(src)] = 1.0
        for j, name in enumerate(external_inputs):
            N[inp(name), j] = 1.0
        for name in zero_inputs:
            inp(name)
        unwired = set(in_index) - fed
        if unwired:
            raise InterconnectionError(f"unwired input channels: {sorted(unwired)}")
        for i, name in enumerate(external_outputs):
            P[i, out(name)] = 1.0
        self._M, self._N, self._P = M, N, P
        self.inputs = tuple(external_inputs)
        self.outputs = tuple(external_outputs)

    def assemble(
        self, blocks: Sequence[StateSpaceBlock], name: str = "interconnection"
    ) -> StateSpaceBlock:
        """One state-space model of the wired blocks (given in the wiring's order).

        Raises
        ------
        InterconnectionError
            If the blocks do not match the wiring, mix sample periods, or form
            a singular algebraic loop.
        """
        if len(blocks) != len(self.block_names):
            raise InterconnectionError(f"expected {len(self.block_names)} blocks")
        for b, ins, outs in zip(blocks, self._inputs, self._outputs, strict=True):
            if b.inputs != ins or b.outputs != outs:
                raise InterconnectionError(f"block {b.name} does not match the wiring")
        dts = {b.dt for b in blocks if b.num_states > 0}
        if len(dts) > 1:
            raise InterconnectionError(f"blocks mix sample periods {sorted(dts)}")
        dt = dts.pop() if dts else 0.0
        A = _block_diag([b.A for b in blocks])
        B = _block_diag([b.B for b in blocks])
        C = _block_diag([b.C for b in blocks])
        D = _block_diag([b.D for b in blocks])
        M, N, P = self._M, self._N, self._P
        K = np.eye(M.shape[1]) - D @ M
        try:
            W = np.linalg.inv(K)
        except np.linalg.LinAlgError:
            raise InterconnectionError("the blocks form a singular algebraic loop") from None
        BM = B @ M @ W
        return StateSpaceBlock(
            name,
            A + BM @ C,
            BM @ D @ N + B @ N,
            P @ W @ C,
            P @ W @ D @ N,
            self.inputs,
            self.outputs,
            dt,
        )
