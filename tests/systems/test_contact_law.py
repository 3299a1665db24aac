"""The contact law: the nominal spring at null values, closed forms, never
pulls, force rate is the time derivative, AutoDiff, validation.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.autodiffutils import AutoDiffXd, InitializeAutoDiff

from hybridtable.errors import ParameterError
from hybridtable.systems.contact import ContactParams, UnilateralSpringContact
from hybridtable.systems.contact_law import ContactLaw, ContactLawParams, contact_law_force

K = 60000.0


def _eval(system, motion):
    ctx = system.CreateDefaultContext()
    system.GetInputPort("motion").FixValue(ctx, np.asarray(motion, dtype=float))
    return system.GetOutputPort("force").Eval(ctx)[0], system.GetOutputPort("force_rate").Eval(ctx)[
        0
    ]


# -- contact law -----------------------------------------------------------------
@pytest.mark.parametrize(
    "motion", [(-1e-3, 0.1, 0.0), (0.0, 0.2, 1.0), (2e-3, 0.05, -3.0), (5e-3, -0.08, 2.0)]
)
def test_contact_law_at_null_values_is_the_nominal_spring(motion):
    assert _eval(ContactLaw(ContactLawParams(K)), motion) == pytest.approx(
        _eval(UnilateralSpringContact(ContactParams(K)), motion), rel=1e-15, abs=0.0
    )


def test_contact_law_closed_forms():
    p, v, a = 3e-3, 0.05, -2.0
    f, rate = contact_law_force(ContactLawParams(K, damping_n_s_per_m=400.0), p, v, a)
    assert f == pytest.approx(K * p + 400.0 * v) and rate == pytest.approx(K * v + 400.0 * a)
    f, _ = contact_law_force(ContactLawParams(K, hunt_crossley_s_per_m=3.0), p, v)
    assert f == pytest.approx(K * p * (1 + 3.0 * v))
    # Power law: secant stiffness k at d_ref, f ~ d^n elsewhere.
    law = ContactLawParams(K, exponent=1.5, reference_deflection_m=4e-3)
    assert contact_law_force(law, 4e-3, 0.0)[0] == pytest.approx(K * 4e-3)
    assert contact_law_force(law, 1e-3, 0.0)[0] == pytest.approx(K * 4e-3 * (1 / 4) ** 1.5)
    # Series compliance: k / (1 + k s) for a linear spring; the implicit law otherwise.
    s = 2e-6
    f, _ = contact_law_force(ContactLawParams(K, series_compliance_m_per_n=s), p, 0.0)
    assert f == pytest.approx(K / (1 + K * s) * p)
    law = ContactLawParams(
        K, exponent=1.5, reference_deflection_m=4e-3, series_compliance_m_per_n=s
    )
    f, _ = contact_law_force(law, p, 0.0)
    assert f == pytest.approx(K * 4e-3 * ((p - s * f) / 4e-3) ** 1.5, rel=1e-12)
    # Coulomb friction: +F compressing, -F relaxing, smoothed over v_F.
    law = ContactLawParams(K, friction_force_n=15.0, friction_velocity_m_per_s=1e-3)
    assert contact_law_force(law, p, 0.05)[0] == pytest.approx(K * p + 15.0)
    assert contact_law_force(law, p, -0.05)[0] == pytest.approx(K * p - 15.0)
    assert contact_law_force(law, p, 0.0)[0] == pytest.approx(K * p)


def _bisected(k, n, dr, s, d):
    """The root of f = g(d - s f) by plain bisection: phi(f) = f - g(d - s f) rises
    from -g(d) at f = 0 to f > 0 at f = d / s."""
    lo, hi = 0.0, min(k * dr * (d / dr) ** n, d / s)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid - k * dr * (max(d - s * mid, 0.0) / dr) ** n > 0.0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def test_a_softening_spring_behind_a_series_compliance_solves_its_own_equation():
    # found by diagnose's generator study: with a softening exponent (n < 1) the
    # search left its bracket (d - s f < 0) and raised on a complex power
    rng = np.random.default_rng(5)
    for _ in range(3000):
        k, n = 10 ** rng.uniform(3, 6), rng.uniform(0.3, 3.0)
        dr, s, d = 10 ** rng.uniform(-5, -2), 10 ** rng.uniform(-9, -3), 10 ** rng.uniform(-7, -1)
        law = ContactLawParams(
            k, exponent=n, reference_deflection_m=dr, series_compliance_m_per_n=s
        )
        f, _ = contact_law_force(law, d, 0.0)
        assert isinstance(f, float)
        assert f == pytest.approx(_bisected(k, n, dr, s, d), rel=1e-9), (k, n, dr, s, d)


def test_contact_law_never_pulls_and_is_zero_apart():
    law = ContactLawParams(K, damping_n_s_per_m=5000.0, friction_force_n=50.0)
    assert contact_law_force(law, 1e-4, -0.05) == (0.0, 0.0)  # 6 - 250 - 50 < 0
    assert contact_law_force(law, -1e-3, 0.3) == (0.0, 0.0)


def test_contact_law_force_rate_is_the_time_derivative():
    law = ContactLawParams(
        K,
        exponent=1.4,
        reference_deflection_m=5e-3,
        damping_n_s_per_m=200.0,
        hunt_crossley_s_per_m=1.0,
        friction_force_n=10.0,
        friction_velocity_m_per_s=0.01,
        series_compliance_m_per_n=1e-6,
    )
    p, v, a, dt = 3e-3, 0.004, -1.5, 1e-7
    f0, rate = contact_law_force(law, p, v, a)
    f1, _ = contact_law_force(law, p + v * dt + 0.5 * a * dt * dt, v + a * dt)
    assert rate == pytest.approx((f1 - f0) / dt, rel=1e-4)


def test_contact_law_converts_to_autodiff():
    law = ContactLawParams(
        K,
        exponent=1.5,
        reference_deflection_m=4e-3,
        damping_n_s_per_m=100.0,
        series_compliance_m_per_n=1e-6,
    )
    ad = ContactLaw(law).ToAutoDiffXd()
    ctx = ad.CreateDefaultContext()
    x = np.array([3e-3, 0.02, 0.0])
    ad.GetInputPort("motion").FixValue(ctx, InitializeAutoDiff(x))
    f = ad.GetOutputPort("force").Eval(ctx)[0]
    assert isinstance(f, AutoDiffXd)
    eps = 1e-9
    fd = [
        (contact_law_force(law, *(x + eps * e))[0] - contact_law_force(law, *(x - eps * e))[0])
        / (2 * eps)
        for e in np.eye(3)
    ]
    np.testing.assert_allclose(f.derivatives(), fd, rtol=1e-5, atol=1e-6)


def test_contact_law_parameters_are_validated():
    with pytest.raises(ParameterError, match="damping_n_s_per_m"):
        ContactLawParams(K, damping_n_s_per_m=-1.0)
    with pytest.raises(ParameterError, match="exponent"):
        ContactLawParams(K, exponent=0.0)


def test_the_law_is_zero_apart_as_the_replay_assumes():
    """``force_law_unilateral``: the replay evaluates the law only where ``p > 0``
    and takes ``0 * p`` elsewhere; that is the law's own value apart, signed
    zeros and NaN included, for every term of the law."""
    law = ContactLaw(
        ContactLawParams(
            8e4,
            exponent=1.5,
            damping_n_s_per_m=200.0,
            hunt_crossley_s_per_m=0.5,
            friction_force_n=30.0,
            series_compliance_m_per_n=1e-6,
        )
    )
    assert law.force_law_unilateral
    p = np.array([-1e-3, -0.0, 0.0, 1e-12, 2e-3, np.nan])
    for v in (-0.3, 0.0, 0.4):
        each = np.array([law.force_law(x, v, 1.0) for x in p])
        apart = 0.0 * p
        assert np.array_equal(each[~(p > 0.0)], apart[~(p > 0.0)], equal_nan=True)
        assert np.array_equal(np.signbit(each[~(p > 0.0)]), np.signbit(apart[~(p > 0.0)]))
