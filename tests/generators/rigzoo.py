"""Rig zoo: an independent generator of recorded hybrid-table runs with hidden effects.

Written from the physics and the run format (``docs/run-format.md``) alone:
nothing here imports ``hybridtable`` or the other generators of this folder, so
a study built on it cannot be tuned to the model's own code.

Physics (what a run of a rig is)
--------------------------------
- **Table**: a second-order servo, ``p'' = w^2 (u - p) - 2 zeta w p'`` with the
  command ``u = p_des[k]`` held from tick k to tick k+1. Being linear with a
  held input, it is stepped *exactly* (matrix exponential of the augmented
  system) over the tick or over each of :data:`SUBSTEPS` sub-steps of it. At
  ``t = 0`` the table is at ``-initial_gap_m`` moving at the run's
  ``initial_velocity_m_per_s``.
- **Contact**: the other device is fixed at 0, so the penetration is the table
  (contact point) position ``q``; nominal force ``k q`` for ``q > 0``, else 0.
  No force acts back on the table (a stiff position servo).
- **Force sensor**: ``f_mea[k] = f(t_k - D) + noise`` with ``D`` the JSON's
  delay, a whole number of ticks (or, with the fractional-delay condition
  below, a fraction more; ``f = 0`` before ``t = 0``). Sensor dynamics (filters)
  act on a fine history of the force (``SUBSTEPS`` points per tick, filters
  discretised exactly for a piecewise-linear input); fractional delays read it
  by 4-point cubic interpolation.
- **Position sensor**: ``p_act[k] = p(t_k) + noise``.
- **Rig computer**: steps 2-4 of the format, on the noisy readings (step 3 by
  the rig's integrator, the format's semi-implicit Euler unless the
  integrator condition below says otherwise). At tick 0
  there is no earlier reading, so the SDC derivative is taken as 0 there; the
  MDC's ``p_des[-1]`` is the model's start ``-initial_gap_m``.
- **Noise**: white, AR(1) or AR(2), stationary from the first sample, with a
  marginal standard deviation ``sigma_f`` (force) / ``sigma_p`` (position).

When no effect is hidden and the noise is off, a run is the nominal model's
exactly (rounding aside). Three integration paths exist: a lean float loop for
tick-exact physics (nominal table, static contact law, whole-tick delay, no
sensor dynamics); a sub-stepped numpy path (linear tables stepped exactly,
filters, fractional delays, nominal or hidden, the base-excited table mode); and RK4 in floats
for the nonlinear tables (rate-limited servo; the optional loaded table mode,
on which the contact force acts).
On the physics they share they agree to rounding (tested), and halving the
sub-step changes a record by < 1e-4 of its range.

Hidden effects
--------------
Each hidden effect is a :class:`Hidden` with a dimensionless ``magnitude``
(``0`` = absent); :func:`physical_params` turns it into the law's physical
parameters (the laws are listed in :data:`EFFECTS`, one line each). Physics
effects are sized by :func:`size_effect`: bisection of the magnitude until
the nominal model's error (:func:`nominal_error`: recorded readings against
the recorded commands replayed through the nominal table, contact and sensor,
in units of the true noise std) reaches a target. :func:`magnitude_bounds`
keeps the magnitudes physically plausible; a set whose target needs more, or
whose sized rig misbehaves (diverges, does not separate, CoR out of
0.05-2), is drawn again from its seed (:func:`resolve`). Computer effects
(``mass_error``, ``lead_time_error``, ``compensator_stiffness_error``) do not
change the readings given the commands, so they get a relative size instead
(3-20 %, 10-40 %).

The library's names (``contact_damping`` ...) are what ``diagnose`` should
answer; the laws are this file's own. Effects outside the library carry a
``borderline`` note where a library effect (or a pair) could plausibly mimic
them; ``table_resonance`` does too. Its law is the brief's literal one (a
base-excited mode driven by the servo position, the contact point and the
position reading on the platform). A mode loaded by the contact force
(``shape["mass_ratio"] > 0``) is supported but not drawn: it reads mostly
as a series compliance.

Outside-library effects (12 kinds; * = borderline, see ``EFFECTS[n].borderline``)
--------------------------------------------------------------------------------
- ``contact_offset`` *: contact at q > p0 (preload / offset geometry);
  one run alone fits extra_delay + stiffness_error, several velocities do not.
- ``position_sensor_lag``: p_act read dp late (fractional ticks).
- ``position_sensor_bias``: constant offset on p_act.
- ``third_order_servo`` *: a first-order lag before the servo (table of a
  different order); shifts p_act and the force together.
- ``rate_limited_table``: the servo's velocity command is clipped.
- ``stiffness_drift`` *: k drifts over the session (run order), velocity
  order kept non-monotone so nonlinear_stiffness cannot follow it.
- ``quantized_force_sensor`` *: f_mea quantised (step well above the noise);
  noise-like, a noise estimate from the data may absorb it.
- ``asymmetric_friction`` *: direction-dependent friction = coulomb + a
  contact-only offset (the offset is not a library effect).
- ``load_dependent_gain`` **: f_read = f (1 + g f / f_ref); with no back-action
  this is a contact law change, nonlinear_stiffness mimics it closely.
- ``sensor_saturation``: f_read = min(f, f_sat).
- ``sensor_zero_drift``: a force offset ramping over each run.
- ``resonant_force_sensor`` *: an underdamped second-order force sensor; far
  above the contact it is a delay / first-order filter look-alike.

Rig conditions (not effects: properties of the rig the JSON states, or does not)
--------------------------------------------------------------------------------
Three conditions real rigs produce, each a field of :class:`Rig` (drawn by
:func:`draw_rig` on request), so each combines with any hidden effect and with
the others. A rig of the original zoo has none of them.

- **Zero deadband** (``Rig.deadband_n = 0``, the paper's own rig model): the
  gate ``f_mea <= 0`` then passes sensor noise in free flight, so ``f_comp``
  is the clamped noise (about half of the free-flight ticks non-zero, and the
  SDC / MDC terms with it) before and after the contact, and the model drifts.
  Noise-free it is the run with a tiny deadband.
- **Fractional nominal sensor delay** (``Rig.delay_frac``, a fraction of a
  tick added to ``delay_ticks``): the JSON's ``sensor_delay_s`` is
  ``(delay_ticks + delay_frac) h`` (e.g. 3.4 ms at 1 kHz, a real sensor's
  filter delay) and the physics reads the force that much late, by the same
  cubic interpolation of the fine force history as a fractional
  ``extra_delay`` (the sub-stepped path). :func:`nominal_replay` models it the
  same way, so a null set's nominal error stays the noise's.
- **The rig computer's integrator** (``Rig.integrator``, one of
  :data:`INTEGRATORS`; the JSON does not say which, a hidden property of the
  rig recorded in the set's truth): how step 3 of the format moves the
  spacecraft model with the force ``f_comp[k]`` held over the tick,
  ``a = -f_comp[k] / m``. Every rule gives ``v_new = v_old + a h``; they differ
  in the position (see :func:`model_step`):

  - ``semi_implicit_euler`` (the format's): ``x += v_new h`` = ``x + v_old h + a h^2``;
  - ``explicit_euler``: ``x += v_old h``, then ``v += a h``;
  - ``trapezoid``: ``x += (v_old + v_new) / 2 h`` = ``x + v_old h + a h^2 / 2``;
  - ``rk4``: classical RK4 on ``x' = v, v' = a`` with ``a`` constant over the
    tick. Its stages are ``v, v + a h/2, v + a h/2, v + a h`` for x and ``a``
    four times for v, so ``x += v_old h + a h^2 / 2`` and ``v += a h``: the
    exact solution for a held force, **the same update as ``trapezoid``** (to
    rounding; :data:`INTEGRATOR_EQUIVALENT` maps it to ``trapezoid``).

  Against the exact (trapezoid) positions, the semi-implicit ones lead by
  ``(h / 2) (v_k - v_0)`` and the explicit ones lag by as much: over a
  contact, explicit Euler acts as half a tick more delay than the exact rule
  (energy added, a higher CoR), semi-implicit Euler as half a tick less.
  Exactly: explicit Euler with a sensor delay of D ticks is the format's rule
  with D + 1 ticks, its velocity one tick early (``v_exp[k] = v_semi[k+1]``,
  the same commands ``p_des`` and, noise-free, ``f_mea[k] = f_mea'[k+1]``)
  when the compensation has no MDC term (the MDC's ``p_des[k-1] - p_act[k]``
  breaks the shift); tested. A record still tells them apart: its
  ``p_des`` steps by the previous tick's ``v_des``.

The study classes ``deadband0``, ``fractional_delay`` and ``integrator``
(:data:`CONDITION_CLASSES`) each draw sets of a rig with that condition and
otherwise like the other classes: a null or a single library effect (physics,
sized as a ``single``; or computer, sized as a ``computer``).
``SetSpec.truth()`` is the hidden effect (empty for a null) and
``SetSpec.condition()`` / the ``condition`` key of ``SetSpec.to_json()`` says
which condition applies (the integrator's rule and its equivalents).

Sets and the study
------------------
A :class:`SetSpec` is one rig, its noise, its runs (velocities, compensators,
lengths) and its hidden effects. :func:`draw_study` draws the study's sets
unsized (fast: only the nominal loop is simulated, to validate the rig);
:func:`resolve` sizes them and :func:`write_set` (which resolves first)
writes ``run<i>.csv/.json`` pairs. ``SetSpec.truth()`` is the set of effect
names expected (empty for nulls and for outside-library sets, whose right
answer is ``explained: false``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.signal import cont2discrete, lfilter, ss2tf, tf2ss

__all__ = [
    "COMPENSATORS",
    "EFFECTS",
    "LIBRARY_PHYSICS",
    "COMPUTER_EFFECTS",
    "OUTSIDE_EFFECTS",
    "CLASSES",
    "BASE_CLASSES",
    "CONDITION_CLASSES",
    "INTEGRATORS",
    "INTEGRATOR_EQUIVALENT",
    "DEFAULT_INTEGRATOR",
    "EffectDef",
    "Rig",
    "NoiseSpec",
    "Hidden",
    "Scales",
    "SetSpec",
    "RunRecord",
    "SizingError",
    "draw_rig",
    "draw_noise",
    "draw_shape",
    "magnitude_bounds",
    "draw_base",
    "draw_study",
    "make_hidden",
    "physical_params",
    "simulate_run",
    "model_step",
    "rig_with_delay",
    "simulate_set",
    "nominal_replay",
    "nominal_error",
    "set_error",
    "set_cor",
    "size_effect",
    "resolve",
    "write_run",
    "write_set",
    "read_set",
]

FORMAT = "hybridtable-run/1"
COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")
#: Sub-steps per tick of the fine path (history of the sensed force).
SUBSTEPS = 20
#: Longest run, in ticks.
MAX_TICKS = 3000
#: No-contact time kept after the separation, s.
QUIET_S = 0.2
#: The study's classes of the original zoo (their draws are fixed by the seed).
BASE_CLASSES = ("null", "single", "pair", "pair_cancel", "outside", "tiny", "computer")
#: Classes of a rig condition (zero deadband, fractional nominal delay, the
#: computer's integrator), each set a null or a single library effect.
CONDITION_CLASSES = ("deadband0", "fractional_delay", "integrator")
CLASSES = BASE_CLASSES + CONDITION_CLASSES
#: Rules by which the rig computer steps the spacecraft model (step 3 of the
#: format), the format's own first; see the module's docstring.
INTEGRATORS = ("semi_implicit_euler", "explicit_euler", "trapezoid", "rk4")
DEFAULT_INTEGRATOR = INTEGRATORS[0]
#: Each rule's class of rules that give the same update for a force held over
#: the tick (``rk4`` is exact for it, as is ``trapezoid``).
INTEGRATOR_EQUIVALENT = {
    "semi_implicit_euler": "semi_implicit_euler",
    "explicit_euler": "explicit_euler",
    "trapezoid": "trapezoid",
    "rk4": "trapezoid",
}


# --------------------------------------------------------------------------- #
# Effects
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class EffectDef:
    """A kind of hidden effect: its law (``magnitude`` is dimensionless, 0 =
    absent) and a first guess of the magnitude for sizing."""

    name: str
    library: bool
    kind: str  # "physics" | "computer"
    guess: float
    law: str
    borderline: str = ""


def _defs() -> dict[str, EffectDef]:
    lib, out = True, False
    phys, comp = "physics", "computer"
    rows = [
        # ---- library physics ----
        (
            "contact_damping",
            lib,
            phys,
            0.05,
            "f = max(k q + c q', 0) in contact; c = 2 mag sqrt(k m)",
            "",
        ),
        (
            "hunt_crossley",
            lib,
            phys,
            0.1,
            "f = max(k q (1 + alpha q'), 0); alpha = mag / v_ref",
            "",
        ),
        (
            "nonlinear_stiffness",
            lib,
            phys,
            0.05,
            "f = K q^n, n = 1 +- mag, K = k p_ref^(1-n) (the nominal force at p_ref)",
            "",
        ),
        ("stiffness_error", lib, phys, 0.05, "f = k (1 +- mag) q", ""),
        (
            "series_compliance",
            lib,
            phys,
            0.05,
            "f = k (q - s f), s = mag / k  (= a spring k / (1 + mag))",
            "",
        ),
        (
            "coulomb_friction",
            lib,
            phys,
            0.01,
            "f = max(k q + F sign(q'), 0) in contact; F = mag f_ref",
            "",
        ),
        (
            "sensor_filter",
            lib,
            phys,
            0.3,
            "first-order low-pass on the sensed force, tau = mag h",
            "",
        ),
        ("extra_delay", lib, phys, 0.3, "sensor delay D + d, d = mag h (fractional ticks)", ""),
        (
            "table_resonance",
            lib,
            phys,
            0.3,
            "contact point: a base-excited mode, q'' = wr^2 (p - q) + 2 zr wr (p' - q'),"
            " fr = f_table / mag, zr 0.02-0.1; the contact and p_act (a position"
            " measured on the platform) both see q. shape mass_ratio mu > 0 loads"
            " the mode with the contact force (q'' ... - f / (mu m)); not used in"
            " the study",
            "base-excited, at fr far above the contact the quasi-static lag"
            " q - p = -p''/wr^2 ~ f / (m wr^2) reads as a series compliance in"
            " the force; p_act (and the ringing) separates it. The loaded variant"
            " is mostly a series compliance in the force",
        ),
        ("force_bias", lib, phys, 1.0, "f_mea = f + b, b = +- mag sigma_f", ""),
        # ---- computer ----
        ("mass_error", lib, comp, 0.1, "the computer integrates with m (1 +- mag)", ""),
        ("lead_time_error", lib, comp, 0.2, "the computer's SDC lead time is L (1 +- mag)", ""),
        (
            "compensator_stiffness_error",
            lib,
            comp,
            0.2,
            "the computer's MDC stiffness is k (1 +- mag)",
            "",
        ),
        # ---- outside the library ----
        (
            "contact_offset",
            out,
            phys,
            0.02,
            "contact at q > p0: f = k (q - p0), p0 = mag p_ref",
            "an extra_delay + stiffness_error fits one run; the onset shift"
            " p0/v differs with the approach velocity, so several runs separate it",
        ),
        ("position_sensor_lag", out, phys, 0.3, "p_act[k] = p(t_k - dp), dp = mag h", ""),
        ("position_sensor_bias", out, phys, 1.0, "p_act = p + bp, bp = +- mag sigma_p", ""),
        (
            "third_order_servo",
            out,
            phys,
            0.5,
            "a first-order lag tau_s = mag h between the command and the servo",
            "a table-side effect that shifts p_act and the force together; a"
            " library table effect that also moves p_act could partly mimic it",
        ),
        (
            "rate_limited_table",
            out,
            phys,
            0.1,
            "velocity command clipped: p'' = 2 zeta w (clip(w (u - p) / (2 zeta), +-vmax) - p'),"
            " vmax = v_ref / (1 + mag)",
            "",
        ),
        (
            "stiffness_drift",
            out,
            phys,
            0.05,
            "k drifts linearly over the session (run index order): k (1 + drift (s - 1/2)),"
            " s = (run + t / T_run) / n_runs",
            "stiffness_error fits the mean k; with run order not monotone in"
            " velocity nonlinear_stiffness cannot follow the drift",
        ),
        (
            "quantized_force_sensor",
            out,
            phys,
            5.0,
            "f_mea = q round((f + noise) / q), q = mag sigma_f",
            "the quantisation error is noise-like; a diagnosis that estimates"
            " the noise from the data may absorb it",
        ),
        (
            "asymmetric_friction",
            out,
            phys,
            0.01,
            "f = k q + F_in (q' > 0), k q - r F_in (q' < 0); = coulomb"
            " (1+r)/2 F_in + a contact-only offset (1-r)/2 F_in",
            "coulomb_friction explains the symmetric half; the contact-only"
            " offset is not a library effect but a soft-at-onset nonlinear"
            " stiffness (n < 1) may partly mimic it",
        ),
        (
            "load_dependent_gain",
            out,
            phys,
            0.05,
            "f_mea = f (1 + g f / f_ref) + noise",
            "a static map of the force with no back-action equals a contact"
            " law change: nonlinear_stiffness mimics it closely (only the"
            " spread of approach velocities separates the shapes)",
        ),
        (
            "sensor_saturation",
            out,
            phys,
            0.05,
            "f_mea = min(f, f_sat) + noise, f_sat = (1 - mag) f_ref",
            "",
        ),
        (
            "sensor_zero_drift",
            out,
            phys,
            1.0,
            "f_mea = f + b (2 t / T_run - 1), b = +- mag sigma_f (a ramp over each run)",
            "",
        ),
        (
            "resonant_force_sensor",
            out,
            phys,
            0.3,
            "second-order sensor ws^2 / (s^2 + 2 zs ws s + ws^2), ws = 1 / (mag h), zs 0.03-0.12",
            "at small mag (ws far above the contact) it acts as a pure delay"
            " 2 zs / ws: extra_delay / sensor_filter mimic it; the ringing"
            " separates it at larger mag",
        ),
    ]
    return {r[0]: EffectDef(*r) for r in rows}


EFFECTS: dict[str, EffectDef] = _defs()
LIBRARY_PHYSICS = tuple(n for n, e in EFFECTS.items() if e.library and e.kind == "physics")
COMPUTER_EFFECTS = tuple(n for n, e in EFFECTS.items() if e.kind == "computer")
OUTSIDE_EFFECTS = tuple(n for n, e in EFFECTS.items() if not e.library)


# --------------------------------------------------------------------------- #
# Data classes
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class Rig:
    """What the JSON of every run of a set says (besides compensator, velocity, id).

    The rig's true physics is this unless a :class:`Hidden` effect says otherwise.
    ``delay_frac`` (0 <= it < 1, default 0) is a fraction of a tick added to
    the nominal delay ``delay_ticks`` (the JSON states the sum);
    ``integrator`` (one of :data:`INTEGRATORS`) is how the rig computer steps
    the spacecraft model, which the JSON does not state.
    """

    sample_rate_hz: int
    mass_kg: float
    stiffness_n_per_m: float
    delay_ticks: int
    table_hz: float
    table_zeta: float
    deadband_n: float
    lead_time_s: float
    initial_gap_m: float
    delay_frac: float = 0.0
    integrator: str = DEFAULT_INTEGRATOR

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator {self.integrator!r} is not one of {INTEGRATORS}")
        if not 0.0 <= self.delay_frac < 1.0:
            raise ValueError(f"delay_frac {self.delay_frac} is not in [0, 1)")

    @property
    def h(self) -> float:
        return 1.0 / self.sample_rate_hz

    @property
    def delay_ticks_exact(self) -> float:
        """The nominal (and true) sensor delay in ticks, fraction included."""
        return self.delay_ticks + self.delay_frac

    @property
    def delay_ticks_ceil(self) -> int:
        """Whole ticks that cover the delay."""
        return self.delay_ticks + (1 if self.delay_frac > 0.0 else 0)

    @property
    def sensor_delay_s(self) -> float:
        if self.delay_frac:
            return round(self.delay_ticks_exact / self.sample_rate_hz, 12)
        return self.delay_ticks / self.sample_rate_hz

    def conditions(self) -> dict:
        """The rig's conditions beyond the original zoo's (empty if none):
        ``zero_deadband``, ``fractional_delay`` (with the delay in ticks) and a
        non-default ``integrator`` (with the rules equivalent to it)."""
        out: dict = {}
        if self.deadband_n == 0.0:
            out["zero_deadband"] = True
        if self.delay_frac:
            out["fractional_delay"] = True
            out["sensor_delay_ticks"] = self.delay_ticks_exact
        if self.integrator != DEFAULT_INTEGRATOR:
            out["integrator"] = self.integrator
            out["integrator_equivalent"] = sorted(
                n
                for n in INTEGRATORS
                if INTEGRATOR_EQUIVALENT[n] == INTEGRATOR_EQUIVALENT[self.integrator]
            )
        return out

    def __repr__(self) -> str:
        # The dataclass repr, the conditions' fields only where not the
        # defaults (a rig of the original zoo reads as it always did: the
        # redraw reasons in a set's info quote it).
        body = ", ".join(f"{k}={v!r}" for k, v in self.public_dict().items())
        return f"{type(self).__qualname__}({body})"

    def public_dict(self) -> dict:
        """The fields, the conditions' only where they are not the defaults
        (a rig of the original zoo gives the dict it always gave)."""
        d = dict(self.__dict__)
        if not self.delay_frac:
            d.pop("delay_frac")
        if self.integrator == DEFAULT_INTEGRATOR:
            d.pop("integrator")
        return d

    @property
    def contact_hz(self) -> float:
        return math.sqrt(self.stiffness_n_per_m / self.mass_kg) / (2 * math.pi)

    @property
    def contact_time_s(self) -> float:
        return math.pi * math.sqrt(self.mass_kg / self.stiffness_n_per_m)

    def run_json(self, run_id: str, compensator: str, velocity: float) -> dict:
        return {
            "format": FORMAT,
            "run_id": run_id,
            "sample_rate_hz": self.sample_rate_hz,
            "spacecraft_mass_kg": self.mass_kg,
            "contact_stiffness_n_per_m": self.stiffness_n_per_m,
            "sensor_delay_s": self.sensor_delay_s,
            "table_natural_frequency_hz": self.table_hz,
            "table_damping_ratio": self.table_zeta,
            "compensator": compensator,
            "lead_time_s": self.lead_time_s,
            "initial_gap_m": self.initial_gap_m,
            "initial_velocity_m_per_s": velocity,
            "force_deadband_n": self.deadband_n,
        }


def rig_with_delay(rig: Rig, delay_s: float) -> Rig:
    """``rig`` with the nominal (and true) sensor delay ``delay_s``: whole ticks
    plus a fraction (a delay within 1e-9 tick of a whole number is whole)."""
    d = delay_s * rig.sample_rate_hz
    nd = round(d)
    if abs(d - nd) < 1e-9:
        return replace(rig, delay_ticks=int(nd), delay_frac=0.0)
    nd = math.floor(d)
    return replace(rig, delay_ticks=int(nd), delay_frac=round(d - nd, 12))


@dataclass(frozen=True)
class NoiseSpec:
    """Measurement noise: ``kind`` white / ar1 / ar2, AR coefficients
    ``e[k] = a1 e[k-1] + a2 e[k-2] + w[k]`` and the marginal std of each channel."""

    kind: str
    ar: tuple[float, ...]
    sigma_f: float
    sigma_p: float

    def lag1(self) -> float:
        """Lag-1 autocorrelation of the noise."""
        if not self.ar:
            return 0.0
        if len(self.ar) == 1:
            return self.ar[0]
        a1, a2 = self.ar
        return a1 / (1.0 - a2)

    def unit_series(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Stationary series of unit marginal variance."""
        if not self.ar:
            return rng.standard_normal(n)
        burn = 2000
        w = rng.standard_normal(n + burn)
        if len(self.ar) == 1:
            phi = self.ar[0]
            var = 1.0 / (1.0 - phi * phi)
            e = lfilter([1.0], [1.0, -phi], w)
        else:
            a1, a2 = self.ar
            var = (1.0 - a2) / ((1.0 + a2) * ((1.0 - a2) ** 2 - a1 * a1))
            e = lfilter([1.0], [1.0, -a1, -a2], w)
        return e[burn:] / math.sqrt(var)

    def draw(self, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
        return self.sigma_f * self.unit_series(rng, n), self.sigma_p * self.unit_series(rng, n)


@dataclass(frozen=True)
class Scales:
    """Reference sizes of a set that effect magnitudes are measured in."""

    k: float
    m: float
    h: float
    lead: float
    f_table: float
    v_ref: float
    p_ref: float
    f_ref: float
    sigma_f: float
    sigma_p: float

    @classmethod
    def of(cls, rig: Rig, velocities, noise: NoiseSpec) -> Scales:
        v = float(max(velocities))
        k, m = rig.stiffness_n_per_m, rig.mass_kg
        return cls(
            k=k,
            m=m,
            h=rig.h,
            lead=rig.lead_time_s,
            f_table=rig.table_hz,
            v_ref=v,
            p_ref=v * math.sqrt(m / k),
            f_ref=v * math.sqrt(m * k),
            sigma_f=noise.sigma_f,
            sigma_p=noise.sigma_p,
        )


@dataclass(frozen=True)
class Hidden:
    """A hidden effect. ``magnitude`` None: to be sized to ``target_error``."""

    name: str
    magnitude: float | None = None
    shape: dict = field(default_factory=dict)
    target_error: float | None = None

    @property
    def library(self) -> bool:
        return EFFECTS[self.name].library

    @property
    def kind(self) -> str:
        return EFFECTS[self.name].kind

    def params(self, scales: Scales) -> dict[str, float]:
        if self.magnitude is None:
            raise SizingError(f"{self.name} is not sized yet")
        return physical_params(self.name, self.magnitude, self.shape, scales)

    def to_json(self, scales: Scales | None = None) -> dict:
        out = {
            "name": self.name,
            "library": self.library,
            "kind": self.kind,
            "magnitude": self.magnitude,
            "shape": dict(self.shape),
            "target_error": self.target_error,
            "law": EFFECTS[self.name].law,
        }
        if scales is not None and self.magnitude is not None:
            out["params"] = self.params(scales)
        if EFFECTS[self.name].borderline:
            out["borderline"] = EFFECTS[self.name].borderline
        return out


@dataclass(frozen=True)
class SetSpec:
    """One set: a rig, its noise, its runs and its hidden effects."""

    set_id: str
    label: str
    rig: Rig
    noise: NoiseSpec
    velocities: tuple[float, ...]
    compensators: tuple[str, ...]
    n_ticks: tuple[int, ...]
    seed: int
    hidden: tuple[Hidden, ...] = ()
    info: dict = field(default_factory=dict)

    @property
    def scales(self) -> Scales:
        return Scales.of(self.rig, self.velocities, self.noise)

    @property
    def run_stem(self) -> str:
        """Stem of the runs' ``run_id``: the set id for the original classes
        (as before), a neutral name for the condition classes, whose run JSON
        must not tell the hidden effect or the computer's integrator."""
        if self.label in CONDITION_CLASSES:
            return f"rig{self.seed:010d}"
        return self.set_id

    @property
    def sized(self) -> bool:
        return all(h.magnitude is not None for h in self.hidden)

    def truth(self) -> set[str]:
        """Effect names a right diagnosis names (outside-library sets: none,
        the right answer is an unexplained verdict)."""
        if self.label in ("null", "outside"):
            return set()
        return {h.name for h in self.hidden}

    @property
    def expects_unexplained(self) -> bool:
        return self.label == "outside"

    def condition(self) -> dict:
        """Which rig condition applies (:meth:`Rig.conditions`, empty for a rig
        of the original zoo); ``integrator`` is always given once any
        condition is (the format's rule unless the rig's differs), so a study
        can score whether a tool named the rule."""
        out = self.rig.conditions()
        if out or self.label in CONDITION_CLASSES:
            out.setdefault("integrator", self.rig.integrator)
            out.setdefault(
                "integrator_equivalent",
                sorted(
                    n
                    for n in INTEGRATORS
                    if INTEGRATOR_EQUIVALENT[n] == INTEGRATOR_EQUIVALENT[self.rig.integrator]
                ),
            )
        return out

    def to_json(self) -> dict:
        sc = self.scales
        out = {
            "set_id": self.set_id,
            "label": self.label,
            "truth": sorted(self.truth()),
            "rig": self.rig.public_dict() | {"contact_hz": self.rig.contact_hz},
            "noise": {
                "kind": self.noise.kind,
                "ar": list(self.noise.ar),
                "sigma_f": self.noise.sigma_f,
                "sigma_p": self.noise.sigma_p,
            },
            "velocities": list(self.velocities),
            "compensators": list(self.compensators),
            "n_ticks": list(self.n_ticks),
            "seed": self.seed,
            "hidden": [h.to_json(sc) for h in self.hidden],
            "info": dict(self.info),
        }
        cond = self.condition()
        if cond:
            out["condition"] = cond
        return out


@dataclass
class RunRecord:
    """A simulated (or read back) run: its JSON, its columns, and the truth."""

    meta: dict
    time_s: np.ndarray
    p_des: np.ndarray
    p_act: np.ndarray
    f_mea: np.ndarray
    f_comp: np.ndarray
    v_des: np.ndarray
    penetration: np.ndarray | None = None
    force: np.ndarray | None = None
    diverged: bool = False

    @property
    def cor(self) -> float:
        return -float(self.v_des[-1]) / float(self.meta["initial_velocity_m_per_s"])

    def contact_ticks(self) -> np.ndarray:
        if self.penetration is None:
            raise ValueError("no truth in a run read back")
        return np.flatnonzero(self.penetration > 0)


class SizingError(RuntimeError):
    """An effect could not be sized (or is not sized yet)."""


# --------------------------------------------------------------------------- #
# Parameters of the effects
# --------------------------------------------------------------------------- #
def physical_params(name: str, mag: float, shape: dict, sc: Scales) -> dict[str, float]:
    """Physical parameters of effect ``name`` at magnitude ``mag``."""
    s = float(shape.get("sign", 1.0))
    twopi = 2 * math.pi
    if name == "contact_damping":
        return {"c_n_s_per_m": 2 * mag * math.sqrt(sc.k * sc.m)}
    if name == "hunt_crossley":
        return {"alpha_s_per_m": mag / sc.v_ref}
    if name == "nonlinear_stiffness":
        n = 1.0 + s * mag
        return {"n": n, "K": sc.k * sc.p_ref ** (1.0 - n)}
    if name == "stiffness_error":
        return {"k_true_n_per_m": sc.k * (1.0 + s * mag)}
    if name == "series_compliance":
        return {"s_m_per_n": mag / sc.k}
    if name == "coulomb_friction":
        return {"F_n": mag * sc.f_ref}
    if name == "sensor_filter":
        return {"tau_s": mag * sc.h}
    if name == "extra_delay":
        return {"d_s": mag * sc.h}
    if name == "table_resonance":
        return {
            "fr_hz": sc.f_table / mag,
            "zeta_r": float(shape.get("zeta", 0.05)),
            # 0: base-excited (the contact force does not load the mode).
            "m_r_kg": float(shape.get("mass_ratio", 0.0)) * sc.m,
        }
    if name == "force_bias":
        return {"b_n": s * mag * sc.sigma_f}
    if name == "mass_error":
        return {"m_used_kg": sc.m * (1.0 + s * mag)}
    if name == "lead_time_error":
        return {"lead_used_s": sc.lead * (1.0 + s * mag)}
    if name == "compensator_stiffness_error":
        return {"k_used_n_per_m": sc.k * (1.0 + s * mag)}
    if name == "contact_offset":
        return {"p0_m": mag * sc.p_ref}
    if name == "position_sensor_lag":
        return {"dp_s": mag * sc.h}
    if name == "position_sensor_bias":
        return {"bp_m": s * mag * sc.sigma_p}
    if name == "third_order_servo":
        return {"tau_servo_s": mag * sc.h}
    if name == "rate_limited_table":
        return {"vmax_m_per_s": sc.v_ref / (1.0 + mag)}
    if name == "stiffness_drift":
        return {"drift": s * mag}
    if name == "quantized_force_sensor":
        return {"q_n": mag * sc.sigma_f}
    if name == "asymmetric_friction":
        return {"F_in_n": mag * sc.f_ref, "r": float(shape.get("ratio", 0.0))}
    if name == "load_dependent_gain":
        return {"g": s * mag, "f_ref_n": sc.f_ref}
    if name == "sensor_saturation":
        return {"f_sat_n": (1.0 - mag) * sc.f_ref}
    if name == "sensor_zero_drift":
        return {"b_n": s * mag * sc.sigma_f}
    if name == "resonant_force_sensor":
        return {"fs_hz": 1.0 / (twopi * mag * sc.h), "zeta_s": float(shape.get("zeta", 0.1))}
    raise KeyError(name)


def magnitude_bounds(hidden: Hidden, sc: Scales) -> tuple[float, float]:
    """Range of a magnitude kept physically plausible (sizing beyond it
    raises :class:`SizingError`, and :func:`resolve` draws another rig)."""
    name = hidden.name
    h = sc.h
    wc = sc.k**0.5 / sc.m**0.5
    ms20 = 0.02 / h  # 20 ms in ticks
    b = {
        "contact_damping": (1e-4, 1.0),
        "hunt_crossley": (1e-4, 3.0),
        "nonlinear_stiffness": (1e-4, 1.0 if hidden.shape.get("sign", 1.0) > 0 else 0.5),
        "stiffness_error": (1e-4, 0.5),
        "series_compliance": (1e-4, 1.0),
        "coulomb_friction": (1e-5, 0.3),
        "sensor_filter": (1e-3, ms20),
        "extra_delay": (1e-3, ms20),
        "table_resonance": (1e-3, 0.97),
        "force_bias": (1e-3, 50.0),
        "mass_error": (0.0, 0.5),
        "lead_time_error": (0.0, 0.8),
        "compensator_stiffness_error": (0.0, 0.8),
        "contact_offset": (1e-4, 0.5),
        "position_sensor_lag": (1e-3, ms20),
        "position_sensor_bias": (1e-3, 50.0),
        "third_order_servo": (1e-3, ms20),
        "rate_limited_table": (1e-4, 3.0),
        "stiffness_drift": (1e-4, 1.0),
        "quantized_force_sensor": (1e-2, 200.0),
        "asymmetric_friction": (1e-5, 0.3),
        "load_dependent_gain": (1e-4, 1.0),
        "sensor_saturation": (1e-4, 0.8),
        "sensor_zero_drift": (1e-3, 50.0),
        "resonant_force_sensor": (1e-3, min(20.0, 1.0 / (3.0 * wc * h))),
    }
    return b[name]


def draw_shape(name: str, rng: np.random.Generator) -> dict:
    """The fixed, non-scaled choices of an effect (sign, damping ...)."""
    sign = float(rng.choice([-1.0, 1.0]))
    if name in ("nonlinear_stiffness",):
        return {"sign": 1.0 if rng.random() < 0.6 else -1.0}
    if name in (
        "stiffness_error",
        "force_bias",
        "mass_error",
        "lead_time_error",
        "compensator_stiffness_error",
        "position_sensor_bias",
        "stiffness_drift",
        "load_dependent_gain",
        "sensor_zero_drift",
    ):
        return {"sign": sign}
    if name == "table_resonance":
        return {
            "zeta": float(rng.uniform(0.02, 0.1)),
            "mass_ratio": 0.0,
        }
    if name == "resonant_force_sensor":
        return {"zeta": float(rng.uniform(0.03, 0.12))}
    if name == "asymmetric_friction":
        return {"ratio": float(rng.uniform(0.0, 0.3))}
    return {}


def make_hidden(
    name: str,
    rng: np.random.Generator,
    *,
    magnitude: float | None = None,
    target_error: float | None = None,
) -> Hidden:
    return Hidden(name, magnitude, draw_shape(name, rng), target_error)


# --------------------------------------------------------------------------- #
# The model of one run's physics
# --------------------------------------------------------------------------- #
def _foh_filter(num, den, dt):
    """Exact discretisation of a SISO filter for a piecewise-linear input."""
    a, b, c, d = tf2ss(num, den)
    ad, bd, cd, dd, _ = cont2discrete((a, b, c, d), dt, method="foh")
    nd_, dd_ = ss2tf(ad, bd, cd, dd)
    return np.atleast_1d(np.asarray(nd_)[0]).astype(float), np.asarray(dd_, float)


def _expm(m: np.ndarray) -> np.ndarray:
    """Matrix exponential of a small matrix (scaling and squaring of a Taylor
    series; scipy's expm is needlessly slow on these tiny augmented systems)."""
    norm = float(np.max(np.sum(np.abs(m), axis=1)))
    s = max(0, math.ceil(math.log2(norm)) + 3) if norm > 0 else 0
    a = m / 2.0**s
    term = np.eye(m.shape[0])
    out = term.copy()
    for i in range(1, 20):
        term = term @ a / i
        out = out + term
    for _ in range(s):
        out = out @ out
    return out


def _lti_step(a: np.ndarray, b: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """Phi, Gamma of x' = A x + B u with u held over tau."""
    n = a.shape[0]
    m = np.zeros((n + 1, n + 1))
    m[:n, :n] = a
    m[:n, n] = b
    e = _expm(m * tau)
    return e[:n, :n], e[:n, n]


class _Physics:
    """The true physics and the rig computer of one run (built from effects)."""

    def __init__(self, rig: Rig, effects: dict[str, dict], run_index: int, n_runs: int):
        k = rig.stiffness_n_per_m
        self.rig = rig
        self.k_lin = k
        self.nonlin: tuple[float, float] | None = None
        self.p0 = 0.0
        self.alpha = 0.0
        self.c = 0.0
        self.F = 0.0
        self.F_in = 0.0
        self.F_out = 0.0
        self.drift = 0.0
        self.run_index = run_index
        self.n_runs = n_runs
        self.table = "nominal"
        self.table_par: dict = {}
        self.filters: list[tuple[str, tuple]] = []
        self.extra_delay = 0.0
        self.gain_g = 0.0
        self.f_ref = 1.0
        self.f_sat = math.inf
        self.bias = 0.0
        self.zdrift = 0.0
        self.quant = 0.0
        self.pos_lag = 0.0
        self.pos_bias = 0.0
        self.m_used = rig.mass_kg
        self.L_used = rig.lead_time_s
        self.K_used = k
        for name, p in effects.items():
            if name == "stiffness_error":
                self.k_lin = p["k_true_n_per_m"]
            elif name == "nonlinear_stiffness":
                self.nonlin = (p["K"], p["n"])
            elif name == "contact_damping":
                self.c = p["c_n_s_per_m"]
            elif name == "hunt_crossley":
                self.alpha = p["alpha_s_per_m"]
            elif name == "coulomb_friction":
                self.F = p["F_n"]
            elif name == "sensor_filter":
                self.filters.append(("lp1", (p["tau_s"],)))
            elif name == "extra_delay":
                self.extra_delay += p["d_s"]
            elif name == "table_resonance":
                self.table = "resonance_loaded" if p["m_r_kg"] > 0 else "resonance"
                self.table_par = {
                    "wr": 2 * math.pi * p["fr_hz"],
                    "zr": p["zeta_r"],
                    "m_r": p["m_r_kg"],
                }
            elif name == "force_bias":
                self.bias += p["b_n"]
            elif name == "mass_error":
                self.m_used = p["m_used_kg"]
            elif name == "lead_time_error":
                self.L_used = p["lead_used_s"]
            elif name == "compensator_stiffness_error":
                self.K_used = p["k_used_n_per_m"]
            elif name == "contact_offset":
                self.p0 = p["p0_m"]
            elif name == "position_sensor_lag":
                self.pos_lag = p["dp_s"]
            elif name == "position_sensor_bias":
                self.pos_bias = p["bp_m"]
            elif name == "third_order_servo":
                self.table = "third"
                self.table_par = {"tau": p["tau_servo_s"]}
            elif name == "rate_limited_table":
                self.table = "ratelimit"
                self.table_par = {"vmax": p["vmax_m_per_s"]}
            elif name == "stiffness_drift":
                self.drift = p["drift"]
            elif name == "quantized_force_sensor":
                self.quant = p["q_n"]
            elif name == "asymmetric_friction":
                self.F_in = p["F_in_n"]
                self.F_out = p["r"] * p["F_in_n"]
            elif name == "load_dependent_gain":
                self.gain_g = p["g"]
                self.f_ref = p["f_ref_n"]
            elif name == "sensor_saturation":
                self.f_sat = p["f_sat_n"]
            elif name == "sensor_zero_drift":
                self.zdrift = p["b_n"]
            elif name == "resonant_force_sensor":
                self.filters.append(("res2", (2 * math.pi * p["fs_hz"], p["zeta_s"])))
            elif name == "series_compliance":
                pass  # below, once the spring is known
            else:
                raise KeyError(name)
        if "series_compliance" in effects:
            s = effects["series_compliance"]["s_m_per_n"]
            if self.nonlin is not None:
                raise ValueError("series_compliance with nonlinear_stiffness is not supported")
            self.k_lin = self.k_lin / (1.0 + self.k_lin * s)
        self.fine = (
            self.table != "nominal"
            or bool(self.filters)
            or self.extra_delay > 0.0
            or self.pos_lag > 0.0
            or rig.delay_frac > 0.0
        )

    # ---- contact law -------------------------------------------------------
    def _k_at(self, t: float, t_run: float) -> float:
        if self.drift == 0.0:
            return self.k_lin
        s = (self.run_index + t / t_run) / self.n_runs
        return self.k_lin * (1.0 + self.drift * (s - 0.5))

    def law(self, q: float, qd: float, t: float, t_run: float) -> float:
        z = q - self.p0
        if z <= 0.0:
            return 0.0
        if self.nonlin is not None:
            fs = self.nonlin[0] * z ** self.nonlin[1]
        else:
            fs = self._k_at(t, t_run) * z
        f = fs
        if self.alpha:
            f *= 1.0 + self.alpha * qd
        if self.c:
            f += self.c * qd
        if qd > 0.0:
            f += self.F + self.F_in
        elif qd < 0.0:
            f -= self.F + self.F_out
        return f if f > 0.0 else 0.0

    def law_vec(self, q: np.ndarray, qd: np.ndarray, t: np.ndarray, t_run: float) -> np.ndarray:
        z = q - self.p0
        inside = z > 0.0
        zc = np.where(inside, z, 0.0)
        if self.nonlin is not None:
            f = self.nonlin[0] * zc ** self.nonlin[1]
        elif self.drift:
            s = (self.run_index + t / t_run) / self.n_runs
            f = self.k_lin * (1.0 + self.drift * (s - 0.5)) * zc
        else:
            f = self.k_lin * zc
        if self.alpha:
            f = f * (1.0 + self.alpha * qd)
        if self.c:
            f = f + self.c * qd
        if self.F or self.F_in or self.F_out:
            f = f + np.where(qd > 0.0, self.F + self.F_in, 0.0)
            f = f - np.where(qd < 0.0, self.F + self.F_out, 0.0)
        return np.where(inside, np.maximum(f, 0.0), 0.0)

    # ---- sensor maps -------------------------------------------------------
    def read_force(self, s: float, t: float, t_run: float) -> float:
        if self.gain_g:
            s = s * (1.0 + self.gain_g * s / self.f_ref)
        if s > self.f_sat:
            s = self.f_sat
        return s + self.bias + (self.zdrift * (2.0 * t / t_run - 1.0) if self.zdrift else 0.0)

    # ---- table -------------------------------------------------------------
    def table_lti(self, v0: float):
        """A, B, initial state and the rows of (encoder, contact point, its rate)."""
        r = self.rig
        w = 2 * math.pi * r.table_hz
        z = r.table_zeta
        g = r.initial_gap_m
        if self.table == "nominal":
            a = np.array([[0.0, 1.0], [-w * w, -2 * z * w]])
            b = np.array([0.0, w * w])
            return a, b, np.array([-g, v0]), (0, 0, 1)
        if self.table == "resonance":
            wr, zr = self.table_par["wr"], self.table_par["zr"]
            a = np.array(
                [
                    [0.0, 1.0, 0.0, 0.0],
                    [-w * w, -2 * z * w, 0.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                    [wr * wr, 2 * zr * wr, -wr * wr, -2 * zr * wr],
                ]
            )
            b = np.array([0.0, w * w, 0.0, 0.0])
            # p_act is measured on the platform, at the contact point.
            return a, b, np.array([-g, v0, -g, v0]), (2, 2, 3)
        if self.table == "third":
            tau = self.table_par["tau"]
            a = np.array([[-1.0 / tau, 0.0, 0.0], [0.0, 0.0, 1.0], [w * w, -w * w, -2 * z * w]])
            b = np.array([1.0 / tau, 0.0, 0.0])
            return a, b, np.array([-g + 2 * z * v0 / w, -g, v0]), (1, 1, 2)
        raise ValueError(self.table)


def _interp(arr: np.ndarray, r: float, filled: int) -> float:
    """Value of the fine history at fractional index r (cubic, linear at the edge)."""
    i = math.floor(r)
    f = r - i
    if f < 1e-9:
        return float(arr[i])
    if f > 1.0 - 1e-9:
        return float(arr[i + 1])
    if i + 2 > filled or i < 1:
        return float(arr[i] + f * (arr[i + 1] - arr[i]))
    ym, y0, y1, y2 = arr[i - 1], arr[i], arr[i + 1], arr[i + 2]
    return float(
        -f * (f - 1) * (f - 2) / 6 * ym
        + (f + 1) * (f - 1) * (f - 2) / 2 * y0
        - (f + 1) * f * (f - 2) / 2 * y1
        + (f + 1) * f * (f - 1) / 6 * y2
    )


def _noise_arrays(noise: NoiseSpec | None, seed, n: int):
    if noise is None:
        return np.zeros(n), np.zeros(n)
    return noise.draw(np.random.default_rng(seed), n)


def simulate_run(
    rig: Rig,
    effects: dict[str, dict] | None,
    velocity: float,
    compensator: str,
    n_ticks: int,
    *,
    noise: NoiseSpec | None = None,
    seed=0,
    run_index: int = 0,
    n_runs: int = 1,
    run_id: str = "run",
    force_fine: bool = False,
) -> RunRecord:
    """Simulate one run of ``rig`` with the hidden ``effects`` (name -> physical
    parameters, see :func:`physical_params`) and measurement ``noise`` (None:
    noise-free). ``seed`` seeds the noise (any numpy seed, e.g. ``[set, run]``).
    """
    if compensator not in COMPENSATORS:
        raise ValueError(compensator)
    ph = _Physics(rig, dict(effects or {}), run_index, n_runs)
    nf, npos = _noise_arrays(noise, seed, n_ticks)
    if ph.fine or force_fine:
        out = _loop_fine(ph, velocity, compensator, n_ticks, nf, npos)
    else:
        out = _loop_fast(ph, velocity, compensator, n_ticks, nf, npos)
    meta = rig.run_json(run_id, compensator, velocity)
    return RunRecord(meta=meta, **out)


def _computer_flags(compensator: str) -> tuple[bool, bool]:
    return compensator in ("SDC", "SDMDC"), compensator in ("MDC", "SDMDC")


def _compensate(f_mea, f_prev, p_act, u_prev, db, sdc, mdc, lead, kc, h) -> float:
    """Step 2 of the format: deadband, lead (SDC), stiffness (MDC), clamp at 0."""
    if f_mea <= db:
        return 0.0
    fc = f_mea
    if sdc:
        fc += lead * (f_mea - f_prev) / h
    if mdc:
        fc += kc * (u_prev - p_act)
    return fc if fc > 0.0 else 0.0


def model_step(rule: str, x: float, v: float, fc: float, m: float, h: float) -> tuple[float, float]:
    """Step 3 of the format by the rule ``rule`` (one of :data:`INTEGRATORS`):
    the spacecraft model ``x' = v, v' = -fc / m`` over one tick ``h`` with the
    compensated force ``fc`` held. Returns the new ``(x, v)``.

    - ``semi_implicit_euler``: ``v += a h``, then ``x += v h`` (the format's);
    - ``explicit_euler``: ``x += v h``, then ``v += a h``;
    - ``trapezoid``: ``v += a h``, ``x += (v_old + v_new) / 2 h``;
    - ``rk4``: classical RK4 with the force held; for the constant
      acceleration it is exact, ``x += v_old h + a h^2 / 2``, ``v += a h``:
      the same update as ``trapezoid`` (to rounding).
    """
    if rule == "semi_implicit_euler":
        v += -fc / m * h
        x += v * h
        return x, v
    a = -fc / m
    if rule == "explicit_euler":
        return x + v * h, v + a * h
    if rule == "trapezoid":
        v_new = v + a * h
        return x + 0.5 * (v + v_new) * h, v_new
    if rule == "rk4":
        hh = 0.5 * h
        k1x, k1v = v, a
        k2x, k2v = v + hh * k1v, a
        k3x, k3v = v + hh * k2v, a
        k4x, k4v = v + h * k3v, a
        return (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    raise ValueError(rule)


def _loop_fast(ph: _Physics, v0: float, comp: str, n: int, nf, npos) -> dict:
    rig = ph.rig
    h = rig.h
    nd = rig.delay_ticks
    t_run = n * h
    a, b, x0, _ = ph.table_lti(v0)
    phi, gam = _lti_step(a, b, h)
    a11, a12, a21, a22 = (float(v) for v in phi.ravel())
    b1, b2 = float(gam[0]), float(gam[1])
    sdc, mdc = _computer_flags(comp)
    m, lead, kc, db = ph.m_used, ph.L_used, ph.K_used, rig.deadband_n
    quant = ph.quant
    rule = rig.integrator
    semi = rule == "semi_implicit_euler"
    maps = ph.gain_g != 0.0 or ph.f_sat < math.inf or ph.bias != 0.0 or ph.zdrift != 0.0
    nfl = nf.tolist()
    npl = npos.tolist()
    fh = [0.0] * n
    out_p_des = [0.0] * n
    out_p_act = [0.0] * n
    out_f_mea = [0.0] * n
    out_f_comp = [0.0] * n
    out_v = [0.0] * n
    pen = [0.0] * n
    p, pd = float(x0[0]), float(x0[1])
    x = -rig.initial_gap_m
    v = v0
    u_prev = x
    f_prev = None
    law = ph.law
    simple = (
        ph.nonlin is None
        and ph.p0 == 0.0
        and not (ph.alpha or ph.c or ph.F or ph.F_in or ph.F_out or ph.drift)
    )
    kl = ph.k_lin
    vlim = 100.0 * abs(v0) + 1.0
    diverged = False
    for k in range(n):
        t = k * h
        if simple:
            fk = kl * p if p > 0.0 else 0.0
        else:
            fk = law(p, pd, t, t_run)
        fh[k] = fk
        s = fh[k - nd] if k >= nd else 0.0
        if maps:
            s = ph.read_force(s, t, t_run)
        f_mea = s + nfl[k]
        if quant:
            f_mea = quant * round(f_mea / quant)
        p_act = p + ph.pos_bias + npl[k]
        if f_prev is None:
            f_prev = f_mea
        fc = _compensate(f_mea, f_prev, p_act, u_prev, db, sdc, mdc, lead, kc, h)
        if semi:
            v += -fc / m * h
            x += v * h
        else:
            x, v = model_step(rule, x, v, fc, m, h)
        out_p_des[k] = x
        out_p_act[k] = p_act
        out_f_mea[k] = f_mea
        out_f_comp[k] = fc
        out_v[k] = v
        pen[k] = p - ph.p0
        f_prev = f_mea
        u_prev = x
        p, pd = a11 * p + a12 * pd + b1 * x, a21 * p + a22 * pd + b2 * x
        if not abs(v) < vlim:
            diverged = True
            break
    return _pack(n, h, out_p_des, out_p_act, out_f_mea, out_f_comp, out_v, pen, fh, diverged)


def _pack(n, h, pdes, pact, fmea, fcomp, v, pen, force, diverged) -> dict:
    return {
        "time_s": np.arange(n) * h,
        "p_des": np.asarray(pdes, float),
        "p_act": np.asarray(pact, float),
        "f_mea": np.asarray(fmea, float),
        "f_comp": np.asarray(fcomp, float),
        "v_des": np.asarray(v, float),
        "penetration": np.asarray(pen, float),
        "force": np.asarray(force, float),
        "diverged": diverged,
    }


def _loop_fine(ph: _Physics, v0: float, comp: str, n: int, nf, npos) -> dict:
    rig = ph.rig
    h = rig.h
    N = SUBSTEPS
    dt = h / N
    t_run = n * h
    nd = rig.delay_ticks
    dsteps = nd * N + ph.extra_delay / dt
    if rig.delay_frac:
        # The nominal delay's fraction of a tick, read like a fractional extra delay.
        dsteps += rig.delay_frac * N
    if abs(dsteps - round(dsteps)) < 1e-9:
        dsteps = float(round(dsteps))
    lsteps = ph.pos_lag / dt
    pad = int(math.ceil(max(dsteps, lsteps))) + 4 * N
    size = pad + n * N + 1
    S = np.zeros(size)
    PE = np.empty(size)
    PE[: pad + 1] = -rig.initial_gap_m + v0 * dt * np.arange(-pad, 1)
    jj = np.arange(1, N + 1)

    filters = []
    for kind, par in ph.filters:
        if kind == "lp1":
            num, den = [1.0], [par[0], 1.0]
        else:
            ws, zs = par
            num, den = [ws * ws], [1.0, 2 * zs * ws, ws * ws]
        bz, az = _foh_filter(num, den, dt)
        filters.append([bz, az, np.zeros(max(len(az), len(bz)) - 1)])

    rate = ph.table == "ratelimit"
    reso = ph.table == "resonance_loaded"
    w = 2 * math.pi * rig.table_hz
    z2w = 2 * rig.table_zeta * w
    if rate:
        gain = w / (2 * rig.table_zeta)
        vmax = ph.table_par["vmax"]
        p, pd = -rig.initial_gap_m, v0
        q_now = p
    elif reso:
        st = [-rig.initial_gap_m, v0, -rig.initial_gap_m, v0]
        q_now = st[2]
        wr, zr, m_r = ph.table_par["wr"], ph.table_par["zr"], ph.table_par["m_r"]
        k_hi = max(ph.k_lin, rig.stiffness_n_per_m) * 3.0
        w_hi = math.sqrt(wr * wr + k_hi / m_r) + 2 * zr * wr + ph.c / m_r + w
        sub = max(1, math.ceil(w_hi * dt / 0.25))
        reso_par = (w * w, z2w, wr * wr, 2 * zr * wr, 1.0 / m_r, sub)
    else:
        a, b, xs, (ie, iq, iqd) = ph.table_lti(v0)
        nst = a.shape[0]
        big = np.empty((3 * N + nst, nst))
        gbig = np.empty(3 * N + nst)
        for j in range(1, N + 1):
            phj, gj = _lti_step(a, b, j * dt)
            big[j - 1] = phj[ie]
            gbig[j - 1] = gj[ie]
            big[N + j - 1] = phj[iq]
            gbig[N + j - 1] = gj[iq]
            big[2 * N + j - 1] = phj[iqd]
            gbig[2 * N + j - 1] = gj[iqd]
        big[3 * N :] = phj
        gbig[3 * N :] = gj
        q_now = float(xs[iq])

    sdc, mdc = _computer_flags(comp)
    m, lead, kc, db = ph.m_used, ph.L_used, ph.K_used, rig.deadband_n
    quant = ph.quant
    rule = rig.integrator
    semi = rule == "semi_implicit_euler"
    res = {key: np.zeros(n) for key in ("p_des", "p_act", "f_mea", "f_comp", "v_des", "pen", "f")}
    x = -rig.initial_gap_m
    v = v0
    u_prev = x
    f_prev = None
    vlim = 100.0 * abs(v0) + 1.0
    diverged = False
    f_last_tick = 0.0
    for k in range(n):
        base = pad + k * N
        t = k * h
        s = _interp(S, base - dsteps, base)
        s = ph.read_force(s, t, t_run)
        f_mea = s + nf[k]
        if quant:
            f_mea = quant * round(f_mea / quant)
        pe = float(PE[base]) if lsteps == 0.0 else _interp(PE, base - lsteps, base)
        p_act = pe + ph.pos_bias + npos[k]
        if f_prev is None:
            f_prev = f_mea
        fc = _compensate(f_mea, f_prev, p_act, u_prev, db, sdc, mdc, lead, kc, h)
        if semi:
            v += -fc / m * h
            x += v * h
        else:
            x, v = model_step(rule, x, v, fc, m, h)
        res["p_des"][k] = x
        res["p_act"][k] = p_act
        res["f_mea"][k] = f_mea
        res["f_comp"][k] = fc
        res["v_des"][k] = v
        res["pen"][k] = q_now - ph.p0
        res["f"][k] = f_last_tick
        f_prev = f_mea
        u_prev = x
        # ---- physics from t_k to t_k+1 under the held command x ----
        if rate:
            pe_c, q_c, qd_c = _ratelimit_chunk(p, pd, x, dt, N, z2w, gain, vmax)
            p, pd = pe_c[-1], qd_c[-1]
            pe_c = np.asarray(pe_c)
            q_c = pe_c
            qd_c = np.asarray(qd_c)
        elif reso:
            pe_c, q_c, qd_c = _resonance_chunk(st, x, dt, N, reso_par, ph, t, t_run)
            pe_c, q_c, qd_c = np.asarray(pe_c), np.asarray(q_c), np.asarray(qd_c)
        else:
            y = big @ xs + gbig * x
            pe_c = y[:N]
            q_c = y[N : 2 * N]
            qd_c = y[2 * N : 3 * N]
            xs = y[3 * N :]
        f_c = ph.law_vec(q_c, qd_c, t + dt * jj, t_run)
        f_last_tick = float(f_c[-1])
        for flt in filters:
            f_c, flt[2] = lfilter(flt[0], flt[1], f_c, zi=flt[2])
        S[base + 1 : base + N + 1] = f_c
        PE[base + 1 : base + N + 1] = pe_c
        q_now = float(q_c[-1])
        if not abs(v) < vlim or not math.isfinite(q_now):
            diverged = True
            break
    return _pack(
        n,
        h,
        res["p_des"],
        res["p_act"],
        res["f_mea"],
        res["f_comp"],
        res["v_des"],
        res["pen"],
        res["f"],
        diverged,
    )


def _ratelimit_chunk(p, pd, u, dt, N, z2w, gain, vmax):
    """RK4 sub-steps of the rate-limited servo over one tick."""
    pe = [0.0] * N
    vel = [0.0] * N

    def acc(pp, vv):
        c = gain * (u - pp)
        if c > vmax:
            c = vmax
        elif c < -vmax:
            c = -vmax
        return z2w * (c - vv)

    hdt = 0.5 * dt
    for j in range(N):
        k1p, k1v = pd, acc(p, pd)
        k2p, k2v = pd + hdt * k1v, acc(p + hdt * k1p, pd + hdt * k1v)
        k3p, k3v = pd + hdt * k2v, acc(p + hdt * k2p, pd + hdt * k2v)
        k4p, k4v = pd + dt * k3v, acc(p + dt * k3p, pd + dt * k3v)
        p = p + dt / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p)
        pd = pd + dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
        pe[j] = p
        vel[j] = pd
    return pe, pe, vel


def _resonance_chunk(st, u, dt, N, par, ph: _Physics, t0, t_run):
    """RK4 over one tick of the servo and the contact-point mode, with the
    contact force acting on the mode's mass (``st`` updated in place).
    Returns the measured position (the contact point), q and q'."""
    w2, z2w, wr2, c_r, inv_mr, sub = par
    law = ph.law
    p, pd, q, qd = st
    hs = dt / sub
    hh = 0.5 * hs
    qs = [0.0] * N
    qds = [0.0] * N
    t = t0
    for j in range(N):
        for _ in range(sub):
            th = t + hh
            a1 = w2 * (u - p) - z2w * pd
            b1 = wr2 * (p - q) + c_r * (pd - qd) - law(q, qd, t, t_run) * inv_mr
            p2, v2, q2, w2_ = p + hh * pd, pd + hh * a1, q + hh * qd, qd + hh * b1
            a2 = w2 * (u - p2) - z2w * v2
            b2 = wr2 * (p2 - q2) + c_r * (v2 - w2_) - law(q2, w2_, th, t_run) * inv_mr
            p3, v3, q3, w3 = p + hh * v2, pd + hh * a2, q + hh * w2_, qd + hh * b2
            a3 = w2 * (u - p3) - z2w * v3
            b3 = wr2 * (p3 - q3) + c_r * (v3 - w3) - law(q3, w3, th, t_run) * inv_mr
            p4, v4, q4, w4 = p + hs * v3, pd + hs * a3, q + hs * w3, qd + hs * b3
            t = t + hs
            a4 = w2 * (u - p4) - z2w * v4
            b4 = wr2 * (p4 - q4) + c_r * (v4 - w4) - law(q4, w4, t, t_run) * inv_mr
            p += hs / 6.0 * (pd + 2 * v2 + 2 * v3 + v4)
            q += hs / 6.0 * (qd + 2 * w2_ + 2 * w3 + w4)
            pd += hs / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
            qd += hs / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4)
        qs[j] = q
        qds[j] = qd
    st[0], st[1], st[2], st[3] = p, pd, q, qd
    # p_act is measured on the platform, at the contact point.
    return qs, qs, qds


# --------------------------------------------------------------------------- #
# Sets
# --------------------------------------------------------------------------- #
def _effects_of(hidden, scales: Scales) -> dict[str, dict]:
    return {h.name: h.params(scales) for h in hidden}


def simulate_set(
    spec: SetSpec, *, noise: bool = True, hidden: tuple[Hidden, ...] | None = None
) -> list[RunRecord]:
    """Every run of ``spec`` (optionally with other hidden effects, or noise-free)."""
    hid = spec.hidden if hidden is None else hidden
    effects = _effects_of(hid, spec.scales)
    runs = []
    n_runs = len(spec.velocities)
    for i, (v, c, n) in enumerate(
        zip(spec.velocities, spec.compensators, spec.n_ticks, strict=True)
    ):
        runs.append(
            simulate_run(
                spec.rig,
                effects,
                v,
                c,
                n,
                noise=spec.noise if noise else None,
                seed=[spec.seed, i],
                run_index=i,
                n_runs=n_runs,
                run_id=f"{spec.run_stem}-run{i + 1}",
            )
        )
    return runs


# --------------------------------------------------------------------------- #
# The nominal model's error
# --------------------------------------------------------------------------- #
def nominal_replay(
    meta: dict, p_des: np.ndarray, *, fine: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """The recorded commands through the nominal table, contact and sensor (no
    noise): the position and the force reading the nominal model predicts.

    A sensor delay of a whole number of ticks reads the tick-exact force that
    many ticks late; a fractional one (or ``fine``) reads the force history
    sub-stepped as the generator's fine path does (:data:`SUBSTEPS` points a
    tick, cubic interpolation), so a noise-free nominal run replays exactly."""
    fs = float(meta["sample_rate_hz"])
    h = 1.0 / fs
    w = 2 * math.pi * float(meta["table_natural_frequency_hz"])
    z = float(meta["table_damping_ratio"])
    k = float(meta["contact_stiffness_n_per_m"])
    d_ticks = float(meta["sensor_delay_s"]) * fs
    nd = int(round(d_ticks))
    if fine or abs(d_ticks - nd) >= 1e-9:
        return _nominal_replay_fine(meta, p_des, d_ticks)
    phi, gam = _lti_step(np.array([[0.0, 1.0], [-w * w, -2 * z * w]]), np.array([0.0, w * w]), h)
    a11, a12, a21, a22 = (float(v) for v in phi.ravel())
    b1, b2 = float(gam[0]), float(gam[1])
    p = -float(meta["initial_gap_m"])
    pd = float(meta["initial_velocity_m_per_s"])
    n = len(p_des)
    pos = [0.0] * n
    for i, u in enumerate(p_des.tolist()):
        pos[i] = p
        p, pd = a11 * p + a12 * pd + b1 * u, a21 * p + a22 * pd + b2 * u
    pos_a = np.asarray(pos)
    f = k * np.maximum(pos_a, 0.0)
    fr = np.zeros(n)
    if nd < n:
        fr[nd:] = f[: n - nd]
    return pos_a, fr


def _nominal_replay_fine(
    meta: dict, p_des: np.ndarray, d_ticks: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`nominal_replay` on the generator's sub-stepped grid (the same
    table steps, force history and interpolation as :func:`_loop_fine`)."""
    fs = float(meta["sample_rate_hz"])
    h = 1.0 / fs
    N = SUBSTEPS
    dt = h / N
    w = 2 * math.pi * float(meta["table_natural_frequency_hz"])
    z = float(meta["table_damping_ratio"])
    k = float(meta["contact_stiffness_n_per_m"])
    dsteps = d_ticks * N
    if abs(dsteps - round(dsteps)) < 1e-9:
        dsteps = float(round(dsteps))
    n = len(p_des)
    pad = int(math.ceil(dsteps)) + 4 * N
    S = np.zeros(pad + n * N + 1)
    a = np.array([[0.0, 1.0], [-w * w, -2 * z * w]])
    b = np.array([0.0, w * w])
    # Rows as in _loop_fine: encoder, contact point, its rate, then the state.
    big = np.empty((3 * N + 2, 2))
    gbig = np.empty(3 * N + 2)
    for j in range(1, N + 1):
        phj, gj = _lti_step(a, b, j * dt)
        for blk, row in ((0, 0), (1, 0), (2, 1)):
            big[blk * N + j - 1] = phj[row]
            gbig[blk * N + j - 1] = gj[row]
    big[3 * N :] = phj
    gbig[3 * N :] = gj
    xs = np.array([-float(meta["initial_gap_m"]), float(meta["initial_velocity_m_per_s"])])
    pos = np.empty(n)
    fr = np.empty(n)
    p_now = float(xs[0])
    for i, u in enumerate(p_des.tolist()):
        base = pad + i * N
        pos[i] = p_now
        fr[i] = _interp(S, base - dsteps, base)
        y = big @ xs + gbig * u
        q_c = y[N : 2 * N]
        S[base + 1 : base + N + 1] = np.where(q_c > 0.0, k * np.where(q_c > 0.0, q_c, 0.0), 0.0)
        xs = y[3 * N :]
        p_now = float(y[N - 1])
    return pos, fr


def nominal_error(runs: list[RunRecord], sigma_f: float, sigma_p: float) -> float:
    """``sqrt(mean((residual / sigma)^2))`` over both channels and all runs;
    residual = recorded reading - nominal replay, sigma = the channel's noise
    marginal std (the truth: the noise spec)."""
    acc = 0.0
    count = 0
    for r in runs:
        if r.diverged:
            return math.inf
        p_nom, f_nom = nominal_replay(r.meta, r.p_des)
        ef = (r.f_mea - f_nom) / sigma_f
        ep = (r.p_act - p_nom) / sigma_p
        acc += float(ef @ ef + ep @ ep)
        count += 2 * len(ef)
    out = math.sqrt(acc / count)
    return out if math.isfinite(out) else math.inf


def set_error(spec: SetSpec, hidden: tuple[Hidden, ...] | None = None) -> float:
    """Nominal error of the set (with its noise)."""
    return nominal_error(simulate_set(spec, hidden=hidden), spec.noise.sigma_f, spec.noise.sigma_p)


def set_cor(spec: SetSpec, hidden: tuple[Hidden, ...] | None = None) -> float:
    """Mean coefficient of restitution of the set's runs (noise-free): ``-v_end / v0``."""
    runs = simulate_set(spec, noise=False, hidden=hidden)
    if any(r.diverged for r in runs):
        return math.inf
    return float(np.mean([r.cor for r in runs]))


# --------------------------------------------------------------------------- #
# Sizing
# --------------------------------------------------------------------------- #
def _bisect(func, target, lo, hi, guess, *, rel_tol, max_eval=40):
    """Magnitude in [lo, hi] where the increasing ``func`` reaches ``target``
    (geometric bracketing then bisection). Returns (mag, value, evaluations)."""
    evals = []

    def f(x):
        y = func(x)
        evals.append((x, y))
        return y

    x = min(max(guess, lo), hi)
    y = f(x)
    if abs(y - target) <= rel_tol * target:
        return x, y, evals
    if y < target:
        a, fa = x, y
        b = None
        while b is None:
            if a >= hi:
                raise SizingError(f"target {target:g} not reached at the bound {hi:g} ({fa:g})")
            x2 = min(a * 3.0, hi)
            y2 = f(x2)
            if y2 >= target:
                b, fb = x2, y2
            else:
                a, fa = x2, y2
    else:
        b, fb = x, y
        a = None
        while a is None:
            if b <= lo:
                raise SizingError(f"target {target:g} exceeded at the bound {lo:g} ({fb:g})")
            x2 = max(b / 3.0, lo)
            y2 = f(x2)
            if y2 <= target:
                a, fa = x2, y2
            else:
                b, fb = x2, y2
    best = min(((a, fa), (b, fb)), key=lambda e: abs(e[1] - target))
    while len(evals) < max_eval:
        if abs(best[1] - target) <= rel_tol * target:
            break
        # Secant in log(magnitude) when safely inside, else geometric midpoint.
        la, lb = math.log(a), math.log(b)
        mid = 0.5 * (la + lb)
        if math.isfinite(fa) and math.isfinite(fb) and fb > fa:
            sec = la + (target - fa) * (lb - la) / (fb - fa)
            if la + 0.1 * (lb - la) < sec < lb - 0.1 * (lb - la):
                mid = sec
        xm = math.exp(mid)
        ym = f(xm)
        if ym < target:
            a, fa = xm, ym
        else:
            b, fb = xm, ym
        if abs(ym - target) < abs(best[1] - target):
            best = (xm, ym)
    return best[0], best[1], evals


def size_effect(
    spec: SetSpec,
    index: int,
    target: float,
    *,
    others: bool = False,
    rel_tol: float = 0.02,
) -> SetSpec:
    """Scale ``spec.hidden[index]``'s magnitude until the set's nominal error
    (:func:`set_error`, with noise) reaches ``target``. The other hidden
    effects are left out unless ``others``. Returns the updated spec (its
    ``info`` holds the error reached); raises :class:`SizingError` if the
    target cannot be reached within the effect's bounds."""
    hid = spec.hidden[index]
    d = EFFECTS[hid.name]
    lo, hi = magnitude_bounds(hid, spec.scales)

    def with_mag(mag):
        h2 = replace(hid, magnitude=mag)
        if others:
            return tuple(h2 if i == index else h for i, h in enumerate(spec.hidden))
        return (h2,)

    def err_of(x):
        return set_error(spec, with_mag(x))

    top = err_of(hi)
    if top < target:
        raise SizingError(f"target {target:g} not reached at the bound {hi:g} ({top:g})")
    mag, err, _ = _bisect(
        err_of,
        target,
        lo,
        hi,
        hid.magnitude or d.guess,
        rel_tol=rel_tol,
    )
    new = tuple(replace(h, magnitude=mag) if i == index else h for i, h in enumerate(spec.hidden))
    info = dict(spec.info)
    info.setdefault("sized_error", {})[hid.name] = err
    return replace(spec, hidden=new, info=info)


def _size_on_cor(spec: SetSpec, cor_null: float) -> SetSpec:
    """Size the second effect of a pair so the set's CoR equals ``cor_null``
    (a lag of up to 0.1 s allowed: slow contacts need long lags to cancel)."""
    first, second = spec.hidden
    d = EFFECTS[second.name]
    lo, hi = magnitude_bounds(second, spec.scales)
    hi = max(hi, 0.1 / spec.rig.h)

    def cor_of(mag):
        return set_cor(spec, (first, replace(second, magnitude=mag)))

    # CoR rises with the energy-adding effect; bisection on CoR - cor_null + 1
    # (an increasing positive function) to an absolute tolerance of 0.002.
    shift = 1.0
    mag, val, _ = _bisect(
        lambda x: cor_of(x) - cor_null + shift,
        shift,
        lo,
        hi,
        d.guess,
        rel_tol=0.002,
    )
    return replace(spec, hidden=(first, replace(second, magnitude=mag)))


def _sane(spec: SetSpec) -> str:
    """Why a sized set is not a usable rig ('' if it is): a run diverges, does
    not separate with 0.1 s to spare, or bounces with a CoR out of 0.05-2."""
    for r in simulate_set(spec, noise=False):
        if r.diverged:
            return "a run diverges"
        ct = r.contact_ticks()
        n = len(r.v_des)
        if len(ct) and ct[-1] + int(0.1 / spec.rig.h) > n:
            return "a run does not separate in time"
        if not 0.05 <= r.cor <= 2.0:
            return f"a run's CoR is {r.cor:.3g}"
    return ""


def _resolve_cancel(spec: SetSpec, info: dict, min_pair_error: float = 2.5) -> SetSpec:
    """Size a CoR-cancelling pair (see :func:`resolve`)."""
    cor_null = set_cor(spec, ())
    first, second = spec.hidden
    target = first.target_error or 4.0
    for _attempt in range(6):
        f1 = size_effect(replace(spec, hidden=(first,)), 0, target).hidden[0]
        cor1 = set_cor(spec, (f1,))
        if cor_null - cor1 <= 0.05:
            target *= 1.5
            continue
        f2 = _size_on_cor(replace(spec, hidden=(f1, second)), cor_null).hidden[1]
        cor2 = set_cor(spec, (f2,))
        cor_pair = set_cor(spec, (f1, f2))
        if abs(cor_pair - cor_null) >= 0.01:
            raise SizingError(f"the pair's CoR {cor_pair:.4f} is not the null's {cor_null:.4f}")
        if cor2 - cor_null < 0.03:
            raise SizingError("the energy-adding effect does not change the CoR clearly")
        err_pair = set_error(spec, (f1, f2))
        if err_pair >= min_pair_error:
            break
        # The two cancel in the readings too (a lag reads as negative
        # damping to first order): make both larger until the pair shows.
        target *= 1.5
    else:
        raise SizingError("no CoR-cancelling pair that the data show")
    info.update(
        {
            "cor_null": cor_null,
            "cor_first_alone": cor1,
            "cor_second_alone": cor2,
            "cor_pair": cor_pair,
            "first_target_error": target,
            "error_first_alone": set_error(spec, (f1,)),
            "error_second_alone": set_error(spec, (f2,)),
        }
    )
    return replace(spec, hidden=(f1, f2), info=info)


def _resolve_once(spec: SetSpec) -> SetSpec:
    info = dict(spec.info)
    if spec.label == "pair_cancel":
        return _resolve_cancel(spec, info)
    if spec.label == "pair":
        sized = []
        for h in spec.hidden:
            one = size_effect(replace(spec, hidden=(h,)), 0, h.target_error or 3.5)
            sized.append(one.hidden[0])
            info.setdefault("sized_error", {}).update(one.info["sized_error"])
        return replace(spec, hidden=tuple(sized), info=info)
    out = spec
    for i, h in enumerate(spec.hidden):
        if h.magnitude is None:
            out = size_effect(out, i, h.target_error or 3.0, others=False)
    return out


def resolve(spec: SetSpec, max_redraws: int = 20) -> SetSpec:
    """Size every unsized hidden effect of ``spec``:

    - single / tiny / outside: the effect alone to its ``target_error``;
    - pair: each effect alone to its target, then both together;
    - pair_cancel: the dissipating effect alone to its target (raised until
      it lowers the CoR by more than 0.05), then the energy-adding one so the
      set's mean CoR (noise-free) is the null rig's within 0.01; the
      energy-adding one alone must raise it by more than 0.03, and the pair's
      nominal error must be at least 2.5 (a lag reads as negative damping to
      first order, so damping + delay also cancel in the readings: the
      target is raised until the pair shows);
    - null / computer: nothing to size;
    - deadband0 / fractional_delay / integrator: as a single (a physics
      effect) or nothing (a null, a computer effect); a redraw keeps the
      set's rig condition (``info["condition"]``).

    If a target cannot be reached within :func:`magnitude_bounds`, or the
    sized set is not a usable rig (:func:`_sane`), the set's rig, noise and
    runs are drawn again (deterministically from its seed), up to
    ``max_redraws`` times. ``info`` gets the nominal error reached, the CoR
    figures, and the redraws with their reasons.
    """
    if spec.sized and "error" in spec.info:
        return spec
    cur = spec
    reasons = []
    for attempt in range(max_redraws + 1):
        try:
            out = _resolve_once(cur)
            why = _sane(out)
            if why:
                raise SizingError(why)
        except SizingError as e:
            reasons.append(f"{cur.rig}: {e}")
            rng = np.random.default_rng([spec.seed, attempt + 1])
            base = draw_base(
                rng,
                spec.set_id,
                spec.label,
                need=spec.info.get("need"),
                n_runs=None,
                condition=spec.info.get("condition"),
            )
            cur = replace(base, hidden=spec.hidden, info=dict(base.info))
            continue
        info = dict(out.info)
        info["error"] = set_error(out)
        info["cor"] = set_cor(out)
        info["redraws"] = attempt
        info["redraw_reasons"] = reasons
        return replace(out, info=info)
    raise SizingError(f"{spec.set_id}: no usable rig after {max_redraws} redraws: {reasons[-1]}")


# --------------------------------------------------------------------------- #
# Writing and reading sets
# --------------------------------------------------------------------------- #
def _fmt(x: float) -> str:
    return f"{x:.10g}"


def write_run(folder: Path, stem: str, run: RunRecord) -> Path:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    csv_path = folder / f"{stem}.csv"
    lines = ["time_s,p_des_m,p_act_m,f_mea_n,f_comp_n,v_des_m_per_s"]
    cols = zip(
        run.time_s.tolist(),
        run.p_des.tolist(),
        run.p_act.tolist(),
        run.f_mea.tolist(),
        run.f_comp.tolist(),
        run.v_des.tolist(),
        strict=True,
    )
    lines.extend(",".join(_fmt(v) for v in row) for row in cols)
    csv_path.write_text("\n".join(lines) + "\n")
    (folder / f"{stem}.json").write_text(json.dumps(run.meta, indent=2) + "\n")
    return csv_path


def write_set(folder, spec: SetSpec) -> list[Path]:
    """Write the runs of ``spec`` (sized first if needed) as ``run<i>.csv/.json``
    pairs in ``folder``; returns the csv paths. Nothing else is written there."""
    spec = resolve(spec)
    runs = simulate_set(spec)
    for r in runs:
        if r.diverged:
            raise SizingError(f"{spec.set_id}: a run diverged")
    return [write_run(Path(folder), f"run{i + 1}", r) for i, r in enumerate(runs)]


def read_set(folder) -> list[RunRecord]:
    """Read back the csv/json pairs of a folder (plain numpy, no truth)."""
    out = []
    for csv_path in sorted(Path(folder).glob("*.csv")):
        meta = json.loads(csv_path.with_suffix(".json").read_text())
        data = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
        out.append(
            RunRecord(
                meta=meta,
                time_s=data[:, 0],
                p_des=data[:, 1],
                p_act=data[:, 2],
                f_mea=data[:, 3],
                f_comp=data[:, 4],
                v_des=data[:, 5],
            )
        )
    return out


# --------------------------------------------------------------------------- #
# Drawing rigs, noise, sets and the study
# --------------------------------------------------------------------------- #
def _loguniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def draw_rig(
    rng: np.random.Generator,
    v_typ: float = 0.1,
    min_contact_ratio: float = 0.0,
    *,
    zero_deadband: bool = False,
    fractional_delay: bool = False,
    integrator: str = DEFAULT_INTEGRATOR,
) -> Rig:
    """A rig in the issue's ranges whose contact is at most a quarter of the
    table's frequency and short enough for a run of :data:`MAX_TICKS` ticks.
    ``v_typ`` sets the gap (3-8 ms of approach at that speed);
    ``min_contact_ratio``: the contact's frequency at least this fraction of
    the table's (a table mode is only measurable when the contact excites it).

    Rig conditions (the defaults draw exactly the rigs drawn before they
    existed, from the same generator state):

    - ``zero_deadband``: ``deadband_n = 0`` (the deadband is still drawn, then
      replaced, so the rest of the rig is the one drawn without it);
    - ``fractional_delay``: the nominal delay is whole ticks plus a fraction
      0.10-0.90 of a tick (two decimals), still within 1-20 ms; the SDC lead
      time is that delay (perturbed as usual a quarter of the time);
    - ``integrator``: the rig computer's rule (:data:`INTEGRATORS`), not drawn.
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator {integrator!r} is not one of {INTEGRATORS}")
    for _ in range(10000):
        fs = int(rng.choice([500, 1000, 2000]))
        m = round(_loguniform(rng, 100.0, 5000.0), 3)
        k = round(_loguniform(rng, 1e4, 1e6), 1)
        ft = round(float(rng.uniform(10.0, 80.0)), 2)
        zt = round(float(rng.uniform(0.5, 1.0)), 3)
        fc = math.sqrt(k / m) / (2 * math.pi)
        if fc > ft / 4.0 or fc < min_contact_ratio * ft:
            continue
        tc = math.pi * math.sqrt(m / k)
        if 1.3 * tc + QUIET_S + 0.08 > 0.9 * MAX_TICKS / fs:
            continue
        lo = max(1, math.ceil(1e-3 * fs - 1e-9))
        hi = math.floor(20e-3 * fs + 1e-9)
        nd = int(rng.integers(lo, hi + 1))
        frac = 0.0
        if fractional_delay:
            frac = round(float(rng.uniform(0.1, 0.9)), 2)
            if nd + frac > hi:
                nd -= 1
        lead = (nd + frac) / fs if frac else nd / fs
        if rng.random() < 0.25:
            lead = round(lead * float(rng.uniform(0.8, 1.2)), 6)
        elif frac:
            lead = round(lead, 12)
        db = round(float(rng.uniform(0.0, 5.0)), 3)
        if zero_deadband:
            db = 0.0
        gap = round(v_typ * float(rng.uniform(3e-3, 8e-3)), 6)
        return Rig(fs, m, k, nd, ft, zt, db, lead, gap, frac, integrator)
    raise RuntimeError("no rig drawn")


def draw_noise(rng: np.random.Generator, f_peak: float, p_peak: float) -> NoiseSpec:
    """White, AR(1) or AR(2) noise, force 0.5-5 % of ``f_peak``, position
    0.2-2 % of ``p_peak`` (log-uniform)."""
    kind = str(rng.choice(["white", "ar1", "ar2"]))
    if kind == "white":
        ar: tuple[float, ...] = ()
    elif kind == "ar1":
        ar = (round(float(rng.uniform(0.3, 0.9)), 3),)
    elif rng.random() < 0.5:
        p1, p2 = (float(x) for x in rng.uniform(0.5, 0.9, 2))
        ar = (round(p1 + p2, 4), round(-p1 * p2, 4))
    else:
        r = float(rng.uniform(0.5, 0.9))
        th = float(rng.uniform(0.3, 2.0))
        ar = (round(2 * r * math.cos(th), 4), round(-r * r, 4))
    return NoiseSpec(
        kind,
        ar,
        _loguniform(rng, 0.005, 0.05) * f_peak,
        _loguniform(rng, 0.002, 0.02) * p_peak,
    )


def _comp_noise_ok(rig: Rig, noise: NoiseSpec, comp: str, v: float) -> bool:
    """The compensator's noise gain keeps f_comp's noise under 15 % of the
    run's peak force (else the rig's loop is unusable); "none" is always usable."""
    if comp == "none":
        return True
    sdc, mdc = _computer_flags(comp)
    a = rig.lead_time_s / rig.h if sdc else 0.0
    rho = noise.lag1()
    var = noise.sigma_f**2 * ((1 + a) ** 2 + a * a - 2 * a * (1 + a) * rho)
    if mdc:
        var += (rig.stiffness_n_per_m * noise.sigma_p) ** 2
    return math.sqrt(var) <= 0.15 * v * math.sqrt(rig.mass_kg * rig.stiffness_n_per_m)


def _check_nominal(rig: Rig, velocities, comps) -> tuple[list[int], list[float]] | None:
    """Noise-free nominal runs: run lengths and CoRs, or None if a run
    diverges, does not separate in time or bounces with a CoR out of 0.3-1.6."""
    h = rig.h
    tc = rig.contact_time_s
    lens, cors = [], []
    for v, c in zip(velocities, comps, strict=True):
        est = int(math.ceil((rig.initial_gap_m / v + 1.8 * tc + 0.05 + QUIET_S) / h))
        for n_try in sorted({min(est, MAX_TICKS), MAX_TICKS}):
            r = simulate_run(rig, None, v, c, n_try)
            if r.diverged:
                return None
            ct = r.contact_ticks()
            if len(ct) == 0:
                return None
            last = int(ct[-1])
            quiet = int(math.ceil(QUIET_S / h))
            if last + quiet + rig.delay_ticks_ceil < n_try and r.v_des[-1] < 0:
                break
        else:
            return None
        cor = r.cor
        if not 0.3 <= cor <= 1.6:
            return None
        n = last + int(math.ceil((QUIET_S + 0.15 * tc) / h)) + 2 * rig.delay_ticks_ceil + 10
        if last + quiet + rig.delay_ticks_ceil > MAX_TICKS:
            return None
        lens.append(min(n, MAX_TICKS))
        cors.append(cor)
    return lens, cors


def draw_base(
    rng: np.random.Generator,
    set_id: str,
    label: str,
    *,
    need: str | None = None,
    n_runs: int | None = None,
    condition: dict | None = None,
) -> SetSpec:
    """A validated set with no hidden effect (``need``: "sdc" / "mdc": at
    least two runs with that compensation; "order": at least three runs whose
    velocity is not monotone in the run order; "resonance": a contact at
    least 0.15 of the table's frequency). ``condition``: the rig's conditions,
    keyword arguments of :func:`draw_rig` (``zero_deadband``,
    ``fractional_delay``, ``integrator``), kept in ``info["condition"]`` so
    :func:`resolve` redraws a rig with them; None (or empty) draws exactly
    what was drawn before conditions existed."""
    cond = dict(condition or {})
    bad = set(cond) - {"zero_deadband", "fractional_delay", "integrator"}
    if bad:
        raise ValueError(f"unknown rig condition(s) {sorted(bad)}")
    for _ in range(500):
        nr = int(n_runs or rng.integers(2, 6))
        if need == "order":
            nr = max(nr, 3)
        vel = sorted(_loguniform(rng, 0.03, 0.3) for _ in range(nr))
        if vel[-1] / vel[0] < 1.3 or min(np.diff(vel)) < 0.003:
            continue
        vel = [round(v, 4) for v in vel]
        order = list(rng.permutation(nr))
        vel = [vel[i] for i in order]
        if need == "order" and (np.all(np.diff(vel) > 0) or np.all(np.diff(vel) < 0)):
            continue
        rig = draw_rig(
            rng,
            v_typ=math.sqrt(min(vel) * max(vel)),
            min_contact_ratio=0.15 if need == "resonance" else 0.0,
            **cond,
        )
        vmax = max(vel)
        noise = draw_noise(
            rng,
            vmax * math.sqrt(rig.mass_kg * rig.stiffness_n_per_m),
            vmax * math.sqrt(rig.mass_kg / rig.stiffness_n_per_m),
        )
        comps = []
        for v in vel:
            ok = [c for c in COMPENSATORS if _comp_noise_ok(rig, noise, c, v)]
            if need in ("sdc", "mdc"):
                want = [c for c in ok if ("SD" in c if need == "sdc" else "MDC" in c)]
                if want and sum(1 for c in comps if c in want) < 2:
                    ok = want
            comps.append(str(rng.choice(ok)))
        if need == "sdc" and sum(c in ("SDC", "SDMDC") for c in comps) < 2:
            continue
        if need == "mdc" and sum(c in ("MDC", "SDMDC") for c in comps) < 2:
            continue
        chk = _check_nominal(rig, vel, comps)
        if chk is None:
            continue
        lens, cors = chk
        info = {"cor_nominal_runs": cors, "need": need}
        if cond:
            info["condition"] = cond
        return SetSpec(
            set_id=set_id,
            label=label,
            rig=rig,
            noise=noise,
            velocities=tuple(vel),
            compensators=tuple(comps),
            n_ticks=tuple(lens),
            seed=int(rng.integers(2**31)),
            info=info,
        )
    raise RuntimeError("no valid set drawn")


#: Pairs of library effects drawn for the "pair" class (not two spring laws,
#: which are each other's look-alikes).
PAIRS = (
    ("contact_damping", "force_bias"),
    ("contact_damping", "stiffness_error"),
    ("hunt_crossley", "extra_delay"),
    ("coulomb_friction", "sensor_filter"),
    ("nonlinear_stiffness", "force_bias"),
    ("stiffness_error", "extra_delay"),
    ("series_compliance", "coulomb_friction"),
    ("table_resonance", "force_bias"),
    ("contact_damping", "table_resonance"),
    ("nonlinear_stiffness", "sensor_filter"),
    ("coulomb_friction", "extra_delay"),
)
CANCEL_PAIRS = (
    ("contact_damping", "extra_delay"),
    ("contact_damping", "sensor_filter"),
    ("hunt_crossley", "extra_delay"),
    ("coulomb_friction", "sensor_filter"),
)


def _need(name: str) -> str | None:
    """What a set hiding ``name`` needs of its rig (see :func:`draw_base`)."""
    return {"table_resonance": "resonance", "stiffness_drift": "order"}.get(name)


def draw_study(
    seed: int,
    n_null: int = 15,
    *,
    sizes: tuple[float, ...] = (2.0, 5.0),
    n_pairs: int = 7,
    n_cancel: int = 3,
    n_computer_each: int = 3,
    outside_target: float = 4.0,
    n_outside_extra: int = 4,
    n_tiny: int = 10,
    n_condition_each: int = 8,
) -> list[SetSpec]:
    """The study's sets (unsized; :func:`resolve` / :func:`write_set` size them).

    - ``n_null`` nulls;
    - every library physics effect at each of ``sizes`` (target nominal error);
    - ``n_pairs`` pairs (each effect alone sized to 3.5) and ``n_cancel``
      CoR-cancelling pairs;
    - ``n_computer_each`` sets of each computer effect (3-20 % mass, 10-40 %
      lead time and compensator stiffness);
    - every outside-library kind once at ``outside_target`` plus
      ``n_outside_extra`` more at 2.5;
    - ``n_tiny`` detection-limit sets (a library effect at error 1.2-1.4);
    - ``n_condition_each`` sets of each rig condition (:data:`CONDITION_CLASSES`:
      ``deadband0``, ``fractional_delay``, ``integrator``), drawn after all
      the others (so the sets above are the ones a seed drew before the
      conditions existed): every fourth a null, the others a single library
      effect in a shuffled cycle of the physics ones (sized to one of
      ``sizes``) and the computer ones (3-20 % mass, 10-40 % lead time and
      compensator stiffness). The ``integrator`` class cycles through the
      rules other than the format's (:data:`INTEGRATORS`).

    Each set draws its own rig; a different ``seed`` gives different rigs.
    """
    master = np.random.default_rng(seed)
    specs: list[SetSpec] = []

    def child():
        return np.random.default_rng(int(master.integers(2**63 - 1)))

    for i in range(n_null):
        specs.append(draw_base(child(), f"null-{i:02d}", "null"))
    for name in LIBRARY_PHYSICS:
        for target in sizes:
            rng = child()
            base = draw_base(rng, f"single-{name}-{target:g}", "single", need=_need(name))
            specs.append(replace(base, hidden=(make_hidden(name, rng, target_error=target),)))
    pair_order = master.permutation(len(PAIRS))
    for j in range(n_pairs):
        a, b = PAIRS[pair_order[j % len(PAIRS)]]
        rng = child()
        base = draw_base(rng, f"pair-{j:02d}-{a}+{b}", "pair", need=_need(a) or _need(b))
        specs.append(
            replace(
                base,
                hidden=(
                    make_hidden(a, rng, target_error=3.5),
                    make_hidden(b, rng, target_error=3.5),
                ),
            )
        )
    for j in range(n_cancel):
        a, b = CANCEL_PAIRS[(j + int(master.integers(len(CANCEL_PAIRS)))) % len(CANCEL_PAIRS)]
        rng = child()
        base = draw_base(rng, f"cancel-{j:02d}-{a}+{b}", "pair_cancel")
        specs.append(
            replace(
                base,
                hidden=(make_hidden(a, rng, target_error=4.0), make_hidden(b, rng)),
            )
        )
    ranges = {
        "mass_error": (0.03, 0.2, None),
        "lead_time_error": (0.1, 0.4, "sdc"),
        "compensator_stiffness_error": (0.1, 0.4, "mdc"),
    }
    for name, (lo, hi, need) in ranges.items():
        for j in range(n_computer_each):
            rng = child()
            base = draw_base(rng, f"computer-{name}-{j}", "computer", need=need)
            mag = round(float(rng.uniform(lo, hi)), 4)
            specs.append(replace(base, hidden=(make_hidden(name, rng, magnitude=mag),)))
    kinds = list(OUTSIDE_EFFECTS)
    extra = [kinds[i] for i in master.permutation(len(kinds))[:n_outside_extra]]
    for j, name in enumerate(kinds + extra):
        target = outside_target if j < len(kinds) else 2.5
        rng = child()
        base = draw_base(rng, f"outside-{name}-{target:g}", "outside", need=_need(name))
        specs.append(replace(base, hidden=(make_hidden(name, rng, target_error=target),)))
    tiny_names = [LIBRARY_PHYSICS[i % len(LIBRARY_PHYSICS)] for i in master.permutation(n_tiny)]
    for j, name in enumerate(tiny_names):
        rng = child()
        target = round(float(rng.uniform(1.2, 1.4)), 3)
        base = draw_base(rng, f"tiny-{j:02d}-{name}", "tiny", need=_need(name))
        specs.append(replace(base, hidden=(make_hidden(name, rng, target_error=target),)))
    # ---- rig conditions (drawn last: the sets above are unchanged) ----
    candidates = LIBRARY_PHYSICS + COMPUTER_EFFECTS
    rules = [r for r in INTEGRATORS if r != DEFAULT_INTEGRATOR]
    for label in CONDITION_CLASSES:
        order = [candidates[i] for i in master.permutation(len(candidates))]
        n_eff = 0
        for j in range(n_condition_each):
            if j % 4 == 0:
                name = None
            else:
                name = order[n_eff % len(order)]
                n_eff += 1
            if label == "deadband0":
                cond: dict = {"zero_deadband": True}
            elif label == "fractional_delay":
                cond = {"fractional_delay": True}
            else:
                cond = {"integrator": rules[j % len(rules)]}
            rng = child()
            if name is None:
                need = None
            elif name in ranges:
                need = ranges[name][2]
            else:
                need = _need(name)
            # The set id names the class only (and the runs' run_id not even that).
            base = draw_base(rng, f"{label}-{j:02d}", label, need=need, condition=cond)
            if name is None:
                hidden: tuple[Hidden, ...] = ()
            elif name in ranges:
                lo, hi, _ = ranges[name]
                hidden = (make_hidden(name, rng, magnitude=round(float(rng.uniform(lo, hi)), 4)),)
            else:
                target = float(sizes[int(rng.integers(len(sizes)))])
                hidden = (make_hidden(name, rng, target_error=target),)
            specs.append(replace(base, hidden=hidden))
    return specs
