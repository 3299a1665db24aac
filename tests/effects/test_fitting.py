"""The one fit core (hybridtable.effects.fitting) against closed forms: linear least
squares, its covariance, a log parameter, the best start, the bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.effects.effect import EffectParameter
from hybridtable.effects.fitting import (
    Coordinates,
    LeastSquares,
    fit_values,
    jacobian,
    standard_errors,
)
from hybridtable.effects.spec import RigScale

SCALE = RigScale(1.0, 1.0, 1e-3, 0.0, 0.1, 50.0)
X = np.linspace(0.0, 1.0, 41)


def _param(
    name: str, lower: float, upper: float, scale: float, null: float | None = 0.0, log=False
):
    return EffectParameter(name, "1", name, lower, upper, scale, null=null, log=log)


def _line_space(a0=0.0, b0=0.0) -> Coordinates:
    free = (("line", _param("a", -10.0, 10.0, 0.5)), ("line", _param("b", -10.0, 10.0, 0.5)))
    return Coordinates(free, SCALE, {"line": {"a": a0, "b": b0}})


def _line_data(sigma: float, seed: int = 3):
    rng = np.random.default_rng(seed)
    return 1.5 + 0.7 * X + sigma * rng.standard_normal(X.size)


def _line_residual(y, sigma):
    return lambda v: (v["line"]["a"] + v["line"]["b"] * X - y) / sigma


def test_a_linear_model_lands_on_the_normal_equations_and_their_covariance():
    sigma = 0.05
    y = _line_data(sigma)
    design = np.column_stack([np.ones_like(X), X])
    exact, *_ = np.linalg.lstsq(design, y, rcond=None)
    sol = fit_values(_line_residual(y, sigma), _line_space(), settings=LeastSquares(xtol=1e-12))
    assert sol.values["line"]["a"] == pytest.approx(exact[0], abs=1e-7)
    assert sol.values["line"]["b"] == pytest.approx(exact[1], abs=1e-7)
    r0 = _line_residual(y, sigma)(sol.values)
    std = standard_errors(_line_residual(y, sigma), sol.coordinates, r0, step=1e-2)
    cov = sigma**2 * np.linalg.inv(design.T @ design)
    s2 = max(1.0, float(r0 @ r0) / (X.size - 2))
    assert std["line"]["a"] == pytest.approx(math.sqrt(s2 * cov[0, 0]), rel=1e-6)
    assert std["line"]["b"] == pytest.approx(math.sqrt(s2 * cov[1, 1]), rel=1e-6)


def test_a_misfit_larger_than_the_noise_widens_the_errors_by_sqrt_chi2_per_dof():
    y = _line_data(0.05)
    stated = 0.01  # the data's noise is five times what the residual's unit says
    sol = fit_values(_line_residual(y, stated), _line_space(), settings=LeastSquares(xtol=1e-12))
    r0 = _line_residual(y, stated)(sol.values)
    std = standard_errors(_line_residual(y, stated), sol.coordinates, r0, step=1e-2)
    design = np.column_stack([np.ones_like(X), X])
    bare = stated * math.sqrt(np.linalg.inv(design.T @ design)[1, 1])
    chi2_per_dof = float(r0 @ r0) / (X.size - 2)
    assert chi2_per_dof > 10.0
    assert std["line"]["b"] == pytest.approx(bare * math.sqrt(chi2_per_dof), rel=1e-6)


def test_a_log_parameter_steps_in_its_logarithm_and_its_error_is_relative():
    rate = 37.0
    sigma = 1e-3
    y = np.exp(-rate * X)
    p = _param("rate_per_s", 0.1, 1e3, 0.5, null=None, log=True)
    space = Coordinates((("decay", p),), SCALE, {"decay": {"rate_per_s": 1.0}})

    def residual(v):
        return (np.exp(-v["decay"]["rate_per_s"] * X) - y) / sigma

    # from 1/s, 37 times too slow: one unit of the coordinate is a factor e^0.5
    assert space.values([2.0])["decay"]["rate_per_s"] == pytest.approx(math.e)
    sol = fit_values(residual, space, settings=LeastSquares(max_nfev=200, xtol=1e-12))
    assert sol.values["decay"]["rate_per_s"] == pytest.approx(rate, rel=1e-6)
    jac = jacobian(residual, sol.coordinates, 1e-4)
    dy_drate = X * np.exp(-rate * X) / sigma  # d residual / d rate, closed form (sign aside)
    per_unit = 0.5 * rate  # d rate / d u at the fit
    assert np.abs(jac[:, 0]) == pytest.approx(dy_drate * per_unit, rel=1e-4, abs=1e-6)


def test_the_best_start_is_polished_and_the_result_is_never_worse_than_it():
    # two valleys: chi2 has its global minimum at b = 3 and a local one at b = -3
    def residual(v):
        b = v["line"]["b"]
        return np.array([(b * b - 9.0), 0.1 * (b - 3.0)])

    space = _line_space()
    space = Coordinates(space.free[1:], SCALE, space.origin)
    near_local = fit_values(residual, space, [{"line": {"b": -2.5}}])
    # b = 2.8 has the lower chi2 of the two starts (1.35 against 7.9): it is the one polished
    both = fit_values(residual, space, [{"line": {"b": -2.5}}, {"line": {"b": 2.8}}])
    assert near_local.values["line"]["b"] == pytest.approx(-3.0, abs=0.05)
    assert both.values["line"]["b"] == pytest.approx(3.0, abs=1e-3)
    # a grid over the range finds the other valley, whatever the informed start
    scanned = fit_values(
        residual, space, [{"line": {"b": -2.5}}], grid=[{"line": {"b": b}} for b in (-8, 1, 8)]
    )
    assert scanned.values["line"]["b"] == pytest.approx(3.0, abs=1e-3)
    # a budget of no evaluation at all leaves the best start as it is
    stuck = fit_values(residual, space, [{"line": {"b": 2.0}}], LeastSquares(max_nfev=1))
    assert stuck.cost <= float(residual({"line": {"b": 2.0}}) @ residual({"line": {"b": 2.0}}))


def test_values_stay_within_the_bounds_and_held_values_are_not_moved():
    y = _line_data(0.05) + 50.0  # the intercept wants 51.5, above its bound of 10
    space = _line_space()
    sol = fit_values(_line_residual(y, 0.05), space, [{"line": {"a": 3.0}}], held={})
    assert sol.values["line"]["a"] == pytest.approx(10.0)
    held = Coordinates(space.free[1:], SCALE, {"line": {"a": 2.0, "b": 0.0}})
    fixed = fit_values(
        _line_residual(y, 0.05), held, [{"line": {"a": 9.0, "b": 1.0}}], held={"line": {"a": 2.0}}
    )
    assert fixed.values["line"]["a"] == 2.0


def test_no_room_to_move_gives_no_standard_error():
    p = _param("k", 1.0, 1.0, 0.5, null=1.0)
    space = Coordinates((("e", p),), SCALE, {"e": {"k": 1.0}})
    std = standard_errors(lambda v: np.array([v["e"]["k"]]), space, np.array([1.0]), 1e-2)
    assert std == {"e": {"k": None}}


def _two_valleys(v):
    b = v["line"]["b"]
    return np.array([(b * b - 9.0), 0.1 * (b - 3.0)])


def test_each_start_polishes_a_start_the_origin_beats():
    # the origin (b = 0, chi2 81.09) is beaten by b = -2.5 (7.9) but not by b = 5.5
    # (449): only a polish of every given start finds the valley at b = 3
    space = _line_space()
    space = Coordinates(space.free[1:], SCALE, {"line": {"a": 0.0, "b": -2.5}})
    best_only = fit_values(_two_valleys, space, [{"line": {"b": 5.5}}])
    each = fit_values(_two_valleys, space, [{"line": {"b": 5.5}}], LeastSquares(each_start=True))
    assert best_only.values["line"]["b"] == pytest.approx(-3.0, abs=0.05)
    assert each.values["line"]["b"] == pytest.approx(3.0, abs=1e-3)


def test_a_polish_that_fails_leaves_the_start_and_its_own_residual():
    # least_squares refuses non-finite residuals: the start, as evaluated, is the answer
    seen = []

    def residual(v):
        seen.append(v["line"]["b"])
        b = v["line"]["b"]
        return np.array([b - 1.0, math.nan if b != 2.5 else 0.0])

    space = _line_space()
    space = Coordinates(space.free[1:], SCALE, {"line": {"a": 0.0, "b": 2.5}})
    sol = fit_values(residual, space)
    assert not sol.success
    assert sol.values["line"]["b"] == 2.5 and sol.values["line"]["b"] in seen
    assert sol.cost == pytest.approx(1.5**2)
