"""The one search for models of several effects (``effects.search``), which both
``diagnose`` (pairs and swaps) and ``explain`` (pairs and triples) use."""

from __future__ import annotations

import math

from hybridtable.effects.search import propose, swaps

NAMES = ["a", "b", "c", "d"]


def _screen_from(costs: dict[frozenset, float], calls: list):
    """A screen whose figure is ``costs`` (missing: not screenable), recording what it saw."""

    def screen(combos):
        calls.append(list(combos))
        return [
            (costs.get(frozenset(c), math.inf), {n: {"x": float(i)} for i, n in enumerate(c)})
            for c in combos
        ]

    return screen


def test_the_best_screened_combinations_are_proposed_with_the_screens_start():
    costs = {frozenset("ab"): 3.0, frozenset("cd"): 1.0, frozenset("bd"): 2.0}
    calls: list = []
    out = propose(NAMES, 2, _screen_from(costs, calls), keep=2)
    assert [p.names for p in out] == [("c", "d"), ("b", "d")]
    assert [p.screened for p in out] == [1.0, 2.0]
    assert out[0].start == {"c": {"x": 0.0}, "d": {"x": 1.0}}
    assert len(calls) == 1 and len(calls[0]) == 6  # every pair of four, screened once


def test_an_unscreenable_combination_is_not_proposed_from_the_screen():
    out = propose(NAMES, 2, _screen_from({frozenset("ab"): 1.0}, []), keep=5)
    assert [p.names for p in out] == [("a", "b")]


def test_ties_keep_the_order_of_the_names():
    costs = dict.fromkeys((frozenset("cd"), frozenset("ab"), frozenset("bc")), 1.0)
    out = propose(NAMES, 2, _screen_from(costs, []), keep=2)
    assert [p.names for p in out] == [("a", "b"), ("b", "c")]


def test_combinations_of_the_best_singles_come_unscreened_and_once():
    costs = {frozenset("ab"): 1.0}
    out = propose(
        NAMES,
        2,
        _screen_from(costs, []),
        keep=1,
        start=lambda c: {n: {"single": 1.0} for n in c},
        best=["d", "a", "b"],
    )
    # (a, b) screened first; the best singles' pairs in the names' order, (a, b) not again
    assert [p.names for p in out] == [("a", "b"), ("a", "d"), ("b", "d")]
    assert out[1].start == {"a": {"single": 1.0}, "d": {"single": 1.0}}
    assert math.isnan(out[1].screened)


def test_what_is_not_allowed_is_never_screened_nor_proposed():
    calls: list = []
    costs = {frozenset(c): float(i) for i, c in enumerate(("ab", "ac", "bc", "cd"))}
    out = propose(
        NAMES,
        2,
        _screen_from(costs, calls),
        keep=10,
        best=["a", "b", "c"],
        allowed=lambda c: "c" not in c,
    )
    assert all("c" not in combo for combo in calls[0])
    assert [p.names for p in out] == [("a", "b")]


def test_seen_sets_are_not_proposed_again_across_sizes_and_searches():
    seen = {frozenset("ab")}
    costs = {frozenset(c): 1.0 for c in ("ab", "ac", "abc", "abd")}
    pairs = propose(NAMES, 2, _screen_from(costs, []), keep=4, seen=seen)
    triples = propose(NAMES, 3, _screen_from(costs, []), keep=4, seen=seen)
    assert [p.names for p in pairs] == [("a", "c")]
    assert [p.names for p in triples] == [("a", "b", "c"), ("a", "b", "d")]
    assert seen == {frozenset(c) for c in ("ab", "ac", "abc", "abd")}
    again = propose(NAMES, 3, _screen_from(costs, []), keep=4, seen=seen)
    assert again == []


def test_nothing_to_screen_calls_no_screen():
    calls: list = []
    assert propose(["a"], 2, _screen_from({}, calls), keep=3) == []
    assert calls == []


def test_swaps_replace_one_member_by_one_of_the_pool_each_set_once():
    out = list(swaps(["a", "b"], ["c", "a", "d"]))
    assert out == [("b", "c"), ("b", "d"), ("a", "c"), ("a", "d")]
    # a swap that a pair search proposed already, or that is not allowed, is left out
    seen = {frozenset("bc")}
    out = list(swaps(["a", "b"], ["c", "d"], allowed=lambda c: "d" not in c, seen=seen))
    assert out == [("a", "c")]
    assert frozenset("ac") in seen
    # one effect selected: every swap is a single effect of the pool
    assert list(swaps(["a"], ["a", "b", "b"])) == [("b",)]
