"""The one selection rule (hybridtable.effects.selection): BIC for stated and
estimated noise, look-alikes, the separating run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.effects.selection import Block, bic, delta_bic, lookalikes, most_separating


def test_with_stated_noise_delta_bic_is_the_drop_in_chi2_less_the_parameters_price():
    before = [Block(40.0, 10), Block(25.0, 10)]
    after = [Block(12.0, 10), Block(11.0, 10)]
    expected = (65.0 - 23.0) - 2 * math.log(20)
    assert delta_bic(before, after, 2, stated=True) == pytest.approx(expected)
    assert bic(65.0, 0, 20) - bic(23.0, 2, 20) == pytest.approx(expected)


def test_with_estimated_noise_it_is_the_gaussian_likelihood_ratio_of_each_block():
    # n ln(s0^2 / s1^2) per block: the profile likelihood of a block of unknown variance
    rng = np.random.default_rng(1)
    w = rng.standard_normal(200)
    before, after = Block(float(w @ w) * 4.0, 200), Block(float(w @ w), 200)
    assert delta_bic([before], [after], 1, stated=False) == pytest.approx(
        200 * math.log(4.0) - math.log(200)
    )


def test_no_model_is_credited_with_residuals_below_the_numerical_floor():
    floor = 1e-3
    before = [Block(1e-2 * 100, 100, floor)]
    exact = [Block(0.0, 100, floor)]
    almost = [Block(1e-6 * 100, 100, floor)]
    # both land on the floor: the exact fit is worth no more than the almost exact one
    assert delta_bic(before, exact, 1, stated=False) == delta_bic(before, almost, 1, stated=False)
    assert delta_bic(before, exact, 1, stated=False) == pytest.approx(
        100 * math.log(1e-2 / floor) - math.log(100)
    )


def test_lookalikes_are_within_the_margin_and_not_the_reference_with_more_added():
    models = {
        ("a",): 10.0,
        ("b",): 11.5,
        ("c",): 12.5,
        ("a", "d"): 10.5,
        ("b", "d"): 11.0,
    }
    ref = ("a",)
    alike = lookalikes(ref, list(models), 2.0, models.__getitem__, lambda m: m)
    assert alike == [("b",), ("b", "d")]
    # at the margin itself: in when inclusive (explain's), out when not (diagnose's)
    models[("e",)] = 12.0
    assert ("e",) in lookalikes(ref, list(models), 2.0, models.__getitem__, lambda m: m)
    assert ("e",) not in lookalikes(ref, list(models), 2.0, models.__getitem__, lambda m: m, False)


def test_the_separating_run_is_the_farthest_and_says_how_many_runs_would_do():
    distances = {"slow": 1.0, "fast": 2.5, "heavy": None, "light": 0.5}
    sep = most_separating(distances, distances.get, threshold=10.0)
    assert sep.design == "fast"
    assert sep.distance == 2.5
    assert not sep.separates  # 6.25 < 10
    assert sep.runs_needed == 2  # two such runs: 12.5 > 10
    assert most_separating(["x"], lambda _: None, 10.0) is None
    assert most_separating(["x"], lambda _: 0.0, 10.0).runs_needed is None
