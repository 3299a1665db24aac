"""The contact model: a unilateral spring k_con with optional viscous damping.

``f_act = max(k p_act + c v_act, 0)`` while ``p_act > 0`` (penetration), and
zero when the devices are apart: the contact pushes, never pulls.

The contact is the second swappable back-end of the hybrid loop: input
``motion`` (3), outputs ``force`` (1) and ``force_rate`` (1).
"""

from __future__ import annotations

from dataclasses import dataclass

from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import LeafSystem_
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative, check_positive

__all__ = ["ContactParams", "UnilateralSpringContact", "UnilateralSpringContact_"]


@dataclass(frozen=True)
class ContactParams:
    """Parameters of the contact.

    Parameters
    ----------
    stiffness_n_per_m : float
        Contact stiffness k_con, > 0.
    damping_n_s_per_m : float
        Viscous contact damping c, >= 0 (the paper's contacts have none).
    """

    stiffness_n_per_m: float
    damping_n_s_per_m: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "stiffness_n_per_m", check_positive("stiffness_n_per_m", self.stiffness_n_per_m)
        )
        object.__setattr__(
            self,
            "damping_n_s_per_m",
            check_nonnegative("damping_n_s_per_m", self.damping_n_s_per_m),
        )


@TemplateSystem.define("UnilateralSpringContact_", T_list=[float, AutoDiffXd])
def UnilateralSpringContact_(T):
    class Impl(LeafSystem_[T]):
        """Unilateral spring-damper contact between the table's device and the
        passive device.

        Ports
        -----
        Input ``motion`` (size 3: m, m/s, m/s^2)
            ``[p_act, v_act, a_act]``, penetration and its rates.
        Output ``force`` (size 1, N)
            Actual contact force f_act, compression positive, zero apart.
        Output ``force_rate`` (size 1, N/s)
            d f_act / dt (``k v + c a`` in contact, zero apart); used by the
            continuous-time SDC in analysis.

        ``bilateral=True`` drops the unilateral gating (``f = k p + c v`` for
        any sign of ``p``), the linearization used by the stability analysis:
        ``max(p, 0)`` has zero slope at ``p = 0``.
        """

        def _construct(self, params: ContactParams, bilateral: bool = False, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.bilateral = bool(bilateral)
            self._k = params.stiffness_n_per_m
            self._c = params.damping_n_s_per_m
            self._motion = self.DeclareVectorInputPort("motion", 3)
            self.DeclareVectorOutputPort("force", 1, self._calc_force)
            self.DeclareVectorOutputPort("force_rate", 1, self._calc_force_rate)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.bilateral, converter=converter)

        def _in_contact(self, p, f):
            return self.bilateral or (p > 0.0 and f > 0.0)

        def _calc_force(self, context, output):
            p, v, _ = self._motion.Eval(context)
            f = self._k * p + self._c * v
            output.SetAtIndex(0, f if self._in_contact(p, f) else 0.0 * f)

        def _calc_force_rate(self, context, output):
            p, v, a = self._motion.Eval(context)
            f = self._k * p + self._c * v
            rate = self._k * v + self._c * a
            output.SetAtIndex(0, rate if self._in_contact(p, f) else 0.0 * rate)

    return Impl


UnilateralSpringContact = UnilateralSpringContact_[None]
