"""The docking contact's closed-form linearization (issue 37): K and C from one
evaluation of Drake's contact, against central differences of Drake's own
wrench and against a hand calculation of the pad ring."""

from __future__ import annotations

import numpy as np
import pytest

import hybridtable.six_dof.pads as pads_module
from hybridtable.six_dof.contact import STICTION_TOLERANCE_M_PER_S, DockingContact
from hybridtable.six_dof.params import DockingContactParams
from hybridtable.six_dof.pose import rotation_exp, rotation_jacobian, skew


def central_differences(contact: DockingContact, q, qd, step: float):
    """``K = -dw/dq`` and ``C = -dw/dqd`` by central differences of the wrench."""
    K, C = np.zeros((6, 6)), np.zeros((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = step
        K[:, j] = -(contact.wrench(q + e, qd) - contact.wrench(q - e, qd)) / (2.0 * step)
        C[:, j] = -(contact.wrench(q, qd + e) - contact.wrench(q, qd - e)) / (2.0 * step)
    return K, C


def drakes_point_pairs(contact: DockingContact, q, qd):
    """Drake's own point pairs of the pads with the device at ``q`` moving at
    ``qd`` (the plant's contact results: the oracle of the closed form, and
    what the Stewart platform's plant computes): ``(port origin p, [(contact
    point, force on the device, the pair's depth, normal out of the plate
    toward the device), ...])``."""
    p, results = contact._evaluate(q, qd)
    device = contact._device.index()
    pairs = []
    for i in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(i)
        f = info.contact_force()  # on body B, at the contact point
        pair = info.point_pair()
        normal = pair.nhat_BA_W  # out of B into A
        if info.bodyA_index() == device:
            f = -f
        else:
            normal = -normal
        pairs.append((info.contact_point(), f, pair.depth, normal))
    return p, pairs


def relative_error(A: np.ndarray, B: np.ndarray) -> float:
    return float(np.abs(A - B).max() / np.abs(B).max())


def test_rotation_jacobian_moves_a_body_point_as_exp_does():
    rng = np.random.default_rng(0)
    for theta in (np.zeros(3), np.array([1e-8, -2e-8, 0.0]), *rng.normal(0.0, 0.8, (5, 3))):
        a = rng.normal(size=3)
        b = rotation_exp(theta) @ a
        h = 1e-6
        numeric = np.column_stack(
            [
                (rotation_exp(theta + h * e) @ a - rotation_exp(theta - h * e) @ a) / (2 * h)
                for e in np.eye(3)
            ]
        )
        np.testing.assert_allclose(-skew(b) @ rotation_jacobian(theta), numeric, atol=1e-9)


# (dissipation s/m, friction, speed scale m/s, difference step): sliding well
# above the stiction tolerance, and inside it (the step then a small part of it).
CASES = [
    (0.0, 0.0, 0.0, 1e-7),
    (0.4, 0.0, 0.1, 1e-7),
    (0.5, 0.3, 0.1, 1e-7),
    (0.5, 0.3, 0.5 * STICTION_TOLERANCE_M_PER_S, 1e-4 * STICTION_TOLERANCE_M_PER_S),
]


@pytest.mark.parametrize(("dissipation", "friction", "speed", "step"), CASES)
def test_closed_form_is_the_derivative_of_drakes_contact(dissipation, friction, speed, step):
    """At random offset, tilted (up to 0.3 rad), moving poses with several pads
    touching: within 1e-6 of the largest entry (the issue's figure)."""
    params = DockingContactParams(
        1e5, contact_dissipation_s_per_m=dissipation, friction_coefficient=friction
    )
    contact = DockingContact(params)
    rng = np.random.default_rng(11)
    checked = 0
    while checked < 12:
        q = np.concatenate(
            [rng.uniform(-0.05, 0.05, 2), [rng.uniform(0.0, 0.02)], rng.uniform(-0.3, 0.3, 3)]
        )
        qd = rng.uniform(-1.0, 1.0, 6) * speed
        points: list = []
        contact.wrench(q, qd, points)
        if len(points) < 2:
            continue
        K, C = contact.stiffness(q, qd)
        K_num, C_num = central_differences(contact, q, qd, step)
        assert relative_error(K, K_num) < 1e-6
        if dissipation or friction:
            assert relative_error(C, C_num) < 1e-6
        else:
            assert not C.any()
        checked += 1


def test_pad_ring_by_hand_with_the_geometric_term():
    """Aligned and pressed ``x`` on axis, N pads of radius r on a ring of radius
    R, each a spring k: ``-dF_z/dz = N k``, no stiffness sideways, and about a
    horizontal axis ``N k (R^2/2 + x r)``: the springs' lever arms, plus the
    geometric term of the pads' centres sitting r behind the port, which a
    tilt swings sideways under the pressing forces."""
    k_total, R, r, x = 1e5, 0.3, 0.05, 0.004
    params = DockingContactParams(k_total, ring_radius_m=R, pad_radius_m=r)
    K, C = DockingContact(params).stiffness(np.array([0.0, 0.0, x, 0.0, 0.0, 0.0]))
    tilt = k_total * (R * R / 2 + x * r)
    expected = np.zeros((6, 6))  # rows [moment; force], columns [position; rotation]
    expected[0, 3] = expected[1, 4] = tilt
    expected[5, 2] = k_total
    np.testing.assert_allclose(K, expected, atol=1e-9 * k_total)
    assert not C.any()
    assert k_total * x * r > 1e-3 * tilt  # the geometric term is well above the tolerance


def test_no_contact_no_stiffness():
    contact = DockingContact(DockingContactParams(1e5, friction_coefficient=0.3))
    K, C = contact.stiffness(np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0]), np.ones(6))
    assert not K.any() and not C.any()


def test_compiled_and_python_kernels_agree_bit_for_bit():
    params = DockingContactParams(1e5, contact_dissipation_s_per_m=0.5, friction_coefficient=0.3)
    q = np.array([0.01, -0.02, 0.003, 0.02, -0.05, 0.1])
    qd = np.array([0.02, -0.01, 0.05, 0.1, 0.0, -0.2])
    args = (
        q,
        qd,
        np.ascontiguousarray(params.pad_centres_m),
        params.pad_radius_m,
        params.contact_stiffness_n_per_m / params.pad_count,
        params.contact_dissipation_s_per_m,
        params.friction_coefficient,
    )
    compiled = pads_module.pad_stiffness()
    assert compiled is not pads_module._pad_stiffness  # numba is a dependency
    assert DockingContact(params).stiffness(q, qd)[0].any()
    for a, b in zip(compiled(*args), pads_module._pad_stiffness(*args), strict=True):
        assert np.array_equal(a, b)


def test_pads_as_drakes_point_pairs():
    """The pads' contacts without Drake's query (points, forces, depths,
    normals) are Drake's point pairs, with dissipation and friction, sliding
    and below the stiction tolerance, and none where a pad separates so fast
    that Hunt–Crossley's force vanishes."""
    params = DockingContactParams(1e5, contact_dissipation_s_per_m=20.0, friction_coefficient=0.3)
    contact = DockingContact(params)
    rng = np.random.default_rng(11)
    clamped = 0
    for draw in range(60):
        q = np.concatenate(
            [rng.uniform(-0.05, 0.05, 2), [rng.uniform(-0.004, 0.02)], rng.uniform(-0.2, 0.2, 3)]
        )
        # Slow (below the stiction tolerance) and fast: separating faster than
        # 1 / d = 0.05 m/s, Hunt–Crossley's force vanishes and Drake has no pair.
        speed = 1e-4 if draw % 3 == 0 else 0.15
        qd = rng.uniform(-speed, speed, 6)
        p, pairs = drakes_point_pairs(contact, q, qd)
        U, F, X, N = pads_module._pad_contacts(
            q[:3],
            rotation_exp(q[3:]),
            qd,
            params.pad_centres_m,
            params.pad_radius_m,
            params.contact_stiffness_n_per_m / params.pad_count,
            params.contact_dissipation_s_per_m,
            params.friction_coefficient,
        )
        assert len(X) == len(pairs)
        centres_z = q[2] + params.pad_centres_m @ rotation_exp(q[3:])[2]
        clamped += int(np.sum(params.pad_radius_m + centres_z > 0.0)) - len(pairs)
        for point, force, depth, normal in pairs:
            i = int(np.argmin(np.linalg.norm(U - (point - p), axis=1)))
            np.testing.assert_allclose(U[i], point - p, rtol=0, atol=1e-15)
            np.testing.assert_allclose(F[i], force, rtol=0, atol=1e-12 * np.linalg.norm(force))
            assert abs(X[i] - depth) <= 1e-15
            np.testing.assert_array_equal(N[i], normal)
    assert clamped > 0  # pressed pads without a pair: the clamp was reached
