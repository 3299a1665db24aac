"""The fast engine's laws as plain functions, and its held ticks: one loop, run by Python or
compiled by numba when worth it.

The laws (the contact, the gate, the sampled compensator) are traced once from
their definitions in :mod:`hybridtable.laws` into plain functions
(:func:`~hybridtable.laws.compiled.python_function`), which the fast engine
calls and numba compiles.

A continuous loop whose force law cannot switch inside a tick (the gate and the
clamp read only the held samples) is the campaign workhorse: ``explain``
spends almost all its time there (Table 4: 15,600 runs, 100 M ticks). Each
tick is the contact law, the gate on the delayed sample and one exact step of
the mode the gate chose (:mod:`hybridtable.loop.fast`).

:func:`held_ticks` is that loop, written once. It runs as plain Python for the
first :data:`COMPILE_AFTER_RUNS` runs of a process, and then as machine code
compiled by numba (the same function, its law calls compiled from the same
traced laws): compiling costs about a second, which a single ``simulate``
should not pay, while a fit of thousands of runs gains about two orders of
magnitude. Both execute the same floating-point operations in the same order
(numba without ``fastmath`` contracts nothing), so their records are identical
bit for bit (``tests/loop/test_ticks.py``).

The loop stops at the first tick whose time reaches ``due`` (the stop rule's
next check, evaluated by the caller in Python) before recording it, and when
its record arrays are full; the caller then checks, grows or resumes.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Callable
from typing import Any

from hybridtable.laws.compensation import CompensationLaw, backward_difference, compensate
from hybridtable.laws.compiled import python_function
from hybridtable.laws.contact import spring_contact_force

__all__ = [
    "COMPILE_AFTER_RUNS",
    "bound",
    "compensator_function",
    "compiled_available",
    "contact_function",
    "gate_function",
    "held_ticks",
]

#: Runs a process makes with the Python loop before it compiles the loop: a run
#: of the Python loop costs ~20 ms, compiling ~1 s.
COMPILE_AFTER_RUNS = 40

_runs = 0


def compiled_available() -> bool:
    """Whether numba is importable here (without it the loop stays Python)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def _loop(contact: Callable[..., float], gate_open: Callable[..., bool]):
    """The held-tick loop over the traced ``contact (p, v, k, c)`` and ``gate_open
    (f, dead band)`` laws (plain functions, or numba's compilations of them)."""

    def ticks(state, on, touched, e_on, e_off, law, F, vs, fas, fcs, k, n, h, due, checked):
        p, v, pa, va, u = state
        a0, a1, a2, a3, a4, b0, b1, b2, b3, b4, g0, g1, g2, g3, g4, d0, d1, d2, d3, d4 = e_on
        x0, x1, x2, x3, x4, y0, y1, y2, y3, y4, w0, w1, w2, w3, w4, z0, z1, z2, z3, z4 = e_off
        c0, c1, c2, c3, lead_f, lead_prev, k_con, c_con, db, by_force, clamp = law
        cap = len(vs)
        while True:
            if k >= cap:  # out of room: the caller grows the records
                return (p, v, pa, va, u), on, touched, k, 0.0, 0.0, 1
            f_act = contact(pa, va, k_con, c_con)
            f_comp = (c0 * p + c1 * v + c2 * pa + c3 * va + u) if on else 0.0
            if f_act > 0.0:
                touched = True
            if k * h >= due and not checked:  # the stop rule's check, before the record
                return (p, v, pa, va, u), on, touched, k, f_act, f_comp, 0
            checked = False
            vs[k] = v
            fas[k] = f_act
            fcs[k] = f_comp
            F[k + n + 2] = f_act
            f_mea = F[k + 2]
            u = lead_f * f_mea + lead_prev * F[k + 1]
            gate = gate_open(f_mea, db)
            if (gate or by_force == 0.0) and not (clamp != 0.0 and u < 0.0):
                on = True
                p, v, pa, va = (
                    a0 * p + a1 * v + a2 * pa + a3 * va + a4 * u,
                    b0 * p + b1 * v + b2 * pa + b3 * va + b4 * u,
                    g0 * p + g1 * v + g2 * pa + g3 * va + g4 * u,
                    d0 * p + d1 * v + d2 * pa + d3 * va + d4 * u,
                )
            else:
                on = False
                p, v, pa, va = (
                    x0 * p + x1 * v + x2 * pa + x3 * va + x4 * u,
                    y0 * p + y1 * v + y2 * pa + y3 * va + y4 * u,
                    w0 * p + w1 * v + w2 * pa + w3 * va + w4 * u,
                    z0 * p + z1 * v + z2 * pa + z3 * va + z4 * u,
                )
            k += 1

    return ticks


def bound(function, *constants):
    """``function`` with its trailing arguments bound to ``constants`` (its code
    is compiled once; binding is as cheap as a closure, and calls stay plain)."""
    return types.FunctionType(function.__code__, function.__globals__, None, constants)


@functools.cache
def contact_function():
    """The contact law as one plain function ``(p, v, k, c) -> f`` (traced once:
    :func:`~hybridtable.laws.compiled.python_function`)."""
    return python_function(lambda p, v, k, c: spring_contact_force(k, c, p, v), "pvkc")


@functools.cache
def gate_function(gate: str):
    """The compensator's gate ``(level, dead band) -> open`` as a plain function."""
    return python_function(
        lambda f, db: CompensationLaw(force_deadband_n=db, gate=gate).gate_open(f), ("f", "db")
    )


@functools.cache
def compensator_function(lead: bool, mdc: bool, gate: str, clamp: bool, damping: bool):
    """The sampled rig computer's compensation law for one set of switches, as a
    plain function ``(f_mea, prev, p, v, p_act, v_act, T_lead, h, dead band, k, c)
    -> f_comp`` (traced once per set, its constants as arguments)."""

    def law(f, prev, p, v, pa, va, lead_s, h, db, k, c):
        switches = CompensationLaw(lead_s if lead else 0.0, mdc, db, gate, clamp)
        rate = backward_difference(f, prev, h)
        return compensate(switches, f, rate, p - pa, v - va, k, c if damping else None, pa > 0.0)

    names = ("f", "prev", "p", "v", "pa", "va", "lead", "h", "db", "k", "c")
    return python_function(law, names)


@functools.cache
def _compiled(contact: Callable[..., float], gate_open: Callable[..., bool]):
    import numba

    return numba.njit(_loop(numba.njit(contact), numba.njit(gate_open)))


@functools.cache
def _python(contact: Callable[..., float], gate_open: Callable[..., bool]):
    return _loop(contact, gate_open)


def held_ticks(
    contact: Callable[..., float], gate_open: Callable[..., bool], compiled: bool | None = None
) -> tuple[Callable[..., Any], bool]:
    """The held-tick loop over these traced laws, and whether it is compiled.

    ``compiled`` None: Python for a process's first :data:`COMPILE_AFTER_RUNS`
    calls, compiled after (if numba is importable). A compiled loop takes numpy
    arrays for ``F`` and the records; the Python loop, lists (faster there).
    """
    global _runs
    if compiled is None:
        _runs += 1
        compiled = _runs > COMPILE_AFTER_RUNS and compiled_available()
    if compiled:
        return _compiled(contact, gate_open), True
    return _python(contact, gate_open), False
