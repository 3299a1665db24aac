"""Contact laws beyond the linear spring: power law, viscous and Hunt-Crossley
damping, Coulomb friction, series compliance (:class:`ContactLaw`).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from pydrake.autodiffutils import AutoDiffXd
from pydrake.math import tanh
from pydrake.systems.framework import LeafSystem_
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative, check_positive
from hybridtable.laws.contact import hunt_crossley_force

__all__ = [
    "ContactLawParams",
    "ContactLaw",
    "ContactLaw_",
    "contact_law_force",
]


# -- contact -------------------------------------------------------------------
@dataclass(frozen=True)
class ContactLawParams:
    """A unilateral contact law, SI units.

    In contact (penetration ``d > 0``) the force is::

        f_e = k d_ref (d_c / d_ref)^n,   d_c = d - s f_e     (elastic, series compliance s)
        f   = f_e (1 + alpha v) + c v + F tanh(v / v_F)
        f   = max(f, 0)                                       (never pulls)

    and zero apart (``d <= 0``); ``v`` is the penetration rate.

    Parameters
    ----------
    stiffness_n_per_m : float
        ``k``: the stiffness (with ``n != 1`` the secant stiffness ``f_e / d``
        at ``d = reference_deflection_m``), > 0.
    exponent : float
        ``n`` of the power law, > 0 (1: a linear spring).
    reference_deflection_m : float
        ``d_ref`` of the power law, > 0 (unused when ``n == 1``).
    damping_n_s_per_m : float
        Viscous damping ``c``, >= 0.
    hunt_crossley_s_per_m : float
        Hunt-Crossley factor ``alpha``: damping ``alpha k d`` proportional to
        the deflection, >= 0.
    friction_force_n : float
        Coulomb friction ``F`` against the deflection rate, >= 0.
    friction_velocity_m_per_s : float
        ``v_F``: the sign of ``v`` is smoothed as ``tanh(v / v_F)``, > 0.
    series_compliance_m_per_n : float
        Compliance ``s`` of a structure between the table's position sensor
        and the contact (quasi-static: it takes the elastic force), >= 0.
    """

    stiffness_n_per_m: float
    exponent: float = 1.0
    reference_deflection_m: float = 1e-3
    damping_n_s_per_m: float = 0.0
    hunt_crossley_s_per_m: float = 0.0
    friction_force_n: float = 0.0
    friction_velocity_m_per_s: float = 1e-3
    series_compliance_m_per_n: float = 0.0

    def __post_init__(self) -> None:
        s = object.__setattr__
        for name in (
            "stiffness_n_per_m",
            "exponent",
            "reference_deflection_m",
            "friction_velocity_m_per_s",
        ):
            s(self, name, check_positive(name, getattr(self, name)))
        for name in (
            "damping_n_s_per_m",
            "hunt_crossley_s_per_m",
            "friction_force_n",
            "series_compliance_m_per_n",
        ):
            s(self, name, check_nonnegative(name, getattr(self, name)))

    @property
    def is_linear_spring(self) -> bool:
        return self.exponent == 1.0


def _elastic(params: ContactLawParams, d):
    """Elastic force ``f_e`` and its slope ``d f_e / d d`` at penetration
    ``d > 0`` (float or AutoDiffXd), with the series compliance solved."""
    k, n, s = params.stiffness_n_per_m, params.exponent, params.series_compliance_m_per_n
    if params.is_linear_spring:
        slope = k / (1.0 + k * s)
        return slope * d, slope + 0.0 * d
    dr = params.reference_deflection_m

    def g(x):  # power law and its derivative, x > 0
        gx = k * dr * (x / dr) ** n
        return gx, n * gx / x

    if s == 0.0:
        return g(d)
    # Solve phi(f) = f - g(d - s f) = 0 on (0, g(d)) by safeguarded Newton in
    # float, then one Newton step in T (exact first derivatives).
    dv = float(d.value()) if isinstance(d, AutoDiffXd) else float(d)
    # the root lies in (0, min(g(d), d / s)): the spring's own deflection d - s f is > 0
    lo, hi = 0.0, min(g(dv)[0], dv / s)
    f = min(g(dv)[0] / (1.0 + g(dv)[1] * s), 0.5 * hi)
    for _ in range(60):
        x = dv - s * f
        if x <= 0.0:  # too much force: the series compliance alone takes more than d
            hi = f
            f = 0.5 * (lo + hi)
            continue
        gx, dg = g(x)
        phi = f - gx
        if phi > 0.0:
            hi = f
        else:
            lo = f
        step = phi / (1.0 + s * dg)
        f_new = f - step
        if not lo <= f_new <= hi:
            f_new = 0.5 * (lo + hi)
        if abs(f_new - f) <= 1e-13 * max(abs(f), 1.0):
            f = f_new
            break
        f = f_new
    if not dv - s * f > 0.0:
        f = lo  # the bracket's force side whose spring deflection is > 0
    gx, dg = g(d - s * f)
    f_t = f - (f - gx) / (1.0 + s * dg)
    return f_t, dg / (1.0 + s * dg)


def contact_law_force(params: ContactLawParams, p, v, a=0.0):
    """Force and force rate of the contact law at penetration ``p``, rate
    ``v`` and acceleration ``a`` (float or AutoDiffXd)."""
    if not p > 0.0:
        return 0.0 * p, 0.0 * p
    fe, dfe = _elastic(params, p)
    alpha, c = params.hunt_crossley_s_per_m, params.damping_n_s_per_m
    big_f, vf = params.friction_force_n, params.friction_velocity_m_per_s
    f, dfdp, dfdv = hunt_crossley_force(fe, dfe, alpha, v)
    f = f + c * v
    dfdv = dfdv + c
    if big_f > 0.0:
        th = tanh(v / vf)
        f = f + big_f * th
        dfdv = dfdv + big_f / vf * (1.0 - th * th)
    if not f > 0.0:
        return 0.0 * f, 0.0 * f
    rate = dfdp * v + dfdv * a
    return f, rate


@TemplateSystem.define("ContactLaw_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__])
def ContactLaw_(T):
    class Impl(LeafSystem_[T]):
        """A unilateral contact with the law of :class:`ContactLawParams`.

        Ports
        -----
        Input ``motion`` (size 3: m, m/s, m/s^2)
            ``[p_act, v_act, a_act]`` of the table: penetration and rates.
        Output ``force`` (size 1, N)
            Contact force, compression positive, zero apart.
        Output ``force_rate`` (size 1, N/s)
            Its time derivative (zero apart).
        """

        def _construct(self, params: ContactLawParams, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            #: ``force_law(p, v, a) -> f``: the law this system evaluates.
            self.force_law = lambda p, v, a: contact_law_force(params, p, v, a)[0]
            #: The law is ``0 * p`` wherever ``not p > 0`` (apart): a replay
            #: evaluates it only in contact.
            self.force_law_unilateral = True
            self._motion = self.DeclareVectorInputPort("motion", 3)
            self.DeclareVectorOutputPort("force", 1, self._calc_force)
            self.DeclareVectorOutputPort("force_rate", 1, self._calc_force_rate)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, converter=converter)

        def _calc_force(self, context, output):
            p, v, a = self._motion.Eval(context)
            output.SetAtIndex(0, contact_law_force(self.params, p, v, a)[0])

        def _calc_force_rate(self, context, output):
            p, v, a = self._motion.Eval(context)
            output.SetAtIndex(0, contact_law_force(self.params, p, v, a)[1])

    return Impl


ContactLaw = ContactLaw_[None]
