"""Contact model: unilateral spring, zero force apart, never pulls."""

import numpy as np
import pytest
from pydrake.autodiffutils import AutoDiffXd, InitializeAutoDiff
from pydrake.systems.primitives import Linearize

from hybridtable import ContactParams, ParameterError, UnilateralSpringContact


def _force(contact, motion):
    ctx = contact.CreateDefaultContext()
    contact.GetInputPort("motion").FixValue(ctx, np.asarray(motion, dtype=float))
    f = contact.GetOutputPort("force").Eval(ctx)[0]
    rate = contact.GetOutputPort("force_rate").Eval(ctx)[0]
    return f, rate


@pytest.mark.parametrize("p, v", [(-1e-3, 0.1), (-1e-9, -0.5), (0.0, 0.3), (-0.2, 0.0)])
def test_zero_force_apart(p, v):
    contact = UnilateralSpringContact(ContactParams(1e5, 500.0))
    assert _force(contact, [p, v, 3.0]) == (0.0, 0.0)


def test_spring_law_in_contact():
    contact = UnilateralSpringContact(ContactParams(2e5))
    f, rate = _force(contact, [1.5e-3, -0.04, 7.0])
    assert f == pytest.approx(300.0)
    assert rate == pytest.approx(2e5 * -0.04)


def test_damped_contact_never_pulls():
    contact = UnilateralSpringContact(ContactParams(1e5, 2e4))
    # k p + c v = 100 - 400 < 0: the devices separate faster than the spring relaxes.
    assert _force(contact, [1e-3, -0.02, 0.0]) == (0.0, 0.0)
    f, rate = _force(contact, [1e-3, 0.01, -2.0])
    assert f == pytest.approx(1e5 * 1e-3 + 2e4 * 0.01)
    assert rate == pytest.approx(1e5 * 0.01 + 2e4 * -2.0)


def test_stored_energy_is_returned_on_a_closed_cycle():
    # Work of the undamped contact over a penetration cycle in and out is zero.
    contact = UnilateralSpringContact(ContactParams(1e5))
    t = np.linspace(0.0, 1.0, 20001)
    p = 2e-3 * np.sin(np.pi * t)
    v = 2e-3 * np.pi * np.cos(np.pi * t)
    f = np.array([_force(contact, [pi, vi, 0.0])[0] for pi, vi in zip(p, v, strict=True)])
    work = np.trapezoid(f * v, t)
    assert abs(work) < 1e-6 * np.max(f) * 2e-3


def test_autodiff_and_bilateral_linearization():
    params = ContactParams(1e5, 300.0)
    ad = UnilateralSpringContact(params).ToAutoDiffXd()
    ctx = ad.CreateDefaultContext()
    ad.GetInputPort("motion").FixValue(ctx, InitializeAutoDiff(np.array([1e-3, 0.0, 0.0])))
    f = ad.GetOutputPort("force").Eval(ctx)[0]
    assert isinstance(f, AutoDiffXd)
    np.testing.assert_allclose(f.derivatives(), [1e5, 300.0, 0.0])
    # Bilateral: the linearization at p = 0 keeps the spring (max(p, 0) has slope 0 there).
    bil = UnilateralSpringContact(params, bilateral=True)
    ctx = bil.CreateDefaultContext()
    bil.GetInputPort("motion").FixValue(ctx, np.zeros(3))
    lin = Linearize(bil, ctx, output_port_index=bil.GetOutputPort("force").get_index())
    np.testing.assert_allclose(lin.D(), [[1e5, 300.0, 0.0]])


@pytest.mark.parametrize(
    "k, c, field",
    [
        (0.0, 0.0, "stiffness_n_per_m"),
        (1e5, -1.0, "damping_n_s_per_m"),
        (float("nan"), 0, "stiffness"),
    ],
)
def test_bad_parameters_name_the_field(k, c, field):
    with pytest.raises(ParameterError, match=field):
        ContactParams(k, c)
