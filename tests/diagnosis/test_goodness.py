"""The end test of a diagnosis: its false-alarm rate on noise, and where it
finds a misfit."""

from __future__ import annotations

import numpy as np
import pytest

from hybridtable.diagnosis.evaluate import Evaluation, Evaluator, prepare_runs
from hybridtable.diagnosis.goodness import FALSE_ALARM_RATE, goodness_of_fit
from hybridtable.effects.spec import ModelSpec, RigScale
from tests.generators.effectsim import make_runs


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    runs = make_runs(
        tmp_path_factory.mktemp("null"),
        "none",
        velocities=(0.06, 0.1),
        compensators=("SDMDC", "none"),
        seed=4,
        duration_s=0.55,
    )
    data = prepare_runs(runs)
    ev = Evaluator(data, RigScale.from_runs(runs))
    nominal = {i: ev.evaluate(ModelSpec(), i) for i in range(len(data))}
    return data, nominal


def _synthetic(data, rng, shift=None):
    """Evaluations whose whitened residuals are unit white noise (the null),
    plus ``shift(i, channel, residual_in_noise_units)`` if given."""
    out = {}
    for i, d in enumerate(data):
        res, white = {}, {}
        for c, m in d.noise.items():
            w = rng.standard_normal(d.run.n)
            if shift is not None:
                w = shift(i, c, w)
            white[c] = w
            res[c] = w * m.sigma
        out[i] = Evaluation({}, res, white)
    return out


def test_the_nominal_model_passes_on_runs_without_an_effect(rig):
    data, nominal = rig
    g = goodness_of_fit(data, nominal)
    assert g.passed and g.tests > 40


def test_false_alarm_rate_on_noise_is_at_most_the_stated_one(rig):
    data, _ = rig
    rng = np.random.default_rng(0)
    trials = 400
    fails = sum(not goodness_of_fit(data, _synthetic(data, rng)).passed for _ in range(trials))
    # Bonferroni keeps the family at or below 1 %; allow three binomial standard errors
    bound = FALSE_ALARM_RATE + 3 * np.sqrt(FALSE_ALARM_RATE * (1 - FALSE_ALARM_RATE) / trials)
    assert fails / trials <= bound


def test_a_misfit_at_the_touch_is_found_and_located(rig):
    data, _ = rig
    d = data[1]
    touch = int(np.flatnonzero(d.f_labels == 1)[0])  # first compression tick of the reading

    def bump(i, c, w):
        if i == 1 and c == "f_mea_n":
            w = w.copy()
            w[touch : touch + 8] += 4.0
        return w

    g = goodness_of_fit(data, _synthetic(data, np.random.default_rng(1), bump))
    assert not g.passed and g.p_value < FALSE_ALARM_RATE
    w = g.where
    assert (w.run_id, w.channel, w.phase) == (d.run_id, "f_mea_n", "compression")
    t = d.run.time_s
    assert w.misfit_start_s <= t[touch + 7] and w.misfit_end_s >= t[touch]
    assert w.error > 1.1


def test_a_tiny_systematic_offset_is_significant_but_not_a_misfit(rig):
    data, _ = rig

    def offset(i, c, w):
        # 0.4 noise RMS along every free flight of the table position: sure to
        # be detected (hundreds of ticks) but below the practical floor
        if c == "p_act_m":
            w = w + 0.4 * (data[i].labels == 3)
        return w

    g = goodness_of_fit(data, _synthetic(data, np.random.default_rng(2), offset))
    assert g.passed
    ff = [w for w in g.worst if w.phase == "free_flight" and w.channel == "p_act_m"]
    assert ff and ff[0].p_value < 1e-3 and ff[0].error < 1.2
