"""An independent 6-DoF hybrid docking loop, for test data and cross-checks.

Plain numpy, no Drake and nothing from :mod:`hybridtable`: a rigid spacecraft
whose docking port carries a ring of ``N`` spherical pads pressed against the
flat target face z = 0 (each pad's normal force by the pad law of
docs/run6-format.md, "The pad law": :class:`PadLaw`, :func:`pad_normal_force`;
by default Drake's point contact ``k x (1 + d xdot)``), an ideal or second-order
motion table (exact zero-order-hold update per tick; a structural mode behind it:
``table_resonance``), a sensor delay of whole ticks and the compensators none /
SDC / MDC / SDMDC, where the MDC stiffness ``K = -dw/dq`` (and damping ``C =
-dw/dqd``) comes from central finite differences of this module's own wrench
function at the table's actual pose.

Hidden effects (``simulate_rig6(hidden=...)``): the rig's physical part (the
table, the contact, the F/T sensor) or the rig computer's spacecraft can do
what the arguments do not say, by the laws of docs/run6-format.md ("The
effects, as laws": :data:`LIBRARY_EFFECTS`) or by effects outside the library
(:data:`OUTSIDE_EFFECTS`: backlash in a lateral table axis, a proud pad, a
quadratic gain of the normal force channel, slow lateral table axes; the
ringing sensor mount was outside until the library took the law in as
``mount_resonance``); the pads' friction across the face is :func:`contact_wrench`.
:func:`replay_rig6` drives the physical part alone with recorded commands, as
a replay of a record does.

Conventions: pose ``q = [p_P; theta]`` (port position, rotation vector), rate
``qd = [v_P; omega]`` (world frame), wrench ``w = [moment about the port origin;
force]`` on the chaser. Row k of every array is tick k: what the rig computer
read and computed, and the spacecraft state after its update (so ``q_des[k]``
is the command the table follows over the next tick).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

__all__ = [
    "EFFECT_PARTS",
    "LIBRARY_EFFECTS",
    "OUTSIDE_EFFECTS",
    "PAD_LAW_KEYS",
    "PHYSICAL_ARGUMENTS",
    "PadLaw",
    "STICTION_TOLERANCE_M_PER_S",
    "TABLE_STARTS",
    "contact_wrench",
    "exp_so3",
    "log_so3",
    "normalize_hidden",
    "pad_energy",
    "pad_law",
    "pad_normal_force",
    "pad_ring",
    "pad_spring_force",
    "replay_rig6",
    "simulate_rig6",
    "step5",
    "wrench",
    "wrench_jacobians",
]

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")


def exp_so3(theta: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``theta`` [rad] (Rodrigues)."""
    x, y, z = theta
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:  # series, exact to double precision below 1e-6 rad
        s, c = 1.0 - a2 / 6.0, 0.5 - a2 / 24.0
    else:
        a = math.sqrt(a2)
        s, c = math.sin(a) / a, (1.0 - math.cos(a)) / a2
    hat = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * hat + c * (hat @ hat)


def log_so3(rot: np.ndarray) -> np.ndarray:
    """Rotation vector [rad] of the rotation matrix ``rot`` (angle below pi)."""
    w = 0.5 * np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    sin_a = math.sqrt(w @ w)
    angle = math.atan2(sin_a, 0.5 * (np.trace(rot) - 1.0))
    return w * (angle / sin_a if sin_a > 1e-12 else 1.0 + angle * angle / 6.0)


def pad_ring(pad_count: int, ring_radius_m: float, pad_radius_m: float) -> np.ndarray:
    """Pad centres in the port frame, ``(N, 3)`` [m]: a ring whose tops lie in z_P = 0."""
    phi = 2.0 * np.pi * np.arange(pad_count) / pad_count
    z = np.full(pad_count, -pad_radius_m)
    return np.column_stack([ring_radius_m * np.cos(phi), ring_radius_m * np.sin(phi), z])


# --- the pad law (docs/run6-format.md, "The pad law") ----------------------------


@dataclass(frozen=True)
class PadLaw:
    """What one pad's normal force has beyond Drake's point contact ``k x (1 + d xdot)``.

    Per pad (a ring of ``N`` pads shares the contact's totals: :func:`pad_law`):
    ``f_e = k_pad x_ref ((x - s_pad f_e) / x_ref)^n`` (solved for ``f_e``),
    ``f_n = f_e (1 + d xdot) + c_pad xdot + F_pad tanh(xdot / v_F)``, nothing
    where ``f_n <= 0``. The default is Drake's point contact.

    Attributes
    ----------
    exponent : float
        ``n`` (1), above 0.
    reference_press_m : float or None
        ``x_ref`` (m), above 0; needed only when ``n != 1``.
    damping_n_s_per_m : float
        ``c_pad = c / N`` (N s/m), at least 0.
    compliance_m_per_n : float
        ``s_pad = s N`` (m/N), at least 0: the structure behind the pad.
    friction_force_n : float
        ``F_pad = F / N`` (N), at least 0.
    friction_velocity_m_per_s : float or None
        ``v_F`` (m/s), above 0; needed only when ``F_pad > 0``.
    """

    exponent: float = 1.0
    reference_press_m: float | None = None
    damping_n_s_per_m: float = 0.0
    compliance_m_per_n: float = 0.0
    friction_force_n: float = 0.0
    friction_velocity_m_per_s: float | None = None

    def __post_init__(self):
        for name in ("exponent", "damping_n_s_per_m", "compliance_m_per_n", "friction_force_n"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"pad law: {name} = {value} is not finite")
        if not self.exponent > 0.0:
            raise ValueError(f"pad law: exponent = {self.exponent} must be above 0")
        for name in ("damping_n_s_per_m", "compliance_m_per_n", "friction_force_n"):
            if getattr(self, name) < 0.0:
                raise ValueError(f"pad law: {name} = {getattr(self, name)} must be at least 0")
        x_ref, v_f = self.reference_press_m, self.friction_velocity_m_per_s
        if self.exponent != 1.0 and not (x_ref is not None and math.isfinite(x_ref) and x_ref > 0):
            raise ValueError(
                f"pad law: an exponent {self.exponent} needs a reference press above 0, not {x_ref}"
            )
        if self.friction_force_n > 0.0 and not (
            v_f is not None and math.isfinite(v_f) and v_f > 0.0
        ):
            raise ValueError(
                f"pad law: a normal friction force needs a friction velocity above 0, not {v_f}"
            )

    @property
    def plain(self) -> bool:
        """Drake's point contact: a linear spring, nothing beside or behind it."""
        return (
            self.exponent == 1.0
            and self.damping_n_s_per_m == 0.0
            and self.compliance_m_per_n == 0.0
            and self.friction_force_n == 0.0
        )

    @property
    def dissipative(self) -> bool:
        """Whether the law has a term in the penetration rate besides Hunt-Crossley's."""
        return self.damping_n_s_per_m > 0.0 or self.friction_force_n > 0.0


def pad_law(
    pad_count: int,
    *,
    contact_exponent: float = 1.0,
    reference_press_m: float | None = None,
    contact_damping_n_s_per_m: float = 0.0,
    series_compliance_m_per_n: float = 0.0,
    normal_friction_force_n: float = 0.0,
    normal_friction_velocity_m_per_s: float | None = None,
) -> PadLaw:
    """One pad's :class:`PadLaw` from the contact's totals (the scenario's ``[contact]``
    keys): ``c / N``, ``s N``, ``F / N`` per pad, ``n``, ``x_ref``, ``v_F`` shared."""
    n = int(pad_count)
    return PadLaw(
        exponent=float(contact_exponent),
        reference_press_m=None if reference_press_m is None else float(reference_press_m),
        damping_n_s_per_m=float(contact_damping_n_s_per_m) / n,
        compliance_m_per_n=float(series_compliance_m_per_n) * n,
        friction_force_n=float(normal_friction_force_n) / n,
        friction_velocity_m_per_s=None
        if normal_friction_velocity_m_per_s is None
        else float(normal_friction_velocity_m_per_s),
    )


def _spring(y, k_pad, law):
    """The pad's own spring at deflection ``y >= 0``: ``k_pad x_ref (y / x_ref)^n``."""
    if law.exponent == 1.0:
        return k_pad * y
    x_ref = law.reference_press_m
    return k_pad * x_ref * (y / x_ref) ** law.exponent


def _deflection(x, k_pad, law, max_iter=200):
    """The pad spring's deflection ``y`` in ``(0, x]`` and force ``f = g(y)`` with
    ``y + s_pad f = x`` (``g`` the spring), for pads pressed ``x > 0``.

    Newton from the side where it converges monotonically: on ``y`` from ``y = x``
    for ``n >= 1`` (``y + s g(y) - x`` convex), on ``f`` from ``f = g(x)`` for
    ``n < 1`` (``g^-1(f) + s f - x`` convex); each iterate stays above the root,
    so a step that no longer shrinks it ends the search.
    """
    x = np.asarray(x, dtype=float)
    s, n = law.compliance_m_per_n, law.exponent
    if s == 0.0:
        return x.copy(), _spring(x, k_pad, law)
    x_ref = law.reference_press_m
    eps = 4.0 * np.finfo(float).eps
    if n >= 1.0:
        y = x.copy()
        for _ in range(max_iter):
            g = _spring(y, k_pad, law)
            step = (y + s * g - x) / (1.0 + s * n * g / y)
            if not (step > eps * y).any():
                break
            y = np.where(step > 0.0, y - step, y)
        return y, _spring(y, k_pad, law)
    f = _spring(x, k_pad, law)
    for _ in range(max_iter):
        y = x_ref * (f / (k_pad * x_ref)) ** (1.0 / n)  # g^-1(f)
        step = (y + s * f - x) / (y / (n * f) + s)
        if not (step > eps * f).any():
            break
        f = np.where(step > 0.0, f - step, f)
    return x_ref * (f / (k_pad * x_ref)) ** (1.0 / n), f


def pad_spring_force(x, k_pad_n_per_m, law: PadLaw | None = None):
    """``f_e`` (N) of pads pressed ``x > 0`` (m): ``k_pad x_ref ((x - s_pad f_e) / x_ref)^n``
    solved for ``f_e`` (``n = 1``: ``k_pad x / (1 + k_pad s_pad)``)."""
    law = PadLaw() if law is None else law
    x = np.asarray(x, dtype=float)
    if law.exponent == 1.0:
        return k_pad_n_per_m * x / (1.0 + k_pad_n_per_m * law.compliance_m_per_n)
    return _deflection(x, k_pad_n_per_m, law)[1]


def pad_normal_force(x, xdot, k_pad_n_per_m, d_s_per_m=0.0, law: PadLaw | None = None):
    """``f_n`` (N, at least 0) of pads pressed ``x > 0`` (m) at the rate ``xdot`` (m/s):
    ``f_e (1 + d xdot) + c_pad xdot + F_pad tanh(xdot / v_F)``, 0 where that is not above 0.
    With the default law this is Drake's ``k x max(1 + d xdot, 0)``, number for number."""
    x, xdot = np.asarray(x, dtype=float), np.asarray(xdot, dtype=float)
    if law is None or law.plain:
        return k_pad_n_per_m * x * np.maximum(1.0 + d_s_per_m * xdot, 0.0)
    f = pad_spring_force(x, k_pad_n_per_m, law) * (1.0 + d_s_per_m * xdot)
    if law.damping_n_s_per_m != 0.0:
        f = f + law.damping_n_s_per_m * xdot
    if law.friction_force_n != 0.0:
        f = f + law.friction_force_n * np.tanh(xdot / law.friction_velocity_m_per_s)
    return np.maximum(f, 0.0)


def pad_energy(x, k_pad_n_per_m, law: PadLaw | None = None):
    """Elastic energy (J) stored in pads pressed ``x > 0``: the spring's
    ``k_pad x_ref^2 (y / x_ref)^(n+1) / (n + 1)`` at its deflection ``y`` and the
    structure's ``s_pad f_e^2 / 2`` (``k_pad x^2 / 2`` with the default law)."""
    x = np.asarray(x, dtype=float)
    if law is None or law.plain:
        return 0.5 * k_pad_n_per_m * x**2
    if law.exponent == 1.0:
        f = pad_spring_force(x, k_pad_n_per_m, law)
        y = x - law.compliance_m_per_n * f
    else:
        y, f = _deflection(x, k_pad_n_per_m, law)
    return f * y / (law.exponent + 1.0) + 0.5 * law.compliance_m_per_n * f**2


def wrench(q, qd, pads, k_pad_n_per_m, d_s_per_m=0.0, pad_radius_m=0.01, law=None):
    """Contact wrench on the chaser at the port origin, and the pad penetrations.

    Each pad pressed ``x = delta > 0`` at the rate ``xdot`` (the port's velocity
    at the pad, along +z: into the plate) pushes back along -z with
    :func:`pad_normal_force` (``law``: docs/run6-format.md, "The pad law").

    Parameters
    ----------
    q, qd : array (6,)
        Port pose ``[p_P (m); theta (rad)]`` and rate ``[v_P (m/s); omega (rad/s)]``.
    pads : array (N, 3)
        Pad centres in the port frame [m].
    k_pad_n_per_m, d_s_per_m, pad_radius_m : float
        Stiffness of one pad [N/m], Hunt-Crossley dissipation [s/m], pad radius [m].
    law : PadLaw, optional
        One pad's law beyond Drake's point contact (default: none).

    Returns
    -------
    w : array (6,)
        ``[moment (N m); force (N)]``.
    delta : array (N,)
        Penetration of each pad [m] (in contact where > 0).
    """
    b = pads @ exp_so3(q[3:]).T  # lever arms from the port origin, world frame
    delta = q[2] + b[:, 2] + pad_radius_m
    on = delta > 0.0
    fz = np.zeros(len(b))
    if on.any():
        om = qd[3:]
        rate = qd[2] + om[0] * b[on, 1] - om[1] * b[on, 0]  # (v_P + omega x b)_z
        if law is None or law.plain:
            fz[on] = -k_pad_n_per_m * delta[on] * np.maximum(1.0 + d_s_per_m * rate, 0.0)
        else:
            fz[on] = -pad_normal_force(delta[on], rate, k_pad_n_per_m, d_s_per_m, law)
    w = np.array([b[:, 1] @ fz, -(b[:, 0] @ fz), 0.0, 0.0, 0.0, fz.sum()])
    return w, delta


def wrench_jacobians(q, qd, *args, step=1e-7, damped=False):
    """``K = -dw/dq`` and ``C = -dw/dqd`` (6x6) by central differences of :func:`wrench`.

    ``args`` are those of :func:`wrench` after ``q, qd``; ``C`` is zero unless ``damped``.
    """
    jac = []
    for x, other, first in ((q, qd, True), (qd, q, False)):
        cols = []
        for j in range(6 if (first or damped) else 0):
            e = np.zeros(6)
            e[j] = step
            plus = wrench(*((x + e, other) if first else (other, x + e)), *args)[0]
            minus = wrench(*((x - e, other) if first else (other, x - e)), *args)[0]
            cols.append(-(plus - minus) / (2.0 * step))
        jac.append(np.column_stack(cols) if cols else np.zeros((6, 6)))
    return jac[0], jac[1]


def _table_update(freq_hz: float, zeta: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """``Phi`` (2x2) and ``Gamma`` (2,) of one tick of ``x'' = w^2 (u - x) - 2 zeta w x'``."""
    w = 2.0 * math.pi * freq_hz
    e = expm(np.array([[0.0, 1.0, 0.0], [-w * w, -2.0 * zeta * w, w * w], [0.0, 0.0, 0.0]]) * h)
    return e[:2, :2], e[:2, 2]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


# --- hidden effects: what the rig does that its scenario does not say ----------

#: Drake's stiction tolerance: the slip speed [m/s] at which friction is full.
STICTION_TOLERANCE_M_PER_S = 1e-4

#: Where the table starts (``simulate_rig6(table_start=...)``): ``"previous_tick"``,
#: rig6's first reading: at tick -1 the table is at the command less its ramp lag,
#: and tick 0 reads it one tick later; ``"tick0"``: tick 0 reads the table at the
#: command less its ramp lag (docs/run6-format.md, "The table starts tracking the
#: approach: at the command less its ramp lag 2 zeta / omega times the speed,
#: moving at the speed", read at the record's first tick).
TABLE_STARTS = ("previous_tick", "tick0")

#: The library's effects of a six-axis rig (docs/run6-format.md, "The effects, as
#: laws"): each one's parameters and their null values (``None``: the scenario's).
LIBRARY_EFFECTS: dict[str, dict[str, float | None]] = {
    "stiffness_error": {"contact_stiffness_n_per_m": None},
    "hunt_crossley": {"damping_factor_s_per_m": 0.0},
    "friction_across_face": {"extra_friction_coefficient": 0.0},
    "extra_delay": {"extra_delay_s": 0.0},
    "sensor_filter": {"time_constant_s": 0.0},
    "force_bias": {"bias_n": 0.0},
    "sensor_misalignment": {"sensor_roll_rad": 0.0, "sensor_pitch_rad": 0.0, "sensor_yaw_rad": 0.0},
    "sensor_crosstalk": {"fz_to_fx": 0.0, "fz_to_fy": 0.0, "fz_to_mx_m": 0.0, "fz_to_my_m": 0.0},
    "table_misalignment": {"table_roll_rad": 0.0, "table_pitch_rad": 0.0, "table_yaw_rad": 0.0},
    "table_response": {"table_response_ratio": 1.0},
    "table_damping": {"table_damping_factor": 1.0},
    "com_offset": {"com_x_m": 0.0, "com_y_m": 0.0, "com_z_m": 0.0},
    # outside when this generator was written; the library now has the law
    "mount_resonance": {"mount_frequency_hz": math.inf, "mount_damping_ratio": 0.1},
    # the pad law's terms (docs/run6-format.md, "The pad law"), appended last so
    # that the earlier effects keep their places in the draws
    "contact_damping": {"damping_n_s_per_m": 0.0},
    "nonlinear_stiffness": {"exponent": 1.0, "reference_stiffness_n_per_m": None},
    "series_compliance": {"series_compliance_m_per_n": 0.0},
    "coulomb_friction": {"friction_force_n": 0.0},
    # a structural mode between the table's servo and its device, appended last so
    # that the earlier effects keep their places in the draws (``inf``: no mode)
    "table_resonance": {"frequency_hz": math.inf, "damping_ratio": 0.05},
}

#: Effects outside the library, physically plausible for a six-axis rig, none a
#: combination of the library's (their laws: :func:`simulate_rig6`).
OUTSIDE_EFFECTS: dict[str, dict[str, float | None]] = {
    "lateral_backlash": {"backlash_x_m": 0.0, "backlash_y_m": 0.0},
    "pad_proud": {"proud_m": 0.0, "pad_index": 0},
    "fz_quadratic_gain": {"gain_per_n": 0.0},
    "lateral_lag": {"lateral_response_ratio": 1.0},
}

#: The part of the rig each effect acts on.
EFFECT_PARTS: dict[str, str] = {
    "stiffness_error": "contact",
    "hunt_crossley": "contact",
    "friction_across_face": "contact",
    "contact_damping": "contact",
    "nonlinear_stiffness": "contact",
    "series_compliance": "contact",
    "coulomb_friction": "contact",
    "pad_proud": "contact",
    "extra_delay": "sensor_dynamics",
    "sensor_filter": "sensor_dynamics",
    "mount_resonance": "sensor_dynamics",
    "force_bias": "sensor_statics",
    "sensor_misalignment": "sensor_statics",
    "sensor_crosstalk": "sensor_statics",
    "fz_quadratic_gain": "sensor_statics",
    "table_misalignment": "table",
    "table_response": "table",
    "table_damping": "table",
    "lateral_backlash": "table",
    "lateral_lag": "table",
    "table_resonance": "table",
    "com_offset": "computer",
}


def normalize_hidden(hidden: Mapping | None) -> dict[str, dict[str, float | None]]:
    """The hidden effects with every parameter: ``{effect: {parameter: value}}``.

    Parameters
    ----------
    hidden : mapping or None
        An effect of :data:`LIBRARY_EFFECTS` or :data:`OUTSIDE_EFFECTS` to its
        parameters; a parameter not given takes its null value (the effect then
        does nothing through it). ``None`` or ``{}``: nothing hidden.

    Returns
    -------
    dict
        Each effect given, with all its parameters as floats.

    Raises
    ------
    ValueError
        An unknown effect or parameter, a value that is not a finite number
        (``mount_frequency_hz`` and ``frequency_hz`` may be ``inf``: no mount
        resonance, no table resonance), or one out
        of its range (a ratio, factor, frequency, exponent or reference
        stiffness not above 0, a negative time constant, delay, width, height,
        contact damping, series compliance or normal friction force, a damping
        ratio not above 0).
    """
    out: dict[str, dict[str, float | None]] = {}
    for name, params in (hidden or {}).items():
        known = LIBRARY_EFFECTS.get(name, OUTSIDE_EFFECTS.get(name))
        if known is None:
            raise ValueError(
                f"hidden effect {name!r}: one of {sorted(LIBRARY_EFFECTS) + sorted(OUTSIDE_EFFECTS)}"
            )
        params = dict(params or {})
        unknown = set(params) - set(known)
        if unknown:
            raise ValueError(f"hidden effect {name}: {sorted(unknown)} not among {sorted(known)}")
        full = dict(known)
        for key, value in params.items():
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
                raise ValueError(f"hidden effect {name}: {key} = {value!r} is not a number")
            value = float(value)
            if math.isnan(value) or (math.isinf(value) and key not in _MAY_BE_INFINITE):
                raise ValueError(f"hidden effect {name}: {key} = {value} is not finite")
            full[key] = value
        out[name] = full
    _check_ranges(out)
    return out


#: The parameters whose ``inf`` is a value: no mode at all.
_MAY_BE_INFINITE = frozenset({"mount_frequency_hz", "frequency_hz"})


def _check_ranges(effects: Mapping[str, Mapping[str, float | None]]) -> None:
    positive = (
        "contact_stiffness_n_per_m",
        "table_response_ratio",
        "table_damping_factor",
        "mount_frequency_hz",
        "mount_damping_ratio",
        "frequency_hz",
        "damping_ratio",
        "lateral_response_ratio",
        "exponent",
        "reference_stiffness_n_per_m",
    )
    non_negative = (
        "extra_friction_coefficient",
        "damping_n_s_per_m",
        "series_compliance_m_per_n",
        "friction_force_n",
        "extra_delay_s",
        "time_constant_s",
        "backlash_x_m",
        "backlash_y_m",
        "proud_m",
        "pad_index",
    )
    for name, params in effects.items():
        for key, value in params.items():
            if value is None:
                continue
            if key in positive and not value > 0.0:
                raise ValueError(f"hidden effect {name}: {key} = {value} must be above 0")
            if key in non_negative and value < 0.0:
                raise ValueError(f"hidden effect {name}: {key} = {value} must be at least 0")


def step5(x):
    """Drake's smooth step ``x^3 (10 - 15 x + 6 x^2)`` on ``[0, 1]``, 1 above."""
    x = np.minimum(np.asarray(x, dtype=float), 1.0)
    return x**3 * (10.0 + x * (6.0 * x - 15.0))


def contact_wrench(
    q,
    qd,
    pads,
    k_pad_n_per_m,
    d_s_per_m=0.0,
    pad_radius_m=0.01,
    friction_coefficient=0.0,
    stiction_m_per_s=STICTION_TOLERANCE_M_PER_S,
    law=None,
):
    """:func:`wrench` with the pads' regularized Coulomb friction across the face.

    Each touching pad's contact point is half-way between its deepest surface
    point (``delta`` into the plate) and the face: ``x_c = (c_x, c_y, delta / 2)``
    for a pad centre ``c``. The device's point there moves at ``v_P + omega x
    (x_c - p_P)``; its slip ``s t`` is that velocity along the face (x, y). The pad
    pushes the spacecraft with ``-mu(s) f_n t``, ``f_n`` its normal force
    (:func:`pad_normal_force`: ``k delta max(1 + d xdot, 0)`` with the default
    law; none, and so no friction, where it is not above 0), ``mu(s) = mu
    step5(s / v_s)`` (Drake's regularized friction, ``v_s = stiction_m_per_s``),
    about the port origin with the lever ``x_c - p_P``. Without friction
    (``friction_coefficient = 0``) this is :func:`wrench`, number for number.

    Parameters
    ----------
    q, qd, pads, k_pad_n_per_m, d_s_per_m, pad_radius_m, law
        As :func:`wrench`'s.
    friction_coefficient : float
        ``mu`` (1).
    stiction_m_per_s : float
        ``v_s`` (m/s), Drake's stiction tolerance by default.

    Returns
    -------
    w : array (6,)
        ``[moment about the port origin (N m); force (N)]`` on the chaser.
    delta : array (N,)
        Penetration of each pad [m].
    """
    w, delta = wrench(q, qd, pads, k_pad_n_per_m, d_s_per_m, pad_radius_m, law)
    on = delta > 0.0
    if friction_coefficient <= 0.0 or not on.any():
        return w, delta
    b = pads[on] @ exp_so3(q[3:]).T
    dep = delta[on]
    om = np.asarray(qd[3:], dtype=float)
    rate = qd[2] + om[0] * b[:, 1] - om[1] * b[:, 0]
    f_n = pad_normal_force(dep, rate, k_pad_n_per_m, d_s_per_m, law)
    lever = b.copy()
    lever[:, 2] = b[:, 2] + pad_radius_m - 0.5 * dep  # x_c - p_P
    vel = np.asarray(qd[:3], dtype=float) + np.cross(om, lever)
    slip = vel[:, :2]
    s = np.hypot(slip[:, 0], slip[:, 1])
    moving = s > 0.0
    t = np.zeros_like(slip)
    t[moving] = slip[moving] / s[moving, None]
    push = -(friction_coefficient * step5(s / stiction_m_per_s) * f_n)[:, None] * t
    fx, fy = push[:, 0], push[:, 1]
    moment = np.array(
        [
            -(lever[:, 2] @ fy),
            lever[:, 2] @ fx,
            lever[:, 0] @ fy - lever[:, 1] @ fx,
        ]
    )
    return w + np.concatenate([moment, [fx.sum(), fy.sum(), 0.0]]), delta


def _first_order_hold_mount(freq_hz: float, zeta: float, h: float):
    """``F`` (2x2), ``G0``, ``G1`` (2,) of ``y'' = w^2 (u - y) - 2 zeta w y'`` over one
    tick with ``u`` linear between the ticks: ``s[k] = F s[k-1] + G0 u[k-1] + G1 u[k]``."""
    w = 2.0 * math.pi * freq_hz
    a = np.zeros((4, 4))
    a[0, 1] = 1.0
    a[1] = [-w * w, -2.0 * zeta * w, w * w, 0.0]
    a[2, 3] = 1.0  # u(t) = u0 + du t
    e = expm(a * h)
    return e[:2, :2], e[:2, 2] - e[:2, 3] / h, e[:2, 3] / h


def _resonance_update(
    servo_hz: float, servo_zeta: float, mode_hz: float, mode_zeta: float, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """``Phi`` (n x n) and ``Gamma`` (n x 2) of one tick of a table's servo and the
    structural mode behind it, under the command ``[u, u']`` held over the tick
    (docs/run6-format.md, ``table_resonance``): ``s[k] = Phi s[k-1] + Gamma [u; u']``.

    The servo ``[x, x']`` follows the table model's ``x'' = w^2 (u - x) - 2 zeta w x'``
    (it reads ``u`` only), the device ``[y, y']`` follows ``y'' = w_r^2 (x - y) +
    2 zeta_r w_r (x' - y')``: the state is ``[x, x', y, y']`` (n = 4). An ideal
    servo (``servo_hz = inf``) is ``x = u``, ``x' = u'``: the state is ``[y, y']``
    (n = 2). Exact: the exponential of ``[[A, B], [0, 0]] h``.
    """
    wr = 2.0 * math.pi * mode_hz
    k_r, c_r = wr * wr, 2.0 * mode_zeta * wr
    if math.isinf(servo_hz):
        a = np.array([[0.0, 1.0], [-k_r, -c_r]])
        b = np.array([[0.0, 0.0], [k_r, c_r]])
    else:
        w = 2.0 * math.pi * servo_hz
        a = np.array(
            [
                [0.0, 1.0, 0.0, 0.0],
                [-w * w, -2.0 * servo_zeta * w, 0.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
                [k_r, c_r, -k_r, -c_r],
            ]
        )
        b = np.array([[0.0, 0.0], [w * w, 0.0], [0.0, 0.0], [0.0, 0.0]])
    n = len(a)
    big = np.zeros((n + 2, n + 2))
    big[:n, :n], big[:n, n:] = a, b
    e = expm(big * h)
    return e[:n, :n], e[:n, n:]


class _Table:
    """The table's physical part: its response, structural mode, turned axes,
    lateral lag and backlash."""

    def __init__(self, response_hz, damping_ratio, h, effects, table_start, miss):
        self.ideal = math.isinf(response_hz)
        self.shift = np.array([miss[0], miss[1], 0.0], dtype=float)
        self.start_at_tick0 = table_start == "tick0"
        tm = effects.get("table_misalignment")
        self.rot = None
        if tm is not None:
            self.rot = exp_so3(
                np.array([tm["table_roll_rad"], tm["table_pitch_rad"], tm["table_yaw_rad"]])
            )
        bl = effects.get("lateral_backlash")
        self.backlash = None
        if bl is not None and (bl["backlash_x_m"] > 0.0 or bl["backlash_y_m"] > 0.0):
            self.backlash = np.array([bl["backlash_x_m"], bl["backlash_y_m"]])
        tr = effects.get("table_resonance")
        self.mode = None  # (Phi, Gamma) per coordinate: (6, n, n), (6, n, 2)
        if self.ideal:
            if tr is not None and math.isfinite(tr["frequency_hz"]):
                phi, gam = _resonance_update(
                    math.inf, 0.0, tr["frequency_hz"], tr["damping_ratio"], h
                )
                self.mode = (np.stack([phi] * 6), np.stack([gam] * 6))
            return
        freq = response_hz * effects.get("table_response", {}).get("table_response_ratio", 1.0)
        zeta = damping_ratio * effects.get("table_damping", {}).get("table_damping_factor", 1.0)
        ratio = effects.get("lateral_lag", {}).get("lateral_response_ratio", 1.0)
        phi, gam = _table_update(freq, zeta, h)
        lag = 2.0 * zeta / (2.0 * math.pi * freq)
        if ratio != 1.0:  # px, py respond at ratio times the frequency
            phi_xy, gam_xy = _table_update(freq * ratio, zeta, h)
            phi = np.stack([phi_xy] * 2 + [phi] * 4, axis=-1)  # (2, 2, 6)
            gam = np.stack([gam_xy] * 2 + [gam] * 4, axis=-1)  # (2, 6)
            lag = np.array([lag / ratio] * 2 + [lag] * 4)
        self.phi, self.gam, self.lag = phi, gam, lag
        if tr is not None and math.isfinite(tr["frequency_hz"]):
            f_r, z_r = tr["frequency_hz"], tr["damping_ratio"]
            axes = [_resonance_update(freq, zeta, f_r, z_r, h)] * 6
            if ratio != 1.0:
                axes[:2] = [_resonance_update(freq * ratio, zeta, f_r, z_r, h)] * 2
            self.mode = (np.stack([a[0] for a in axes]), np.stack([a[1] for a in axes]))

    def _command(self, q_cmd, qd_cmd):
        if self.rot is None:
            return q_cmd, qd_cmd
        r, s = self.rot, self.shift  # the table is turned about W's origin
        return (
            np.concatenate([r @ (q_cmd[:3] + s) - s, r @ q_cmd[3:]]),
            np.concatenate([r @ qd_cmd[:3], r @ qd_cmd[3:]]),
        )

    def start(self, q_cmd, qd_cmd):
        """The table tracking the approach, commanded ``q_cmd`` at ``qd_cmd``."""
        u, ud = self._command(q_cmd, qd_cmd)
        if not self.ideal:
            self.x, self.xd = u - self.lag * ud, ud.copy()
        if self.mode is not None:  # servo and device where the table starts: unstrained
            x, xd = (u, ud) if self.ideal else (self.x, self.xd)
            self.s = np.stack([x, xd] if self.ideal else [x, xd, x, xd])  # (n, 6)
        self.first = True
        self.out = None if self.backlash is None else (u if self.ideal else self.x)[:2].copy()

    def advance(self, q_cmd, qd_cmd):
        """The pose and rate the table reaches at this tick under the command held
        since the last one (the encoders read the pose)."""
        hold = self.first and self.start_at_tick0
        self.first = False
        if self.mode is not None:  # the device behind the servo: what is seen
            if not hold:
                u, ud = self._command(q_cmd, qd_cmd)
                phi, gam = self.mode
                self.s = np.einsum("cij,jc->ic", phi, self.s) + np.einsum(
                    "cij,jc->ic", gam, np.stack([u, ud])
                )
            q_act, qd_act = self.s[-2].copy(), self.s[-1].copy()
        elif self.ideal:
            q_act, qd_act = self._command(q_cmd, qd_cmd)
        else:
            if not hold:
                u = self._command(q_cmd, qd_cmd)[0]
                phi, gam = self.phi, self.gam
                self.x, self.xd = (
                    phi[0, 0] * self.x + phi[0, 1] * self.xd + gam[0] * u,
                    phi[1, 0] * self.x + phi[1, 1] * self.xd + gam[1] * u,
                )
            q_act, qd_act = self.x, self.xd
        if self.backlash is None:
            return q_act, qd_act
        q_act, qd_act = q_act.copy(), qd_act.copy()
        half = 0.5 * self.backlash
        inner = q_act[:2]
        self.out = np.clip(self.out, inner - half, inner + half)
        gap = inner - self.out
        driven = (gap * qd_act[:2] > 0.0) & (np.abs(gap) >= half * (1.0 - 1e-12))
        q_act[:2] = self.out
        qd_act[:2] = np.where(driven | (half == 0.0), qd_act[:2], 0.0)
        return q_act, qd_act


class _Sensor:
    """The F/T sensor's physical part: low pass and mount, delay line, turn,
    cross-talk, gain nonlinearity and bias (a reading ``[m; f]`` at each tick)."""

    def __init__(self, n_delay, n_ticks, h, effects):
        self.n = n_delay
        self.history = np.zeros((n_delay + n_ticks, 6))  # history[k + n] = chain(w_act[k])
        tau = effects.get("sensor_filter", {}).get("time_constant_s", 0.0)
        self.filter = None
        if tau > 0.0:
            a = math.exp(-h / tau)
            c = tau * (1.0 - a) / h
            self.filter = (a, c - a, 1.0 - c)
            self.y, self.u_prev = np.zeros(6), np.zeros(6)
        mount = effects.get("mount_resonance")
        self.mount = None
        if mount is not None and math.isfinite(mount["mount_frequency_hz"]):
            self.mount = _first_order_hold_mount(
                mount["mount_frequency_hz"], mount["mount_damping_ratio"], h
            )
            self.mount_scale = 1.0 / (2.0 * math.pi * mount["mount_frequency_hz"])
            self.s, self.v_prev = np.zeros((2, 6)), np.zeros(6)
        sm = effects.get("sensor_misalignment")
        self.rot = None
        if sm is not None:
            self.rot = exp_so3(
                np.array([sm["sensor_roll_rad"], sm["sensor_pitch_rad"], sm["sensor_yaw_rad"]])
            )
        ct = effects.get("sensor_crosstalk")
        self.crosstalk = None
        if ct is not None:
            self.crosstalk = np.array(
                [ct["fz_to_mx_m"], ct["fz_to_my_m"], 0.0, ct["fz_to_fx"], ct["fz_to_fy"], 0.0]
            )
        self.gain = effects.get("fz_quadratic_gain", {}).get("gain_per_n", 0.0)
        self.bias = effects.get("force_bias", {}).get("bias_n", 0.0)
        self.static = self.rot is not None or self.crosstalk is not None
        self.static = self.static or self.gain != 0.0 or self.bias != 0.0
        self.dynamic = self.filter is not None or self.mount is not None
        self.peak = 0.0

    def statics(self, w):
        """The reading of the sensor's channels carrying ``w`` (the delay line's output)."""
        if not self.static:
            return w
        m, f = w[:3], w[3:]
        if self.rot is not None:
            m, f = self.rot @ m, self.rot @ f
        out = np.concatenate([m, f])
        if self.crosstalk is not None:
            out = out + self.crosstalk * out[5]
        if self.gain != 0.0:
            out[5] = out[5] + self.gain * out[5] * abs(out[5])
        if self.bias != 0.0:
            out[5] = out[5] - self.bias
        return out

    def read(self, k, w_act):
        """Push the contact's wrench of tick ``k``; the reading of tick ``k``."""
        u = w_act
        if self.dynamic:
            self.peak = max(self.peak, float(np.abs(u).max()))
        if self.filter is not None:
            a, b0, b1 = self.filter
            self.y = a * self.y + b0 * self.u_prev + b1 * u
            self.u_prev = u
            u = self.y
        if self.mount is not None:
            big_f, g0, g1 = self.mount
            self.s = big_f @ self.s + np.outer(g0, self.v_prev) + np.outer(g1, u)
            self.v_prev = u
            u = self.s[0]
        self.history[k + self.n] = u
        return self.statics(self.history[k])

    def pending(self, k) -> bool:
        """Whether a contact's wrench is still on its way to the reading after tick
        ``k`` (with a static effect, or at it: the rig computer's compensated
        wrench need not fall to zero then)."""
        if not (self.dynamic or self.static):
            return bool(self.history[k + 1 : k + self.n + 1].any())
        tol = 1e-4 * self.peak  # a tail within the noise of any rig (0 without dynamics)
        if np.abs(self.history[k : k + self.n + 1]).max() > tol:
            return True
        if self.filter is not None and np.abs(self.y).max() > tol:
            return True
        return self.mount is not None and (
            np.abs(self.s[0]).max() > tol or self.mount_scale * np.abs(self.s[1]).max() > tol
        )


class _Physics:
    """The rig's physical part (table, contact, sensor) under the hidden effects."""

    def __init__(
        self,
        *,
        pads,
        k_pad,
        d,
        pad_radius,
        pad_count,
        table_response_hz,
        table_damping_ratio,
        h,
        n_delay,
        n_ticks,
        effects,
        table_start,
        miss,
        contact=None,
        mass_kg=None,
        approach_speed=None,
    ):
        if table_start not in TABLE_STARTS:
            raise ValueError(f"table_start must be one of {TABLE_STARTS}, not {table_start!r}")
        true_pads = pads
        proud = effects.get("pad_proud")
        if proud is not None and proud["proud_m"] > 0.0:
            i = int(proud["pad_index"])
            if i != proud["pad_index"] or not 0 <= i < len(pads):
                raise ValueError(
                    f"pad_proud: pad_index {proud['pad_index']} not in 0..{len(pads) - 1}"
                )
            true_pads = pads.copy()
            true_pads[i, 2] += proud["proud_m"]  # its top stands proud towards the face
        k_true = effects.get("stiffness_error", {}).get("contact_stiffness_n_per_m")
        k_true_pad = k_pad if k_true is None else k_true / pad_count
        d_true = max(d + effects.get("hunt_crossley", {}).get("damping_factor_s_per_m", 0.0), 0.0)
        self.mu = effects.get("friction_across_face", {}).get("extra_friction_coefficient", 0.0)
        k_true_pad, self.law = _true_pad_law(
            dict(contact or {}), effects, pad_count, k_pad, k_true_pad, mass_kg, approach_speed
        )
        self.args = (true_pads, k_true_pad, d_true, pad_radius)
        extra = effects.get("extra_delay", {}).get("extra_delay_s", 0.0) / h
        n_extra = round(extra)
        if abs(extra - n_extra) > 1e-9 * max(1.0, extra):
            raise ValueError(f"extra_delay_s {extra * h} is not a whole number of ticks of {h} s")
        self.table = _Table(table_response_hz, table_damping_ratio, h, effects, table_start, miss)
        self.sensor = _Sensor(n_delay + n_extra, n_ticks, h, effects)

    def start(self, q_cmd, qd_cmd):
        self.table.start(q_cmd, qd_cmd)

    def tick(self, k, q_cmd, qd_cmd):
        """Tick ``k`` under the command of tick ``k - 1``: the table's pose and rate,
        the contact's wrench, the pads' penetrations and the sensor's reading."""
        q_act, qd_act = self.table.advance(q_cmd, qd_cmd)
        if self.mu > 0.0:
            w_act, delta = contact_wrench(q_act, qd_act, *self.args, self.mu, law=self.law)
        else:
            w_act, delta = wrench(q_act, qd_act, *self.args, self.law)
        return q_act, qd_act, w_act, delta, self.sensor.read(k, w_act)


#: The scenario's ``[contact]`` keys of the pad law beyond Drake's point contact
#: (docs/run6-format.md, "The pad law"), and their defaults.
PAD_LAW_KEYS: dict[str, float | None] = {
    "contact_exponent": 1.0,
    "reference_press_m": None,
    "contact_damping_n_s_per_m": 0.0,
    "series_compliance_m_per_n": 0.0,
    "normal_friction_force_n": 0.0,
    "normal_friction_velocity_m_per_s": None,
}


def _true_pad_law(contact, effects, pad_count, k_pad, k_true_pad, mass_kg, approach_speed):
    """The rig's own pad stiffness (N/m, one pad) and :class:`PadLaw`: the scenario's
    ``[contact]`` (``contact``: :data:`PAD_LAW_KEYS` and ``contact_stiffness_n_per_m``)
    under the hidden pad-law effects (docs/run6-format.md, "The effects, as laws"):

    - ``contact_damping``: ``damping_n_s_per_m`` added to ``contact_damping_n_s_per_m``;
    - ``nonlinear_stiffness``: the stiffness is ``reference_stiffness_n_per_m``
      (``None``: the scenario's ``k``), ``contact_exponent`` is ``exponent`` and
      ``reference_press_m`` is ``v0 sqrt(m / k)`` (``k`` the scenario's);
    - ``series_compliance``: ``series_compliance_m_per_n`` added to the contact's;
    - ``coulomb_friction``: ``friction_force_n`` added to ``normal_friction_force_n``,
      and ``normal_friction_velocity_m_per_s`` is ``0.02 v0``.
    """
    law = {key: contact.get(key, default) for key, default in PAD_LAW_KEYS.items()}
    k_scen = contact.get("contact_stiffness_n_per_m", k_pad * pad_count)
    cd = effects.get("contact_damping")
    if cd is not None:
        law["contact_damping_n_s_per_m"] += cd["damping_n_s_per_m"]
    ns = effects.get("nonlinear_stiffness")
    if ns is not None:
        k_ref = ns["reference_stiffness_n_per_m"]
        k_true_pad = k_pad if k_ref is None else k_ref / pad_count
        law["contact_exponent"] = ns["exponent"]
        law["reference_press_m"] = approach_speed * math.sqrt(mass_kg / k_scen)
    sc = effects.get("series_compliance")
    if sc is not None:
        law["series_compliance_m_per_n"] += sc["series_compliance_m_per_n"]
    cf = effects.get("coulomb_friction")
    if cf is not None:
        law["normal_friction_force_n"] += cf["friction_force_n"]
        law["normal_friction_velocity_m_per_s"] = 0.02 * approach_speed
    return k_true_pad, pad_law(pad_count, **law)


def _delay_ticks(sensor_delay_s: float, sample_rate_hz: float) -> int:
    delay = sensor_delay_s * sample_rate_hz
    n_delay = round(delay)
    if abs(delay - n_delay) > 1e-9 * max(1.0, delay):
        h = 1.0 / sample_rate_hz
        raise ValueError(f"sensor_delay_s {sensor_delay_s} is not a whole number of ticks of {h} s")
    return n_delay


def simulate_rig6(
    *,
    mass_kg: float = 2533.03,
    inertia_kg_m2=(1689.0, 1689.0, 1689.0),
    port_distance_m: float = 1.5,
    lateral_offset_m=(0.0, 0.0),
    misalignment_rad=(0.0, 0.0),
    contact_stiffness_n_per_m: float = 1e5,
    hunt_crossley_dissipation_s_per_m: float = 0.0,
    pad_count: int = 8,
    ring_radius_m: float = 0.3,
    pad_radius_m: float = 0.01,
    contact_exponent: float = 1.0,
    reference_press_m: float | None = None,
    contact_damping_n_s_per_m: float = 0.0,
    series_compliance_m_per_n: float = 0.0,
    normal_friction_force_n: float = 0.0,
    normal_friction_velocity_m_per_s: float | None = None,
    table_response_hz: float = math.inf,
    table_damping_ratio: float = 0.8,
    sample_rate_hz: float = 1000.0,
    sensor_delay_s: float = 0.0,
    compensator: str = "none",
    lead_time_s: float | None = None,
    force_deadband_n: float = 0.0,
    initial_velocity_m_per_s: float = 0.1,
    initial_gap_m: float = 0.001,
    duration_s: float | None = None,
    fd_step: float = 1e-7,
    hidden: Mapping | None = None,
    table_start: str = "previous_tick",
    lateral_miss_m=(0.0, 0.0),
    hold_s: float = 0.05,
) -> dict:
    """One contact of the 6-DoF hybrid docking loop (SI units throughout).

    ``misalignment_rad = (roll, pitch)`` gives the initial attitude
    ``Ry(pitch) Rx(roll)``; the port starts on the docking axis, ``initial_gap_m``
    from the plane (measured at the pad nearest to it), moving at
    ``initial_velocity_m_per_s`` along +z, with no angular velocity.
    ``duration_s=None`` stops ``hold_s`` (0.05 s) after the contact ends.

    ``hidden`` gives the rig's physical part (and, for ``com_offset``, the rig
    computer's spacecraft) effects the arguments do not say: ``{effect:
    {parameter: value}}`` of :data:`LIBRARY_EFFECTS` (docs/run6-format.md, "The
    effects, as laws") or :data:`OUTSIDE_EFFECTS` (:func:`normalize_hidden`).
    The rig computer keeps the arguments' beliefs: its compensator's contact
    model (the nominal pads, stiffness, dissipation and pad law, no friction), its lead
    time (the nominal ``sensor_delay_s`` unless ``lead_time_s``) and its dead
    band. The library's laws:

    - ``stiffness_error``: the contact's total stiffness is
      ``contact_stiffness_n_per_m`` (each pad's ``1 / pad_count`` of it);
    - ``hunt_crossley``: ``damping_factor_s_per_m`` added to the dissipation
      (at least 0);
    - ``contact_damping``, ``nonlinear_stiffness``, ``series_compliance``,
      ``coulomb_friction``: the pad law's terms (:func:`_true_pad_law`): a
      dashpot ``damping_n_s_per_m`` beside the pads (``c / N`` each); the
      pads' stiffness ``reference_stiffness_n_per_m`` as a power law of
      ``exponent`` about ``x_ref = v0 sqrt(m / k)``; a compliance
      ``series_compliance_m_per_n`` behind the ring (``s N`` behind each pad);
      a force ``friction_force_n`` against the penetration rate (``F / N``
      each, ``tanh(xdot / (0.02 v0))``), each added to the arguments' own;
    - ``friction_across_face``: ``extra_friction_coefficient`` of regularized
      Coulomb friction at each touching pad (:func:`contact_wrench`);
    - ``extra_delay``: ``extra_delay_s`` (whole ticks) added to the sensor's delay;
    - ``sensor_filter``: each channel ``u[k]`` of the contact's wrench is read
      through ``y[k] = a y[k-1] + b0 u[k-1] + b1 u[k]`` (``a = exp(-h / tau)``,
      ``c = tau (1 - a) / h``, ``b0 = c - a``, ``b1 = 1 - c``, zero before the
      record), before the delay;
    - ``force_bias``: the reading's ``fz`` is ``fz - bias_n`` (every tick);
    - ``sensor_misalignment``: the reading is ``[R m; R f]``, ``R = exp((roll,
      pitch, yaw))``;
    - ``sensor_crosstalk``: ``fx + fz_to_fx fz``, ``fy + fz_to_fy fz``,
      ``mx + fz_to_mx_m fz``, ``my + fz_to_my_m fz``, with the turned reading's
      ``fz``;
    - ``table_misalignment``: commanded ``[p; theta]`` and ``[v; omega]``, the
      table tracks ``[R p; R theta]`` and ``[R v; R omega]``; the encoders read
      the pose reached;
    - ``table_response``, ``table_damping``: the table model's natural
      frequency times ``table_response_ratio``, its damping ratio times
      ``table_damping_factor`` (its start's ramp lag is its own);
    - ``table_resonance`` (``frequency_hz`` ``f_r``, ``damping_ratio``
      ``zeta_r``): a structural mode between the table's servo and its device,
      on each of the six pose coordinates: the servo ``[x, x']`` follows the
      table model's law (it reads the command's pose ``u``; the ideal table's
      servo is ``x = u``, ``x' = u'``), the device ``[y, y']`` follows ``y'' =
      w_r^2 (x - y) + 2 zeta_r w_r (x' - y')`` (``w_r = 2 pi f_r``), and the
      device's pose and twist are what the contact and the encoders see. The
      command ``[u, u']`` is held over each tick, the states solved exactly
      (:func:`_resonance_update`); servo and device start where the table
      starts, at its speed (the mode unstrained). ``f_r = inf``: no mode. With
      a backlash (outside the library) the play is behind the device;
    - ``com_offset``: the rig computer's spacecraft has its centre of mass
      ``(com_x_m, com_y_m, com_z_m)`` (body frame) from the arguments': its port
      sits at ``[lateral_offset_m - (com_x, com_y), port_distance_m - com_z]``
      from it; the port's initial pose, the table and the contact are unchanged;
    - ``mount_resonance`` (``mount_frequency_hz`` ``f``, ``mount_damping_ratio``
      ``zeta``): the F/T sensor sits on a compliant, lightly damped mount; each
      channel reads ``y'' = w^2 (u - y) - 2 zeta w y'`` (``w = 2 pi f``) of the
      contact's wrench ``u``, solved exactly per tick with ``u`` linear between
      the ticks, zero before the record; before the delay. (Written as an
      effect outside the library; the library has since taken the law in.)

    The sensor chain is, in this order: the low pass, the mount resonance
    (below), the delay line, the turn, the cross-talk, the gain nonlinearity
    and the bias.

    The effects outside the library (:data:`OUTSIDE_EFFECTS`):

    - ``lateral_backlash`` (``backlash_x_m``, ``backlash_y_m``, total widths):
      a backlash in the table's x (y) axis. The table model's output ``x``
      drives the stage through play: the stage stays where it is while ``x``
      moves within ``+- width / 2`` of it, and is dragged at ``x -+ width / 2``
      beyond (``out[k] = clip(out[k-1], x - width / 2, x + width / 2)``, the
      play centred at the start); it moves at the model's rate when dragged,
      else not. The encoders read the stage. Outside: the library's table
      effects are linear and time-invariant in the command.
    - ``pad_proud`` (``proud_m``, ``pad_index``): one pad of the ring stands
      ``proud_m`` proud of the others towards the face (its centre at
      ``z_P = -pad_radius + proud_m``): it touches first and carries more of
      the load. The initial gap is the nominal ring's. Outside: the library
      changes every pad alike (stiffness, dissipation, friction), never the
      ring's geometry.
    - ``fz_quadratic_gain`` (``gain_per_n``, 1/N): the normal channel's gain
      grows with the load: the reading's ``fz`` is ``fz + g fz |fz|`` (after
      the turn and cross-talk, before the bias). Outside: every library sensor
      effect is linear in the wrench or constant.
    - ``lateral_lag`` (``lateral_response_ratio``): the table's lateral axes
      (``px``, ``py``) respond at the ratio times the table model's natural
      frequency (same damping ratio), the axial axis and the attitude at the
      model's own. Outside: ``table_response`` changes every axis alike.
      A finite table only.

    ``table_start`` (:data:`TABLE_STARTS`): ``"previous_tick"`` (the default,
    rig6's first reading) puts the table at the command less its ramp lag at
    tick -1, so tick 0 reads it a tick later; ``"tick0"`` puts it there at
    tick 0.

    ``lateral_miss_m`` is where the port starts across the target's axis
    (x, y). rig6 runs the loop on the axis, and the record is shifted by it
    (the plate is infinite and flat: the contact does not change); only a
    turned table (``table_misalignment``), which turns the commanded position
    about W's origin, sees it: it tracks ``R (p + miss) - miss`` in rig6's frame.

    Parameters
    ----------
    mass_kg, inertia_kg_m2, port_distance_m, lateral_offset_m, misalignment_rad
        The spacecraft (kg, kg m^2 as three principal values or a 3x3 matrix,
        m, m, rad) and its initial attitude.
    contact_stiffness_n_per_m, hunt_crossley_dissipation_s_per_m
        The contact: total stiffness (N/m), Hunt-Crossley dissipation (s/m).
    contact_exponent, reference_press_m, contact_damping_n_s_per_m
        The pad law (docs/run6-format.md, "The pad law"; the ring's totals, as
        the scenario's ``[contact]`` keys): the springs' exponent ``n`` (1),
        their reference press ``x_ref`` (m; needed when ``n != 1``), a dashpot
        ``c`` (N s/m) beside them,
    series_compliance_m_per_n, normal_friction_force_n, normal_friction_velocity_m_per_s
        a compliance ``s`` (m/N) behind them, a friction force ``F`` (N) against
        the penetration rate, smoothed over ``v_F`` (m/s; needed when ``F > 0``).
    pad_count, ring_radius_m, pad_radius_m
        The pad ring (m).
    table_response_hz, table_damping_ratio
        The table model (``inf``: the ideal table).
    sample_rate_hz, sensor_delay_s
        The rig computer's rate (Hz) and the sensor's delay (s, whole ticks).
    compensator, lead_time_s, force_deadband_n
        The rig computer's compensator (:data:`COMPENSATORS`), its lead (s;
        default the delay) and dead band (N, on the measured force's norm).
    initial_velocity_m_per_s, initial_gap_m, duration_s, hold_s
        The approach (m/s, m) and the record's length (s; see above).
    fd_step : float
        The MDC's central-difference step.
    hidden : mapping or None
        The hidden effects (:func:`normalize_hidden`).
    table_start : str
        One of :data:`TABLE_STARTS`.
    lateral_miss_m : pair of float
        The port's start across the target's axis (m).

    Returns
    -------
    dict
        Arrays (one row per tick): ``t_s``, ``port_velocity_z_m_per_s``,
        ``kinetic_energy_j``, ``total_energy_j``, ``wrench_act`` (the
        contact's), ``wrench_mea`` (the sensor's reading the rig computer used,
        without measurement noise) and ``wrench_comp`` (N, 6), ``q_des``,
        ``qd_des`` (the port's pose and twist after the tick's update),
        ``q_act`` and ``qd_act`` (the table's) (N, 6), ``in_contact`` (N,),
        ``com_position_m`` (N, 3), ``angular_momentum_n_m_s`` (N, 3, world frame,
        about the centre of mass); ``command_initial`` and
        ``command_rate_initial`` (6,), the command held before tick 0;
        ``port_position_model_m`` (3,), the port from the computer's centre of
        mass; scalars ``cor_normal``, ``energy_ratio``, ``peak_force_n``,
        ``peak_moment_n_m``, ``contact_duration_s``.

    Raises
    ------
    ValueError
        If the sensor delay (or a hidden extra delay) is not a whole number of
        ticks, the compensator is unknown or a hidden effect is refused
        (:func:`normalize_hidden`).
    RuntimeError
        If no contact happens or it does not end within the default duration.
    """
    if compensator not in COMPENSATORS:
        raise ValueError(f"compensator must be one of {COMPENSATORS}, not {compensator!r}")
    effects = normalize_hidden(hidden)
    if "lateral_lag" in effects and math.isinf(table_response_hz):
        raise ValueError("lateral_lag: an ideal table has no response to slow down")
    h = 1.0 / sample_rate_hz
    n_delay = _delay_ticks(sensor_delay_s, sample_rate_hz)
    lead = sensor_delay_s if lead_time_s is None else lead_time_s
    use_sdc, use_mdc = compensator in ("SDC", "SDMDC"), compensator in ("MDC", "SDMDC")
    m = float(mass_kg)
    inertia = np.asarray(inertia_kg_m2, dtype=float)
    inertia = np.diag(inertia) if inertia.ndim == 1 else inertia
    inertia_inv = np.linalg.inv(inertia)
    r_port = np.array([lateral_offset_m[0], lateral_offset_m[1], port_distance_m], dtype=float)
    if "com_offset" in effects:
        c = effects["com_offset"]
        r_port = r_port - np.array([c["com_x_m"], c["com_y_m"], c["com_z_m"]])
    pads = pad_ring(pad_count, ring_radius_m, pad_radius_m)
    k_pad, d = contact_stiffness_n_per_m / pad_count, hunt_crossley_dissipation_s_per_m
    contact = {
        "contact_stiffness_n_per_m": contact_stiffness_n_per_m,
        "contact_exponent": contact_exponent,
        "reference_press_m": reference_press_m,
        "contact_damping_n_s_per_m": contact_damping_n_s_per_m,
        "series_compliance_m_per_n": series_compliance_m_per_n,
        "normal_friction_force_n": normal_friction_force_n,
        "normal_friction_velocity_m_per_s": normal_friction_velocity_m_per_s,
    }
    law = pad_law(pad_count, **{key: contact[key] for key in PAD_LAW_KEYS})
    args = (pads, k_pad, d, pad_radius_m, law)  # the rig computer's contact model

    # initial state: the nearest pad top `initial_gap_m` from the plane, port on the axis
    roll, pitch = misalignment_rad
    rot = exp_so3(np.array([0.0, pitch, 0.0])) @ exp_so3(np.array([roll, 0.0, 0.0]))
    v0 = float(initial_velocity_m_per_s)
    z_port = -initial_gap_m - pad_radius_m - (pads @ rot.T)[:, 2].max()
    p = np.array([0.0, 0.0, z_port]) - rot @ r_port
    v = np.array([0.0, 0.0, v0])
    om_b = np.zeros(3)
    q_cmd = np.concatenate([p + rot @ r_port, log_so3(rot)])
    qd_cmd = np.concatenate([v, np.zeros(3)])
    command_initial, command_rate_initial = q_cmd.copy(), qd_cmd.copy()

    t_contact = math.pi * math.sqrt(m / contact_stiffness_n_per_m)
    t_max = duration_s if duration_s is not None else initial_gap_m / v0 + 10 * t_contact + 1.0
    n_max = int(round(t_max / h)) + 1
    physics = _Physics(
        pads=pads,
        k_pad=k_pad,
        d=d,
        pad_radius=pad_radius_m,
        pad_count=pad_count,
        table_response_hz=table_response_hz,
        table_damping_ratio=table_damping_ratio,
        h=h,
        n_delay=n_delay,
        n_ticks=n_max,
        effects=effects,
        table_start=table_start,
        miss=lateral_miss_m,
        contact=contact,
        mass_kg=m,
        approach_speed=v0,
    )
    physics.start(q_cmd, qd_cmd)  # steady tracking of the approach ramp
    sensor = physics.sensor
    hold_ticks = int(math.ceil(hold_s / h))
    names = ("q_act", "q_des", "wrench_act", "wrench_comp", "port_velocity_z_m_per_s")
    names += ("kinetic_energy_j", "total_energy_j", "com_position_m", "angular_momentum_n_m_s")
    names += ("wrench_mea", "qd_act", "qd_des")
    rows: dict[str, list] = {name: [] for name in names}
    in_contact = []
    w_prev = np.zeros(6)
    quiet, touched = 0, False
    for k in range(n_max):
        # 1. the table's pose under the command sent at tick k-1, the contact, the sensor
        q_act, qd_act, w_act, delta, w_mea = physics.tick(k, q_cmd, qd_cmd)
        # 2. the compensator
        w_c = np.zeros(6)
        if np.linalg.norm(w_mea[3:]) > force_deadband_n:
            w_c = w_mea.copy()
            if use_sdc:
                w_c += lead * (w_mea - w_prev) / h
            if use_mdc:
                damped = d > 0.0 or law.dissipative
                K, C = wrench_jacobians(q_act, qd_act, *args, step=fd_step, damped=damped)
                w_c -= K @ (q_cmd - q_act) + C @ (qd_cmd - qd_act)
        w_prev = w_mea
        # 3. the spacecraft: semi-implicit Euler; its new port pose and rate are the command
        f = w_c[3:]
        tau = w_c[:3] + _cross(rot @ r_port, f)
        v = v + h * f / m
        p = p + h * v
        om_b = om_b + h * (inertia_inv @ (rot.T @ tau - _cross(om_b, inertia @ om_b)))
        rot = rot @ exp_so3(h * om_b)
        lever, om_w = rot @ r_port, rot @ om_b
        q_cmd = np.concatenate([p + lever, log_so3(rot)])
        qd_cmd = np.concatenate([v + _cross(om_w, lever), om_w])
        ke = 0.5 * m * (v @ v) + 0.5 * om_b @ inertia @ om_b
        own = wrench(q_cmd, qd_cmd, *args)[1]  # penetrations at the spacecraft's own pose
        if law.plain:
            pe = 0.5 * k_pad * np.sum(np.maximum(own, 0.0) ** 2)
        else:
            pe = float(pad_energy(own[own > 0.0], k_pad, law).sum())
        row = (q_act, q_cmd, w_act, w_c, qd_cmd[2], ke, ke + pe, p, rot @ inertia @ om_b)
        row += (w_mea, qd_act, qd_cmd)
        for name, value in zip(names, row, strict=True):
            rows[name].append(value)
        in_contact.append(bool((delta > 0.0).any()))
        touched = touched or in_contact[-1]
        plain = not (sensor.static or sensor.dynamic)  # else w_c may never be exactly 0
        busy = in_contact[-1] or sensor.pending(k) or (plain and w_c.any())
        quiet = 0 if busy else quiet + 1
        if duration_s is None and touched and quiet >= hold_ticks:
            break
    else:
        if duration_s is None:
            raise RuntimeError(f"the contact did not end within {t_max:.3g} s")
    out = {name: np.array(rows[name]) for name in names}
    out["t_s"] = h * np.arange(len(in_contact))
    out["in_contact"] = np.array(in_contact)
    out["command_initial"], out["command_rate_initial"] = command_initial, command_rate_initial
    out["port_position_model_m"] = r_port
    return out | _metrics(out, np.array(in_contact), h, v0, 0.5 * m * v0 * v0)


#: The keyword arguments of :func:`simulate_rig6` the rig's physical part uses.
#: (``mass_kg`` and ``initial_velocity_m_per_s`` only for the scales of the
#: ``nonlinear_stiffness`` and ``coulomb_friction`` laws: ``v0 sqrt(m / k)``, ``0.02 v0``.)
PHYSICAL_ARGUMENTS = (
    "contact_stiffness_n_per_m",
    "hunt_crossley_dissipation_s_per_m",
    "pad_count",
    "ring_radius_m",
    "pad_radius_m",
    "table_response_hz",
    "table_damping_ratio",
    "sample_rate_hz",
    "sensor_delay_s",
    *PAD_LAW_KEYS,
    "mass_kg",
    "initial_velocity_m_per_s",
)


def replay_rig6(
    command_initial,
    command_rate_initial,
    q_des,
    qd_des,
    *,
    hidden: Mapping | None = None,
    table_start: str = "previous_tick",
    lateral_miss_m=(0.0, 0.0),
    **rig,
) -> dict:
    """The rig's physical part driven by recorded commands (no rig computer).

    Tick ``k`` holds the command of tick ``k - 1`` (``q_des[k-1]``, ``qd_des[k-1]``;
    ``command_initial``, ``command_rate_initial`` for tick 0), as in
    :func:`simulate_rig6`, whose physical keyword arguments (:data:`PHYSICAL_ARGUMENTS`,
    with their defaults; any other is ignored, so a ``simulate_rig6`` argument
    dict can be passed whole), ``hidden``, ``table_start`` and ``lateral_miss_m``
    it takes. The
    table starts tracking the initial command at its rate.

    Parameters
    ----------
    command_initial, command_rate_initial : array (6,)
        The pose and rate commanded before tick 0 (``simulate_rig6``'s).
    q_des, qd_des : array (N, 6)
        The commands of the ticks (the port's pose and twist after each update).
    hidden, table_start, lateral_miss_m
        As :func:`simulate_rig6`'s.
    **rig
        :func:`simulate_rig6`'s keyword arguments (others are ignored).

    Returns
    -------
    dict
        ``q_act``, ``qd_act``, ``wrench_act``, ``wrench_mea`` (N, 6) and
        ``in_contact`` (N,).
    """
    defaults = {
        "contact_stiffness_n_per_m": 1e5,
        "hunt_crossley_dissipation_s_per_m": 0.0,
        "pad_count": 8,
        "ring_radius_m": 0.3,
        "pad_radius_m": 0.01,
        "table_response_hz": math.inf,
        "table_damping_ratio": 0.8,
        "sample_rate_hz": 1000.0,
        "sensor_delay_s": 0.0,
        **PAD_LAW_KEYS,
        "mass_kg": 2533.03,
        "initial_velocity_m_per_s": 0.1,
    }
    par = defaults | {k: v for k, v in rig.items() if k in PHYSICAL_ARGUMENTS}
    effects = normalize_hidden(hidden)
    h = 1.0 / par["sample_rate_hz"]
    q_des, qd_des = np.asarray(q_des, dtype=float), np.asarray(qd_des, dtype=float)
    n = len(q_des)
    pads = pad_ring(par["pad_count"], par["ring_radius_m"], par["pad_radius_m"])
    physics = _Physics(
        pads=pads,
        k_pad=par["contact_stiffness_n_per_m"] / par["pad_count"],
        d=par["hunt_crossley_dissipation_s_per_m"],
        pad_radius=par["pad_radius_m"],
        pad_count=par["pad_count"],
        table_response_hz=par["table_response_hz"],
        table_damping_ratio=par["table_damping_ratio"],
        h=h,
        n_delay=_delay_ticks(par["sensor_delay_s"], par["sample_rate_hz"]),
        n_ticks=n,
        effects=effects,
        table_start=table_start,
        miss=lateral_miss_m,
        contact={key: par[key] for key in ("contact_stiffness_n_per_m", *PAD_LAW_KEYS)},
        mass_kg=par["mass_kg"],
        approach_speed=par["initial_velocity_m_per_s"],
    )
    q_cmd = np.asarray(command_initial, dtype=float)
    qd_cmd = np.asarray(command_rate_initial, dtype=float)
    physics.start(q_cmd, qd_cmd)
    names = ("q_act", "qd_act", "wrench_act", "delta", "wrench_mea")
    rows: dict[str, list] = {name: [] for name in names}
    for k in range(n):
        if k:
            q_cmd, qd_cmd = q_des[k - 1], qd_des[k - 1]
        for name, value in zip(names, physics.tick(k, q_cmd, qd_cmd), strict=True):
            rows[name].append(value)
    out = {name: np.array(rows[name]) for name in names}
    out["in_contact"] = np.any(out.pop("delta") > 0.0, axis=1)
    return out


def _metrics(out: dict, in_contact: np.ndarray, h: float, v0: float, ke0: float) -> dict:
    """CoR, energy ratio (both against the last tick before the model felt a wrench),
    peak force and moment of w_act, contact time."""
    pushed = np.flatnonzero(np.any(out["wrench_comp"] != 0.0, axis=1))
    if not len(pushed) or not in_contact.any():
        raise RuntimeError("no contact happened")
    j = pushed[0] - 1  # the last tick before the compensated wrench is first non-zero
    v_in = out["port_velocity_z_m_per_s"][j] if j >= 0 else v0
    ke = out["kinetic_energy_j"]
    ke_in = ke[j] if j >= 0 else ke0
    w = out["wrench_act"]
    # The port's normal velocity keeps changing after the contact while the
    # body turns: take it just after the last wrench the model felt.
    v_out = out["port_velocity_z_m_per_s"][pushed[-1]]
    return {
        "cor_normal": abs(v_out) / abs(v_in),
        "energy_ratio": ke[-1] / ke_in,
        "peak_force_n": float(np.linalg.norm(w[:, 3:], axis=1).max()),
        "peak_moment_n_m": float(np.linalg.norm(w[:, :3], axis=1).max()),
        "contact_duration_s": float(in_contact.sum() * h),
    }
