"""A law compiled into a Drake system with named ports: no Python per step.

:func:`compiled_system` calls the law of each output port (a function of
:mod:`hybridtable.laws`) once on ``pydrake.symbolic`` variables and builds the
Drake system that evaluates the resulting expressions in C++:

- an affine law (the ungated compensator, the bilateral contact of the
  stability analysis) becomes an ``AffineSystem``: exact derivatives for
  ``Linearize``, scalar-convertible to ``AutoDiffXd``;
- a switching law (a gate, a contact that never pulls) becomes a
  ``SymbolicVectorSystem`` with ``if_then_else``.

Named input ports feed a ``Multiplexer``; a ``held`` input is the value a
``ZeroOrderHold`` sampled at the rig computer's last tick (the backward
difference's previous sample; held whether the law reads it or not, so the
system's states do not depend on its constants); several named outputs come out of a
``Demultiplexer``. An input the law does not read is still a port (so every
compensator has the same ports) and is read by nothing.

Drake 1.51's ``SymbolicVectorSystem`` demands continuous dynamics whenever a
diagram around it integrates (``DoCalcTimeDerivatives`` fails on a
stateless or discrete one), so a switching law carries one continuous state
that stays 0 (``x' = 0``; its integration error is 0, so the integrator's
step control is unchanged).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import math
import operator
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.symbolic import (
    DecomposeAffineExpressions,
    Expression,
    Formula,
    MakeVectorVariable,
    Variable,
    Variables,
)
from pydrake.systems.framework import BasicVector_, DiagramBuilder, LeafSystem_, System
from pydrake.systems.primitives import (
    AffineSystem,
    Demultiplexer,
    Multiplexer,
    SymbolicVectorSystem,
    ZeroOrderHold,
)
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._components import Block, Component
from hybridtable.errors import SimulationError

__all__ = [
    "CompiledLaw",
    "compiled_available",
    "compiled_kernel",
    "compiled_system",
    "njit_cached",
    "python_function",
    "python_lambda",
    "LawSystem",
    "LawSystem_",
]

#: ``law(signals) -> value`` of one output port: a number or a sequence;
#: ``signals`` maps every input (and held input) name to its vector of values.
Law = Callable[[Mapping[str, Any]], Any]


def _expression(e: Any) -> Expression:
    return e if isinstance(e, Expression) else Expression(e)


def _affine(expressions: Sequence[Expression], variables: Sequence) -> AffineSystem | None:
    """``y = D u + y0`` when every expression is affine in ``variables``, else None."""
    if not variables:
        return None
    try:
        D, y0 = DecomposeAffineExpressions(expressions, variables)
    except RuntimeError:  # not affine: a switch (if_then_else) or a product of signals
        return None
    n = len(variables)
    return AffineSystem(
        np.zeros((0, 0)), np.zeros((0, n)), np.zeros(0), np.zeros((len(expressions), 0)), D, y0
    )


def _symbolic(expressions: Sequence[Expression], variables: Sequence) -> SymbolicVectorSystem:
    """The expressions evaluated in C++, with the one state Drake demands (see above)."""
    unused = MakeVectorVariable(1, "unused")
    return SymbolicVectorSystem(
        state=unused, dynamics=[Expression(0.0)], input=list(variables), output=expressions
    )


class _Signals(dict):
    """A law's input values by port name, as Python numbers, each evaluated
    when the law first reads it (a port it does not read may be unconnected).

    With ``system`` (the ``float`` form), a non-finite input stops the run
    with a :class:`~hybridtable.errors.SimulationError` naming the system and
    the input: a NaN that reached a continuous state would make the
    integrator's error control shrink its step without end, and a NaN that a
    gate reads as "no contact" would give a silently wrong run.
    """

    def __init__(self, context, ports, held, system=None) -> None:
        super().__init__()
        self._context, self._ports, self._held = context, ports, held
        self._system = system

    def __missing__(self, name: str):
        if name in self._held:
            value = self._context.get_discrete_state(self._held[name]).value().tolist()
        else:
            value = self._ports[name].Eval(self._context).tolist()
        if self._system is not None and not all(map(math.isfinite, value)):
            raise SimulationError(
                f"{self._system.get_name()}'s input {name} is not finite ({value}) at "
                f"t = {self._context.get_time():.6g} s: a system before it gave NaN or inf"
            )
        self[name] = value
        return value


@TemplateSystem.define("LawSystem_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__])
def LawSystem_(T):
    class Impl(LeafSystem_[T]):
        """A law evaluated by a Python callback (``float`` or ``AutoDiffXd``).

        Cheaper than the compiled form where the diagram evaluates the law
        rarely: once per tick of a sampled rig computer, once per step for
        the logger (the compiled form's state is integrated, which evaluates
        its inputs at every integrator stage).
        """

        def _construct(self, inputs, outputs, held, output_sizes, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self._args = (inputs, outputs, held, output_sizes)
            self._ports = {n: self.DeclareVectorInputPort(n, size) for n, size in inputs.items()}
            self._held = {}
            for i, (n, (source, period)) in enumerate(held.items()):
                self.DeclareDiscreteState(inputs[source])
                self._held[n] = i
                self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._make_store(i, source))
            for n, size in output_sizes.items():
                self.DeclareVectorOutputPort(
                    n, BasicVector_[T](size), self._make_calc(outputs[n], size)
                )

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, *other._args, converter=converter)

        def _make_store(self, index, source):
            port = self._ports[source]

            def store(context, discrete_state):
                discrete_state.get_mutable_vector(index).SetFromVector(port.Eval(context))

            return store

        def _make_calc(self, law, size):
            checked = self if T is float else None

            def calc(context, output):
                # Only the inputs the law reads are evaluated (others may be unconnected).
                value = law(_Signals(context, self._ports, self._held, checked))
                if size == 1 and not isinstance(value, list | tuple | np.ndarray):
                    output.SetAtIndex(0, value)
                else:
                    output.SetFromVector(np.atleast_1d(value))

            return calc

    return Impl


LawSystem = LawSystem_[None]


_OPERATORS = {
    operator.gt: ">",
    operator.ge: ">=",
    operator.lt: "<",
    operator.le: "<=",
    operator.eq: "==",
    operator.ne: "!=",
    operator.truediv: "/",
}


#: Drake's symbolic functions -> their Python names in :data:`_NAMESPACE`.
_FUNCTIONS = {
    name: name for name in ("abs", "min", "max", "exp", "log", "sqrt", "sin", "cos", "tanh")
}

#: What the generated code may call: the functions above and the non-finite
#: constants (``repr`` writes ``inf`` and ``nan``), nothing else.
_NAMESPACE = {
    "__builtins__": {},
    "inf": math.inf,
    "nan": math.nan,
    "abs": abs,
    "min": min,
    "max": max,
    **{name: getattr(math, name) for name in ("exp", "log", "sqrt", "sin", "cos", "tanh")},
}


def _python_source(node: Any, names: dict) -> str:
    """Python source of a symbolic expression or formula (the law's trace)."""
    if isinstance(node, float | int):
        return repr(float(node))
    if isinstance(node, Variable):
        return names[node.get_id()]
    f, args = node.Unapply()
    parts = [_python_source(a, names) for a in args]
    label = getattr(f, "__name__", "")
    if f in (Expression, Formula) or label == "Expression":  # a constant or a variable
        return parts[0] if parts else repr(float(node.Evaluate()))
    if label == "True_":
        return "True"
    if label == "False_":
        return "False"
    if label == "_reduce_add":
        return "(" + " + ".join(parts) + ")"
    if label == "_reduce_mul":
        return "(" + " * ".join(parts) + ")"
    if label == "if_then_else":
        return f"({parts[1]} if {parts[0]} else {parts[2]})"
    if label in ("logical_and", "logical_or"):
        return "(" + f" {label[8:]} ".join(parts) + ")"
    if label == "logical_not":
        return f"(not {parts[0]})"
    if f in _OPERATORS:
        return f"({parts[0]} {_OPERATORS[f]} {parts[1]})"
    if label == "pow":
        return f"({parts[0]} ** {parts[1]})"
    if label in _FUNCTIONS:
        return f"{_FUNCTIONS[label]}({', '.join(parts)})"
    raise NotImplementedError(f"no Python form for {label or f} in {node}")


def python_function(law: Callable[..., Any], arguments: Sequence[str]) -> Callable[..., Any]:
    """``law`` compiled into a plain Python function of ``arguments`` (numbers
    in, a number out): the law traced once on symbolic variables, its
    expression written as one Python expression. For the fast engine's ticks:
    one call, no branch on types (the law's ``select`` and ``both`` are paid
    once, here). The law must trace (no Python ``if`` on a signal)."""
    variables = [Variable(a) for a in arguments]
    value = law(*variables)
    names = {v.get_id(): f"x{i}" for i, v in enumerate(variables)}
    if isinstance(value, bool):
        source = repr(value)
    else:
        node = value if isinstance(value, Expression | Formula) else Expression(value)
        source = _python_source(node, names)
    return python_lambda([names[v.get_id()] for v in variables], source)


def compiled_available() -> bool:
    """Whether numba is importable here: the plain functions of the fast engine's
    tick loop and of a sampled table's response run compiled, else as Python."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def njit_cached(function: Callable[..., Any]) -> Callable[..., Any]:
    """``function`` compiled by numba, its machine code kept beside the module or
    in the user's cache (compiled anew in each process where neither is writable)."""
    import numba

    try:
        return numba.njit(cache=True)(function)
    except RuntimeError:
        return numba.njit(function)


#: Plain functions already made callable from compiled code.
_JITABLE: set[Callable[..., Any]] = set()


@functools.cache
def compiled_kernel(
    function: Callable[..., Any], helpers: tuple[Callable[..., Any], ...] = ()
) -> Callable[..., Any]:
    """``function`` compiled by numba (:func:`njit_cached`), once per process;
    the plain functions it calls, ``helpers`` (every one, also those they call),
    become callable from compiled code and stay plain functions for Python
    (numba's ``register_jitable``). Where numba is missing, ``function`` itself:
    the same operations, run as Python. The per-tick arithmetic of the 6-DoF
    loop's systems runs so, one call per port evaluation."""
    if not compiled_available():
        return function
    from numba.extending import register_jitable

    for helper in helpers:
        if helper not in _JITABLE:
            register_jitable(helper)
            _JITABLE.add(helper)
    kernel = njit_cached(function)
    _flush_if_helpers_changed(kernel, function, helpers)
    return kernel


def _flush_if_helpers_changed(
    kernel: Any, function: Callable[..., Any], helpers: Sequence[Callable[..., Any]]
) -> None:
    """numba compiles a cached function anew when its own file changes, not
    when a helper in another file does (its machine code would be stale):
    keep a digest of the helpers' source beside the cache, and empty the
    cache when it differs."""
    cache = getattr(kernel, "_cache", None)
    folder = getattr(cache, "cache_path", None)
    if folder is None:  # not cached
        return
    digest = hashlib.sha256()
    for helper in helpers:
        try:
            digest.update(inspect.getsource(helper).encode())
        except (OSError, TypeError):
            digest.update(helper.__qualname__.encode())
    stamp = digest.hexdigest()
    marker = Path(folder) / f"{function.__module__}.{function.__qualname__}.helpers"
    try:
        if marker.read_text(encoding="utf-8") == stamp:
            return
    except OSError:
        pass
    cache.flush()
    with contextlib.suppress(OSError):
        marker.write_text(stamp, encoding="utf-8")


def python_lambda(arguments: Sequence[str], source: str) -> Callable[..., Any]:
    """``lambda arguments: source``, compiled with nothing in reach but the
    numbers' functions and constants of :data:`_NAMESPACE` (generated code:
    :func:`python_function`)."""
    return eval(f"lambda {', '.join(arguments)}: {source}", dict(_NAMESPACE))  # noqa: S307


def compiled_system(
    name: str,
    inputs: Mapping[str, int],
    outputs: Mapping[str, Law],
    held: Mapping[str, tuple[str, float]] | None = None,
    compiled: bool = True,
) -> System:
    """Compile the laws of ``outputs`` into one Drake system named ``name``.

    Parameters
    ----------
    name : str
    inputs : mapping of str to int
        Input port names and sizes, in port order.
    outputs : mapping of str to callable
        Output port name -> its law ``law(signals) -> value`` (ports in the
        mapping's order).
    held : mapping of str to (str, float), optional
        ``{name: (input, period_s)}``: ``name`` is ``input`` as a
        ``ZeroOrderHold`` of that period sampled it at the last tick.
    compiled : bool
        False: a switching law is a :class:`LawSystem` (a Python callback of
        the laws on the signals' values) instead of a ``SymbolicVectorSystem``;
        an affine law is an ``AffineSystem`` either way.

    Returns
    -------
    System
        Input ports ``inputs``, output ports the law's.
    """
    held = dict(held or {})
    signals = {n: MakeVectorVariable(size, n) for n, size in inputs.items()}
    for n, (source, _) in held.items():
        signals[n] = MakeVectorVariable(inputs[source], n)
    laws = dict(outputs)
    traced = {n: [_expression(e) for e in np.atleast_1d(f(signals))] for n, f in laws.items()}
    expressions = [e for es in traced.values() for e in es]

    used = Variables()
    for e in expressions:
        used.insert(e.GetVariables())
    read = [n for n in signals if any(used.include(v) for v in signals[n])]
    variables = [v for n in read for v in signals[n]]

    if not compiled and _affine(expressions, variables) is None:
        sizes = {n: len(es) for n, es in traced.items()}
        system = LawSystem(dict(inputs), laws, held, sizes)
        system.set_name(name)
        return system

    def core() -> System:  # a new one each time the law's primitives are added
        return _affine(expressions, variables) or _symbolic(expressions, variables)

    return CompiledLaw(name, inputs, held, traced, read, signals, core)


class CompiledLaw(Component):
    """A switching or affine law with named ports (see :func:`compiled_system`):
    its core (``{name}_law``) fed by a ``Multiplexer`` (``{name}_inputs``),
    the held inputs' ``ZeroOrderHold`` s and, for several outputs, a
    ``Demultiplexer`` (``{name}_outputs``)."""

    def __init__(self, name, inputs, held, traced, read, signals, core) -> None:
        Component.__init__(self)
        self._inputs = self._input_sizes = dict(inputs)
        self._held, self._traced = held, traced
        self._read, self._signals, self._core = read, signals, core
        self._build(name)
        self.set_name(name)

    def _add(self, builder: DiagramBuilder, name: str) -> Block:
        inputs, signals, read = self._inputs, self._signals, self._read
        core = builder.AddNamedSystem(f"{name}_law", self._core())
        # Every input port of a subsystem that reads each named input.
        consumers: dict[str, list] = {n: [] for n in inputs}
        if read:
            mux = builder.AddNamedSystem(
                f"{name}_inputs", Multiplexer([len(signals[n]) for n in read])
            )
            builder.Connect(mux.get_output_port(), core.get_input_port())
        for h, (src, period) in self._held.items():  # held even when unread: the same states
            zoh = builder.AddNamedSystem(f"{name}_{h}", ZeroOrderHold(period, inputs[src]))
            consumers[src].append(zoh.get_input_port())
            if h in read:
                builder.Connect(zoh.get_output_port(), mux.get_input_port(read.index(h)))
        for i, n in enumerate(read):
            if n in inputs:
                consumers[n].insert(0, mux.get_input_port(i))
        if len(self._traced) == 1:
            outputs = {next(iter(self._traced)): core.get_output_port()}
        else:
            demux = builder.AddNamedSystem(
                f"{name}_outputs", Demultiplexer([len(es) for es in self._traced.values()])
            )
            builder.Connect(core.get_output_port(), demux.get_input_port())
            outputs = {n: demux.get_output_port(i) for i, n in enumerate(self._traced)}
        return Block(self, consumers, outputs)
