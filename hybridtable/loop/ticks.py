"""The fast engine's laws as plain functions, and its tick loop: one loop, run by Python or
compiled by numba when worth it.

The laws (the contact, the gate, when the MDC term acts, the sampled
compensator) are traced once from their definitions in :mod:`hybridtable.laws`
into plain functions (:func:`~hybridtable.laws.compiled.python_function`),
which the fast engine calls and numba compiles.

A continuous fast run is the campaign workhorse: ``explain`` spends almost all
its time there (Table 4: 15,600 runs, 100 M ticks). Each tick is the contact
law, the gate on the delayed sample, the mode it picks (:func:`_mode`, bits
:data:`ON`, :data:`CONTACT`, :data:`MDC`) and that mode's exact step
(:mod:`hybridtable.loop.fast`). Where the force law switches inside a tick the
loop stops and the caller locates the switch on the exact trajectory.

:func:`tick_loop` gives that loop, written once. It runs as plain Python for
the first :data:`COMPILE_AFTER_RUNS` runs of a process, and then as machine
code compiled by numba (the same function, its law calls compiled from the
same traced laws); :func:`compile_loops` compiles ahead, before a process forks
its workers. Compiling costs about 2 s, which a single ``simulate`` should not
pay, while a fit of thousands of runs gains one to two orders of magnitude.
Both execute the same floating-point operations in the same order (numba
without ``fastmath`` contracts nothing), so their records are identical bit for
bit (``tests/loop/test_ticks.py``).

The loop stops at the first tick whose time reaches ``due`` (the stop rule's
next check, evaluated by the caller in Python) before recording it, when its
record arrays are full, and at a switch inside a tick; the caller then checks,
grows, locates the switch, and resumes.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Callable
from typing import Any

import numpy as np

from hybridtable.laws.compensation import CompensationLaw, backward_difference, compensate
from hybridtable.laws.compiled import compiled_available, python_function
from hybridtable.laws.contact import spring_contact_force

__all__ = [
    "COMPILE_AFTER_RUNS",
    "OFF",
    "ON",
    "CONTACT",
    "MDC",
    "bound",
    "compensator_function",
    "compile_loops",
    "contact_function",
    "corrects_function",
    "gate_function",
    "mode_function",
    "tick_law",
    "tick_loop",
]

#: Runs a process makes with the Python loop before it compiles the loop: a run
#: of the Python loop costs ~20 ms, compiling ~2 s.
COMPILE_AFTER_RUNS = 40

_runs = 0


#: A mode of the continuous loop between switches, as bits of an int: the force
#: acts (1), with the contact's own term (2: no delay), with the MDC term (4).
OFF, ON, CONTACT, MDC = 0, 1, 2, 4


def _mode(contact, gate_open, corrects):
    """``mode(p, v, pa, va, u, gate, rows, law) -> int``: the force law's mode at the
    state ``(p, v, pa, va, u)`` with the held reading's gate ``gate``
    (:meth:`hybridtable.loop.fast._Continuous.mode_of`); ``rows[m]``: the force
    of mode ``m`` over the state; ``law``: the loop's numbers (:func:`tick_law`)."""

    def mode(p, v, pa, va, u, gate, rows, law):
        _, _, k_con, c_con, db, by_force, clamp, undelayed, mdc_on, _ = law
        touching = False
        if undelayed != 0.0:  # the gate reads the contact's own force, now
            raw = contact(pa, va, k_con, c_con)
            touching = raw > 0.0
            gate = touching and gate_open(raw, db)
        if by_force != 0.0 and not gate:
            return OFF
        code = ON
        if touching:
            code += CONTACT
        if mdc_on != 0.0 and corrects(pa):
            code += MDC
        if clamp != 0.0:
            r0, r1, r2, r3, r4 = rows[code]
            if r0 * p + r1 * v + r2 * pa + r3 * va + r4 * u < 0.0:
                return OFF
        return code

    return mode


def _loop(mode_of, contact, gate_open):
    """The tick loop over the traced ``contact (p, v, k, c)`` and ``gate_open
    (f, dead band)`` laws and the mode rule ``mode_of`` (plain functions, or
    numba's compilations of them)."""

    def ticks(state, mode, touched, steps, rows, law, F, vs, fas, fcs, k, n, h, due, checked):
        p, v, pa, va, u = state
        lead_f, lead_prev, k_con, c_con, db, by_force, clamp, undelayed, _, switches = law
        held_on = ON + (MDC if law[8] != 0.0 else 0)
        cap = len(vs)
        while True:
            if k >= cap:  # out of room: the caller grows the records
                return (p, v, pa, va, u), mode, touched, k, 0.0, 0.0, 1, False
            f_act = contact(pa, va, k_con, c_con)
            if mode == OFF:
                f_comp = 0.0
            else:
                r0, r1, r2, r3, r4 = rows[mode]
                f_comp = r0 * p + r1 * v + r2 * pa + r3 * va + r4 * u
            if f_act > 0.0:
                touched = True
            if k * h >= due and not checked:  # the stop rule's check, before the record
                return (p, v, pa, va, u), mode, touched, k, f_act, f_comp, 0, False
            checked = False
            vs[k] = v
            fas[k] = f_act
            fcs[k] = f_comp
            F[k + n + 2] = f_act
            if undelayed != 0.0:  # the force rows hold lead_f f_act(t); u the last sample's part
                u = lead_prev * f_act
                gate = False
            else:
                f_mea = F[k + 2]
                u = lead_f * f_mea + lead_prev * F[k + 1]
                gate = gate_open(f_mea, db)
            if switches == 0.0:  # held: the gate and the clamp read the held samples only
                if (gate or by_force == 0.0) and not (clamp != 0.0 and u < 0.0):
                    mode = held_on
                else:
                    mode = OFF
            else:
                mode = mode_of(p, v, pa, va, u, gate, rows, law)
            a0, a1, a2, a3, a4, b0, b1, b2, b3, b4, g0, g1, g2, g3, g4, d0, d1, d2, d3, d4 = steps[
                mode
            ]
            p1 = a0 * p + a1 * v + a2 * pa + a3 * va + a4 * u
            v1 = b0 * p + b1 * v + b2 * pa + b3 * va + b4 * u
            pa1 = g0 * p + g1 * v + g2 * pa + g3 * va + g4 * u
            va1 = d0 * p + d1 * v + d2 * pa + d3 * va + d4 * u
            if switches != 0.0 and mode_of(p1, v1, pa1, va1, u, gate, rows, law) != mode:
                # the mode switches inside the tick: the caller locates the switch
                return (p, v, pa, va, u), mode, touched, k, f_act, f_comp, 2, gate
            p, v, pa, va = p1, v1, pa1, va1
            k += 1

    return ticks


def tick_law(loop) -> tuple[float, ...]:
    """The numbers the tick loop reads of a :class:`~hybridtable.loop.fast._Continuous`:
    ``(lead_f, lead_prev, k, c, dead band, by_force, clamp, undelayed, mdc, switches)``."""
    flags = (loop.by_force, loop.clamp, loop.undelayed, loop.mdc, loop.switches)
    numbers = (loop.lead_f, loop.lead_prev, loop.k, loop.c, loop.law.force_deadband_n)
    return numbers + tuple(float(f) for f in flags)


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
def corrects_function(motion_correction: bool, gate: str):
    """Whether the MDC term acts at the table position ``pa``
    (:meth:`~hybridtable.laws.compensation.CompensationLaw.corrects_motion`)."""
    law = CompensationLaw(motion_correction=motion_correction, gate=gate)
    return python_function(lambda pa: law.corrects_motion(pa > 0.0), ("pa",))


@functools.cache
def mode_function(gate: str, motion_correction: bool):
    """The mode rule (:func:`_mode`) over the traced laws, as plain Python."""
    return _mode(
        contact_function(), gate_function(gate), corrects_function(motion_correction, gate)
    )


#: The loops compiled in this process (inherited by its forked workers).
_COMPILED: dict[tuple[str, bool], Callable[..., Any]] = {}


def _compiled(gate: str, motion_correction: bool):
    key = (gate, motion_correction)
    if key not in _COMPILED:
        loop = _compile(gate, motion_correction)
        # numba compiles at the first call: one that stops at once, with the types
        # of every later call (the check is due at t = 0)
        zeros = np.zeros
        law = (0.0,) * 10
        loop((0.0,) * 5, OFF, False, zeros((8, 20)), zeros((8, 5)), law, zeros(4), zeros(2),
             zeros(2), zeros(2), 0, 0, 1.0, 0.0, False)  # fmt: skip
        _COMPILED[key] = loop
    return _COMPILED[key]


def compile_loops(variants) -> int:
    """Compile the tick loops of ``variants`` (``(gate, motion_correction)`` pairs)
    now, if numba is importable: a process about to fork its fitting workers
    compiles once for all of them. Returns how many were compiled."""
    if not compiled_available():
        return 0
    todo = [v for v in dict.fromkeys(variants) if v not in _COMPILED]
    for gate, motion_correction in todo:
        _compiled(gate, motion_correction)
    return len(todo)


def _compile(gate: str, motion_correction: bool):
    import numba

    contact = numba.njit(contact_function())
    gate_open = numba.njit(gate_function(gate))
    corrects = numba.njit(corrects_function(motion_correction, gate))
    mode_of = numba.njit(_mode(contact, gate_open, corrects))
    return numba.njit(_loop(mode_of, contact, gate_open))


@functools.cache
def _python(gate: str, motion_correction: bool):
    return _loop(mode_function(gate, motion_correction), contact_function(), gate_function(gate))


def tick_loop(
    gate: str, motion_correction: bool, compiled: bool | None = None
) -> tuple[Callable[..., Any], bool]:
    """The tick loop of a compensator with this ``gate`` and MDC switch, and
    whether it is compiled.

    ``compiled`` None: Python for a process's first :data:`COMPILE_AFTER_RUNS`
    calls, compiled after (if numba is importable). A compiled loop takes numpy
    arrays for ``F``, the records, the steps and the rows; the Python loop, lists
    (faster there).
    """
    global _runs
    if compiled is None:
        _runs += 1
        compiled = (gate, motion_correction) in _COMPILED or (
            _runs > COMPILE_AFTER_RUNS and compiled_available()
        )
    if compiled:
        return _compiled(gate, motion_correction), True
    return _python(gate, motion_correction), False
