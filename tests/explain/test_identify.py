"""What a CoR table determines: the SVD of its sensitivities against first-order physics.

To first order (tests/generators/cortable.first_order_ln_cor) a row's
``ln CoR = pi^2 f_con (delay + lag - T_lead [SDC] - r lag [MDC]) - pi zeta``
with ``lag`` the table's and ``r`` the MDC's stiffness over the true one.
A continuous loop's CoR depends on f_con times its times only (raise f_con by
1 %, shorten every time by 1 %: nothing moves), so no table fixes f_con alone.

- Four compensators at one condition fix three numbers: ``f_con (delay + lag)
  - zeta / pi``, ``f_con T_lead`` (from ``ln none - ln SDC`` and ``ln MDC -
  ln SDMDC``, each ``pi^2 f_con T_lead``) and ``f_con r lag``; a longer delay
  and a less damped contact move the four rows alike.
- Rows at two contact frequencies (same delay, lead and table) add one: a
  delay moves ln CoR in proportion to f_con, a damping ratio by ``-pi zeta``
  at every f_con, so the two no longer move the table alike.

These run on a continuous rig computer, where the invariance is exact (a
sampled one has its tick as a time that does not scale).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridtable.effects.registry import default_effects, get_effect
from hybridtable.explain.conditions import Conditions
from hybridtable.explain.identify import DETERMINED_STD, identifiability
from hybridtable.explain.model import EffectAt, table_scale

COMPENSATORS = ("none", "SDC", "MDC", "SDMDC")
#: A 4-decimal table's rounding and the model's own error, in ln CoR (CoR ~ 1).
SIGMA_LN = math.hypot(1e-4 / math.sqrt(12.0), 1.0e-3)
ONE = (Conditions(),)  # the paper's Table 1: 1 Hz, 1e5 N/m, 5 ms, 25 Hz table
TWO = (Conditions(), Conditions(contact_frequency_hz=2.0, contact_stiffness_n_per_m=4.0e5))
INVARIANCE = {"f_con": 1.0, "delay": -1.0, "T_lead": -1.0, "table lag": -1.0}


def _analyse(conditions):
    cases = [(c, cond) for cond in conditions for c in COMPENSATORS]
    rig = table_scale(cases)
    effects = [EffectAt(get_effect(n), rig) for n in default_effects("explain")]
    return identifiability(effects, cases, np.full(len(cases), SIGMA_LN))


@pytest.fixture(scope="module")
def one():
    return _analyse(ONE)


@pytest.fixture(scope="module")
def two():
    return _analyse(TWO)


def _combination(ident, exponents: dict[str, int]) -> dict | None:
    return next((i for i in ident.identifiable if i["exponents"] == exponents), None)


def _has_invariance(ident) -> bool:
    return any(
        all(u["direction"].get(q) == w for q, w in INVARIANCE.items()) for u in ident.unresolved
    )


def _alike(ident, a: str, b: str) -> bool:
    return any(set(u["direction"]) == {a, b} for u in ident.unresolved)


def _rank(ident) -> int:
    return int(sum(s * DETERMINED_STD > 1.0 for s in ident.singular_values))


# -- one condition -----------------------------------------------------------------


def test_one_condition_fixes_f_con_times_the_lead(one):
    combo = _combination(one, {"f_con": 1, "T_lead": 1})
    assert combo is not None, [i["combination"] for i in one.identifiable]
    assert combo["combination"] == "f_con * T_lead"
    assert combo["relative"]


def test_one_condition_fixes_neither_f_con_nor_a_time_alone(one):
    assert {"f_con", "delay", "T_lead", "table lag"} <= set(one.undetermined)
    singles = {i["combination"] for i in one.identifiable if len(i["exponents"]) == 1}
    assert not singles & {"f_con", "delay", "T_lead", "table lag"}
    assert _has_invariance(one), [u["words"] for u in one.unresolved]


def test_one_condition_fixes_three_numbers_and_a_delay_looks_like_damping(one):
    assert _rank(one) == 3, one.singular_values
    assert _alike(one, "delay", "damping ratio"), [u["words"] for u in one.unresolved]


def test_the_std_of_f_con_times_the_lead_is_the_first_order_one(one):
    # ln none - ln SDC and ln MDC - ln SDMDC each give pi^2 f_con T_lead with
    # variance 2 sigma^2; together sigma^2: the relative std of f_con T_lead is
    # sigma / (pi^2 f_con T_lead) = 0.001 / (pi^2 * 1 Hz * 5 ms) = 2.0 %.
    expected = SIGMA_LN / (math.pi**2 * 1.0 * 0.005)
    combo = _combination(one, {"f_con": 1, "T_lead": 1})
    assert combo is not None
    assert combo["std"] == pytest.approx(expected, rel=0.25), (
        f"f_con * T_lead: reported relative std {combo['std']:.4f}, first order {expected:.4f}"
    )


# -- two contact frequencies ------------------------------------------------------------


def test_two_frequencies_still_fix_no_f_con_alone(two):
    # the invariance is exact for a continuous loop, at any set of frequencies
    assert "f_con" in two.undetermined
    singles = {i["combination"] for i in two.identifiable if len(i["exponents"]) == 1}
    assert "f_con" not in singles
    assert _combination(two, {"f_con": 1, "T_lead": 1}) is not None


def test_two_frequencies_keep_the_f_con_times_invariance_open(two):
    assert _has_invariance(two), (
        "raising f_con by 1 % and shortening every time by 1 % leaves a continuous loop's "
        "CoR unchanged at every frequency; unresolved: "
        + "; ".join(u["words"] for u in two.unresolved)
    )


def test_two_frequencies_separate_a_delay_from_damping(one, two):
    # a delay moves ln CoR by pi^2 f_con * delay, a damping ratio by -pi zeta at any
    # f_con: rows at 1 and 2 Hz tell them apart, and the table fixes one more number
    assert not _alike(two, "delay", "damping ratio"), [u["words"] for u in two.unresolved]
    assert _rank(two) >= _rank(one) + 1, (one.singular_values, two.singular_values)
