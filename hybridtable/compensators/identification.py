"""Online identification of the contact's stiffness and damping.

The paper's MDC needs the contact stiffness k_con, which "should be identified
in real time from several past sampled contact force and position data
points"; with damping, Eq. 6 also needs the damping c_con. This module fits the
Kelvin-Voigt model

    f = k delta + c delta_dot = phi' theta,   phi = [delta, delta_dot]

to past (deflection, deflection rate, force) samples by recursive least
squares with exponential forgetting, in information form (numerically robust
when the data are far more informative than the prior):

    Y <- lambda Y + (1 - lambda) Y0 + phi phi' / sigma_f^2
    y <- lambda y + (1 - lambda) Y0 theta0 + phi f / sigma_f^2
    theta = Y^-1 y,                  lambda = exp(-h / forgetting_time_s)

``theta0 = [k_prior, c_prior]`` is the prior and
``Y0 = diag(1 / stiffness_std^2, 1 / damping_std^2)`` its information; the
estimate minimizes the prior-regularized, exponentially weighted squared
force error. The ``(1 - lambda) Y0`` terms ("stabilized forgetting") keep
``Y >= Y0``, so the covariance ``Y^-1`` never exceeds the prior's: no
wind-up, whatever the excitation.

Well-defined at every instant:

- *alignment*: the force the rig reads is ``T_fms`` old, so the identifier
  pairs it with the deflection of the same instant. In the Drake system the
  table motion goes through a delay line built like the force sensor's
  (:class:`ContactIdentifier`'s ``motion_delay``), so the pairs are exact;
- *contact onset and separation*: a sample is used only while both the
  measured force exceeds ``force_threshold_n`` and the aligned deflection is
  positive; outside contact the state is frozen, and before the first contact
  sample the estimate is the prior. A unilateral contact's force is clamped
  at zero when ``k delta + c delta_dot < 0`` (end of a damped contact); those
  samples read zero force and are skipped by the threshold;
- *noise*: ``force_noise_std_n`` weighs the data against the prior; the
  estimate is reported projected onto ``k >= 0``, ``c >= 0`` (the internal
  state is not clipped).

``damping_std_n_s_per_m = 0`` identifies the stiffness only (``c`` stays at its
prior).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.systems.framework import BasicVector_, Diagram, DiagramBuilder, LeafSystem_, System
from pydrake.systems.primitives import PassThrough
from pydrake.systems.scalar_conversion import TemplateSystem

from hybridtable._validation import check_nonnegative, check_positive, check_positive_or_inf
from hybridtable.errors import ParameterError

__all__ = [
    "IdentifierParams",
    "identifier_settings",
    "RecursiveContactIdentifier",
    "information_step",
    "rls_step",
    "estimate",
    "covariance",
    "in_contact",
    "forgetting_factor",
    "ContactIdentifierLeaf",
    "ContactIdentifierLeaf_",
    "ContactIdentifier",
]


@dataclass(frozen=True)
class IdentifierParams:
    """Parameters of the online contact identifier, SI units.

    Parameters
    ----------
    prior_stiffness_n_per_m : float
        Stiffness before any contact sample (the compensator's belief), > 0.
    prior_damping_n_s_per_m : float
        Damping before any contact sample, >= 0.
    stiffness_std_n_per_m : float
        Prior standard deviation of the stiffness, > 0 (default: equal to the
        prior stiffness, i.e. 100 %).
    damping_std_n_s_per_m : float
        Prior standard deviation of the damping, >= 0; 0 identifies the
        stiffness only.
    force_noise_std_n : float
        Standard deviation of the force measurement noise, > 0 (weighs the
        data against the prior; a small value trusts the data).
    forgetting_time_s : float
        Memory of the estimator, ``lambda = exp(-h / forgetting_time_s)`` per
        sample of period ``h``; ``math.inf``: no forgetting.
    force_threshold_n : float
        Samples whose measured force is at or below this are not used (the
        rig's contact deadband), >= 0.
    """

    prior_stiffness_n_per_m: float
    prior_damping_n_s_per_m: float = 0.0
    stiffness_std_n_per_m: float | None = None
    damping_std_n_s_per_m: float = 0.0
    force_noise_std_n: float = 1e-3
    forgetting_time_s: float = 0.1
    force_threshold_n: float = 0.0

    def __post_init__(self) -> None:
        s = object.__setattr__
        k = check_positive("prior_stiffness_n_per_m", self.prior_stiffness_n_per_m)
        s(self, "prior_stiffness_n_per_m", k)
        if self.stiffness_std_n_per_m is None:
            s(self, "stiffness_std_n_per_m", k)
        s(
            self,
            "stiffness_std_n_per_m",
            check_positive("stiffness_std_n_per_m", self.stiffness_std_n_per_m),
        )
        for name in ("prior_damping_n_s_per_m", "damping_std_n_s_per_m", "force_threshold_n"):
            s(self, name, check_nonnegative(name, getattr(self, name)))
        s(self, "force_noise_std_n", check_positive("force_noise_std_n", self.force_noise_std_n))
        s(
            self,
            "forgetting_time_s",
            check_positive_or_inf("forgetting_time_s", self.forgetting_time_s),
        )

    @property
    def estimates_damping(self) -> bool:
        """True when the damping is identified too."""
        return self.damping_std_n_s_per_m > 0.0

    def prior_information(self) -> tuple[float, float]:
        """Diagonal of ``Y0``: ``1 / stiffness_std^2`` and ``1 / damping_std^2``
        (0 when the damping is not identified: its row is unused)."""
        i_c = 1.0 / self.damping_std_n_s_per_m**2 if self.estimates_damping else 0.0
        return 1.0 / self.stiffness_std_n_per_m**2, i_c

    def initial_state(self) -> np.ndarray:
        """``[Y_kk, Y_kc, Y_cc, y_k, y_c]`` before any sample (the prior)."""
        i_k, i_c = self.prior_information()
        return np.array(
            [i_k, 0.0, i_c, i_k * self.prior_stiffness_n_per_m, i_c * self.prior_damping_n_s_per_m]
        )


def identifier_settings(
    prior_stiffness_n_per_m: float,
    force_deadband_n: float,
    force_noise_n: float = 0.0,
    /,
    **overrides,
) -> IdentifierParams:
    """The online identifiers' settings for a rig (the 1-D ``sdmdc-online`` and
    the 6-DoF one): the prior is the stiffness the compensator believes, its
    standard deviation 100 % of it; the noise a third of the force deadband
    or the sensor's force noise, whichever is larger (at least 1 mN); samples
    above the deadband; a memory of 0.1 s. Keyword arguments override any field
    of :class:`IdentifierParams` (e.g. the damping's prior and standard
    deviation)."""
    fields = {
        "prior_stiffness_n_per_m": prior_stiffness_n_per_m,
        "stiffness_std_n_per_m": prior_stiffness_n_per_m,
        "force_noise_std_n": max(force_deadband_n / 3.0, force_noise_n, 1e-3),
        "forgetting_time_s": 0.1,
        "force_threshold_n": force_deadband_n,
    }
    fields.update(overrides)
    return IdentifierParams(**fields)


def forgetting_factor(forgetting_time_s: float, period_s: float) -> float:
    """``lambda = exp(-period / forgetting_time)`` (1 for no forgetting)."""
    check_positive("period_s", period_s)
    return math.exp(-period_s / forgetting_time_s) if math.isfinite(forgetting_time_s) else 1.0


def in_contact(force, deflection, params: IdentifierParams) -> bool:
    """True when an aligned sample is usable: force above the threshold and
    positive deflection."""
    return bool(force > params.force_threshold_n and deflection > 0.0)


def information_step(Y, y, phi, target, lam, prior_information, prior_theta, weight):
    """One step of recursive least squares with stabilized forgetting, in
    information form, for any number of parameters and outputs:

        Y <- lam Y + (1 - lam) diag(Y0) + weight phi phi'
        y <- lam y + (1 - lam) diag(Y0) theta0 + weight phi target'

    ``Y`` (n x n) and ``y`` (n x m) as nested lists, ``phi`` (n) the regressor,
    ``target`` (m) the sample, ``prior_information`` the diagonal of ``Y0``
    (n), ``prior_theta`` ``theta0`` (n x m). Returns the new ``(Y, y)``
    (nested lists). Element by element, so it runs on any scalar type
    (float, AutoDiffXd). The 1-D identifier (:func:`rls_step`: two parameters,
    one output) and the 6-DoF one
    (:class:`~hybridtable.six_dof.identification.StiffnessIdentifier`: one
    parameter, the tick's six wrench components as six samples, forgetting
    applied with the first) are this step."""
    g = 1.0 - lam
    n = len(phi)
    wphi = [weight * phi[i] for i in range(n)]
    Y_new = [
        [
            lam * Y[i][j] + g * prior_information[i] + wphi[i] * phi[j]
            if i == j
            else lam * Y[i][j] + wphi[i] * phi[j]
            for j in range(n)
        ]
        for i in range(n)
    ]
    y_new = [
        [
            lam * y[i][r] + g * prior_information[i] * prior_theta[i][r] + wphi[i] * target[r]
            for r in range(len(target))
        ]
        for i in range(n)
    ]
    return Y_new, y_new


def rls_step(state, force, deflection, deflection_rate, lam: float, params: IdentifierParams):
    """One identifier step: the new information state
    ``[Y_kk, Y_kc, Y_cc, y_k, y_c]`` as a list (:func:`information_step` with
    ``phi = [delta, delta_dot]`` and the force as the one output).

    Works for any scalar type (float, AutoDiffXd) element-wise; returns
    ``state`` unchanged when the sample is outside contact
    (:func:`in_contact`).
    """
    ykk, ykc, ycc, yk, yc = state
    if not in_contact(force, deflection, params):
        return [ykk, ykc, ycc, yk, yc]
    x, xd = deflection, deflection_rate
    w = 1.0 / params.force_noise_std_n**2
    k0, c0 = params.prior_stiffness_n_per_m, params.prior_damping_n_s_per_m
    if not params.estimates_damping:
        # Known damping: fit k to the force minus the damping force.
        force = force - c0 * xd
        xd = 0.0 * xd
    Y, y = information_step(
        [[ykk, ykc], [ykc, ycc]],
        [[yk], [yc]],
        [x, xd],
        [force],
        lam,
        params.prior_information(),
        [[k0], [c0]],
        w,
    )
    return [Y[0][0], Y[0][1], Y[1][1], y[0][0], y[1][0]]


def estimate(state, params: IdentifierParams):
    """``(k, c)`` of an information state, projected onto ``k, c >= 0``."""
    ykk, ykc, ycc, yk, yc = state
    if params.estimates_damping:
        det = ykk * ycc - ykc * ykc
        k = (ycc * yk - ykc * yc) / det
        c = (ykk * yc - ykc * yk) / det
    else:
        k = yk / ykk
        c = 0.0 * k + params.prior_damping_n_s_per_m
    if k < 0.0:
        k = 0.0 * k
    if c < 0.0:
        c = 0.0 * c
    return k, c


def covariance(state, params: IdentifierParams) -> np.ndarray:
    """The 2x2 covariance ``Y^-1`` of a float state (zero damping row and
    column when the damping is not identified)."""
    ykk, ykc, ycc = (float(v) for v in state[:3])
    if not params.estimates_damping:
        return np.array([[1.0 / ykk, 0.0], [0.0, 0.0]])
    return np.linalg.inv(np.array([[ykk, ykc], [ykc, ycc]]))


class RecursiveContactIdentifier:
    """The identifier on sample arrays (offline use, tests, replays).

    Parameters
    ----------
    params : IdentifierParams
    period_s : float
        Sample period h (sets the forgetting factor per sample).

    Examples
    --------
    >>> ident = RecursiveContactIdentifier(IdentifierParams(5e4), 1e-3)
    >>> k, c = ident.update(force=100.0, deflection=1e-3, deflection_rate=0.0)
    """

    def __init__(self, params: IdentifierParams, period_s: float) -> None:
        self.params = params
        self.period_s = check_positive("period_s", period_s)
        self.lam = forgetting_factor(params.forgetting_time_s, period_s)
        self.state = list(params.initial_state())
        self.samples_used = 0

    @property
    def stiffness_n_per_m(self) -> float:
        return float(estimate(self.state, self.params)[0])

    @property
    def damping_n_s_per_m(self) -> float:
        return float(estimate(self.state, self.params)[1])

    @property
    def covariance(self) -> np.ndarray:
        """Covariance of the estimate ``[k, c]`` (never above the prior's)."""
        return covariance(self.state, self.params)

    def update(
        self, force: float, deflection: float, deflection_rate: float
    ) -> tuple[float, float]:
        """Use one aligned sample; return the estimate ``(k, c)``."""
        if in_contact(force, deflection, self.params):
            self.samples_used += 1
        self.state = rls_step(self.state, force, deflection, deflection_rate, self.lam, self.params)
        return self.stiffness_n_per_m, self.damping_n_s_per_m

    def run(
        self, force_n: np.ndarray, deflection_m: np.ndarray, deflection_rate_m_per_s: np.ndarray
    ) -> np.ndarray:
        """Estimates after each sample of aligned arrays, shape ``(n, 2)``."""
        f = np.asarray(force_n, dtype=float)
        x = np.asarray(deflection_m, dtype=float)
        xd = np.asarray(deflection_rate_m_per_s, dtype=float)
        if not (f.shape == x.shape == xd.shape and f.ndim == 1):
            raise ParameterError("force, deflection and deflection rate must be 1-D, same length")
        out = np.empty((f.size, 2))
        for i in range(f.size):
            out[i] = self.update(f[i], x[i], xd[i])
        return out


@TemplateSystem.define(
    "ContactIdentifierLeaf_", T_list=[float, AutoDiffXd], scope=sys.modules[__name__]
)
def ContactIdentifierLeaf_(T):
    class Impl(LeafSystem_[T]):
        """Recursive least-squares identifier of ``f = k delta + c delta_dot``,
        updated every ``period_s``.

        Ports
        -----
        Input ``measured_force`` (size 1, N)
            f_mea, the force sample.
        Input ``aligned_motion`` (size 3: m, m/s, m/s^2)
            ``[delta, delta_dot, _]``: the table motion of the instant the
            force sample was taken (delayed like the force).
        Output ``contact_parameters`` (size 2: N/m, N s/m)
            The estimate ``[k, c]`` (the prior before the first contact
            sample).

        Discrete state: the information ``[Y_kk, Y_kc, Y_cc, y_k, y_c]``.
        """

        def _construct(self, params: IdentifierParams, period_s: float, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self.params = params
            self.period_s = check_positive("period_s", period_s)
            self._lam = forgetting_factor(params.forgetting_time_s, period_s)
            self._f = self.DeclareVectorInputPort("measured_force", 1)
            self._motion = self.DeclareVectorInputPort("aligned_motion", 3)
            self._state = self.DeclareDiscreteState(params.initial_state())
            self.DeclarePeriodicDiscreteUpdateEvent(self.period_s, 0.0, self._update)
            self.DeclareVectorOutputPort(
                "contact_parameters",
                BasicVector_[T](2),
                self._output,
                {self.discrete_state_ticket(self._state)},
            )

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, other.params, other.period_s, converter=converter)

        def _update(self, context, discrete_state):
            x = context.get_discrete_state(self._state).value()
            f = self._f.Eval(context)[0]
            p, v, _ = self._motion.Eval(context)
            new = rls_step(list(x), f, p, v, self._lam, self.params)
            discrete_state.get_mutable_vector(self._state).SetFromVector(np.array(new))

        def _output(self, context, output):
            x = context.get_discrete_state(self._state).value()
            output.SetFromVector(np.array(estimate(list(x), self.params)))

    return Impl


ContactIdentifierLeaf = ContactIdentifierLeaf_[None]


class ContactIdentifier(Diagram):
    """Online contact identifier: aligns the table motion with the delayed
    force, then runs the recursive least-squares fit.

    Ports
    -----
    Input ``measured_force`` (size 1, N)
        f_mea from the force sensor (delayed by T_fms).
    Input ``table_motion`` (size 3: m, m/s, m/s^2)
        ``[p_act, v_act, a_act]``; ``p_act > 0`` is the contact deflection.
    Output ``contact_parameters`` (size 2: N/m, N s/m)
        The estimate ``[k, c]``.

    Parameters
    ----------
    params : IdentifierParams
    period_s : float
        Update period (the rig computer's period).
    motion_delay : System, optional
        A system delaying a size-3 signal exactly as the force sensor delays
        the force (input port 0, output port 0), e.g. a
        :class:`~hybridtable.systems.sensor.ForceSensorDelay` of size 3 built like the
        loop's sensor. ``None``: no delay (the force is read undelayed).
    """

    def __init__(
        self, params: IdentifierParams, period_s: float, motion_delay: System | None = None
    ) -> None:
        Diagram.__init__(self)
        self.params = params
        builder = DiagramBuilder()
        delay = builder.AddNamedSystem("motion_alignment", motion_delay or PassThrough(3))
        leaf = builder.AddNamedSystem("rls", ContactIdentifierLeaf(params, period_s))
        builder.Connect(delay.get_output_port(0), leaf.GetInputPort("aligned_motion"))
        builder.ExportInput(leaf.GetInputPort("measured_force"), "measured_force")
        builder.ExportInput(delay.get_input_port(0), "table_motion")
        builder.ExportOutput(leaf.GetOutputPort("contact_parameters"), "contact_parameters")
        builder.BuildInto(self)
