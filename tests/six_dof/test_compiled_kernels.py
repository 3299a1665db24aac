"""The 6-DoF loop's per-tick kernels: numba's compilation computes what the plain
functions compute (the same operations; to round-off where numba's BLAS and
LAPACK stand in for numpy's), and the systems refuse as the Python path words it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from hybridtable.errors import DivergenceError, WorkspaceError
from hybridtable.laws.compiled import compiled_kernel
from hybridtable.six_dof import pose_kinematics, spacecraft
from hybridtable.six_dof.pose import rotation_exp
from hybridtable.stewart import ft_sensor
from hybridtable.stewart.geometry import StewartGeometry

RNG = np.random.default_rng(3)


def _close(a, b, scale: float = 1.0) -> None:
    for x, y in zip(np.atleast_1d(a), np.atleast_1d(b), strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13 * scale)


def _body_state() -> np.ndarray:
    x = np.zeros(18)
    x[:6] = RNG.normal(size=6)
    x[6:15] = rotation_exp(RNG.normal(size=3)).ravel()
    x[15:18] = RNG.normal(size=3)
    return x


def test_spacecraft_step_and_port():
    inertia = np.array([[900.0, 20.0, -5.0], [20.0, 1100.0, 8.0], [-5.0, 8.0, 1300.0]])
    arm = np.array([0.1, -0.2, 1.5])
    step = compiled_kernel(spacecraft._step, spacecraft._HELPERS)
    port = compiled_kernel(spacecraft._port_state, spacecraft._HELPERS)
    assert step is not spacecraft._step
    for _ in range(10):
        x, wrench = _body_state(), RNG.normal(scale=1e3, size=6)
        args = (x, wrench, 1e-3, 2533.0, inertia, np.linalg.inv(inertia), arm)
        new, port_new = step(*args)
        plain, plain_port = spacecraft._step(*args)
        _close(new, plain, 10.0)
        _close(port_new, plain_port, 10.0)
        np.testing.assert_array_equal(plain_port, spacecraft._port_state(plain, arm))
        R = new[6:15].reshape(3, 3)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
        _close(port(x, arm), spacecraft._port_state(x, arm), 10.0)


def test_nearest_rotation_is_the_polar_factor():
    """One Newton step from a rotation spoilt by round-off-sized errors (and
    by 1e-8, far above them) lands on the SVD's polar factor ``U V^T``."""
    for size in (1e-15, 1e-8):
        M = rotation_exp(RNG.normal(size=3)) + RNG.normal(scale=size, size=(3, 3))
        u, _, vt = np.linalg.svd(M)
        np.testing.assert_allclose(spacecraft._nearest_rotation(M), u @ vt, rtol=0, atol=4e-15)


def test_legs_and_port_of_the_plant():
    kin = pose_kinematics.PoseKinematics(StewartGeometry())
    legs = compiled_kernel(pose_kinematics._legs, pose_kinematics._HELPERS)
    of_plant = compiled_kernel(pose_kinematics._port_of_plant_state, pose_kinematics._HELPERS)
    for _ in range(10):
        q = np.concatenate([RNG.uniform(-0.02, 0.02, 3), RNG.uniform(-0.05, 0.05, 3)])
        qd = RNG.normal(scale=0.1, size=6)
        args = (q, qd, kin.world_origin_m, kin.port_in_plate_m, kin._top, kin._base)
        for a, b in zip(legs(*args), pose_kinematics._legs(*args), strict=True):
            _close(a, b)
        x = RNG.normal(size=30)
        x[3:7] /= np.linalg.norm(x[3:7])
        wanted = pose_kinematics._port_of_plant_state(
            x, 3, 17, kin.world_origin_m, kin.port_in_plate_m
        )
        _close(of_plant(x, 3, 17, kin.world_origin_m, kin.port_in_plate_m), wanted, 10.0)
        lengths, rates = kin.inverse_kinematics(q, qd)
        np.testing.assert_array_equal(
            kin.commanded_legs(np.concatenate([q, qd])), np.concatenate([lengths, rates])
        )


def test_commanded_legs_refuse_in_words():
    kin = pose_kinematics.PoseKinematics(StewartGeometry())
    far = np.zeros(12)
    far[2] = 5.0
    with pytest.raises(WorkspaceError, match="outside the Stewart platform's workspace"):
        kin.commanded_legs(far)
    near = pose_kinematics.PoseKinematics(StewartGeometry(), max_condition_number=1.5)
    with pytest.raises(WorkspaceError, match="near a singularity"):
        near.commanded_legs(np.zeros(12))
    with pytest.raises(DivergenceError, match="not finite"):
        kin.commanded_legs(np.full(12, np.nan))


def test_payload_reading():
    reading = compiled_kernel(ft_sensor._reading, ft_sensor._HELPERS)
    inertia = np.array([[0.5, 0.01, 0.0], [0.01, 0.6, 0.02], [0.0, 0.02, 0.3]])
    payload = (12.0, np.array([0.0, 0.01, 0.2]), inertia, np.array([0.0, 0.0, -9.81]))
    for _ in range(10):
        x = RNG.normal(size=26)
        a = RNG.normal(size=6)
        t_s, f_s, point = RNG.normal(size=3), RNG.normal(scale=100.0, size=3), RNG.normal(size=3)
        args = (x, a, 4, 19, *payload, t_s, f_s, point)
        for got, wanted in zip(reading(*args), ft_sensor._reading(*args), strict=True):
            _close(got, wanted, 100.0)
        R, wrench = ft_sensor._reading(*args)
        w = x[19:22]
        by_law = ft_sensor.payload_compensated_wrench(
            ft_sensor.DevicePayload(*payload), R, w, a[:3], a[3:], t_s, f_s, point
        )
        np.testing.assert_array_equal(wrench, by_law)


def test_a_changed_helper_recompiles_a_cached_kernel(tmp_path):
    """numba's cache knows the kernel's file only: a helper changed in another
    file must not leave the cached machine code of the old one."""
    (tmp_path / "helper_mod.py").write_text("def h(x):\n    return x + 1.0\n")
    (tmp_path / "kernel_mod.py").write_text(
        "from helper_mod import h\n\n\ndef k(x):\n    return 2.0 * h(x)\n"
    )
    script = (
        "import sys\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        "from hybridtable.laws.compiled import compiled_kernel\n"
        "from helper_mod import h\n"
        "from kernel_mod import k\n"
        "print(compiled_kernel(k, (h,))(1.0))\n"
    )

    def run() -> str:
        done = subprocess.run(
            [sys.executable, "-c", script], capture_output=True, text=True, check=True
        )
        return done.stdout.strip()

    assert run() == "4.0"
    assert list((tmp_path / "__pycache__").glob("kernel_mod.k-*.nbi"))  # cached
    (tmp_path / "helper_mod.py").write_text("def h(x):\n    return x + 2.0\n")
    assert run() == "6.0"
