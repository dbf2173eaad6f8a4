"""The array heap of open states (ogcp.planner.search.open_list) against heapq on tuples."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from ogcp.planner.search.open_list import OpenList


def _random_ops(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for i in range(count):
        # Few distinct keys and depths: ties are common and settled by the tie number.
        yield bool(rng.random() < 0.35), float(rng.integers(0, 6)) / 7, -int(rng.integers(0, 4)), i


def _same(a, b) -> bool:
    """Entries equal, NaN g included."""
    return len(a) == len(b) and all(x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pops_come_in_the_order_of_heapq_on_tuples(seed):
    ours = OpenList(capacity=4)  # grows several times
    theirs: list[tuple] = []
    tie = 0
    for pop, key, neg_depth, ident in _random_ops(seed, 3000):
        if pop and theirs:
            assert _same(ours.pop(), heapq.heappop(theirs))
        else:
            lower, stage, g = key / 2, ident % 4, float("nan") if ident % 5 == 0 else key / 3
            ours.push(key, neg_depth, lower, stage, g, ident)
            heapq.heappush(theirs, (key, neg_depth, tie, lower, stage, g, ident))
            tie += 1
        assert len(ours) == len(theirs)
        if theirs:
            assert ours.first_key() == theirs[0][0]
    assert ours.lowest_lower() == min(entry[3] for entry in theirs)
    expected = heapq.nsmallest(16, theirs, key=lambda e: e[3])
    assert all(_same(a, b) for a, b in zip(ours.smallest_lower(16), expected, strict=True))
    ident = theirs[len(theirs) // 2][6]
    assert _same(ours.first_of(ident), min((e for e in theirs if e[6] == ident), key=lambda e: e[:3]))
    while theirs:
        assert _same(ours.pop(), heapq.heappop(theirs))


def test_a_restored_entry_keeps_its_tie_and_an_empty_list_says_so():
    open_list = OpenList(capacity=2)
    assert len(open_list) == 0 and open_list.first_key() == np.inf and open_list.lowest_lower() == np.inf
    with pytest.raises(IndexError):
        open_list.pop()
    open_list.push(0.5, 0, 0.4, 1, 0.0, 7)
    open_list.push(0.5, 0, 0.3, 2, 0.0, 8)
    first = open_list.pop()
    assert first == (0.5, 0, 0, 0.4, 1, 0.0, 7)
    open_list.restore(first)
    assert open_list.pop() == first  # tie 0 still comes before tie 1
    with pytest.raises(KeyError):
        open_list.first_of(99)


@pytest.mark.parametrize("seed", [0, 3])
def test_a_purge_removes_the_entries_past_the_cutoff_and_keeps_the_order_of_the_rest(seed):
    ours = OpenList(capacity=8)
    theirs: list[tuple] = []
    for tie, (_, key, neg_depth, ident) in enumerate(_random_ops(seed, 2000)):
        lower, stage = key / 2, ident % 4
        ours.push(key, neg_depth, lower, stage, 0.0, ident)
        heapq.heappush(theirs, (key, neg_depth, tie, lower, stage, 0.0, ident))
    cutoff = 1.5 / 7
    idents, stages = ours.purge(cutoff)
    gone = sorted((e[6], e[4]) for e in theirs if e[3] > cutoff)
    assert sorted(zip(idents.tolist(), stages.tolist(), strict=True)) == gone and gone
    assert ours.holds(idents[0]) is False
    theirs = [e for e in theirs if e[3] <= cutoff]
    heapq.heapify(theirs)
    assert len(ours) == len(theirs) and ours.holds(theirs[0][6])
    while theirs:
        assert _same(ours.pop(), heapq.heappop(theirs))
    assert [len(a) for a in ours.purge(0.0)] == [0, 0]


@pytest.mark.parametrize("seed", [0, 1])
def test_pushing_many_at_once_is_pushing_each_in_turn(seed):
    rng = np.random.default_rng(seed)
    one, many = OpenList(capacity=4), OpenList(capacity=4)
    for batch in range(40):
        k = int(rng.integers(0, 9))
        keys = rng.integers(0, 5, size=k) / 7  # ties settled by depth, then by the tie number
        neg_depths = -rng.integers(0, 3, size=k)
        lowers, gs = keys / 2, np.where(rng.random(k) < 0.5, np.nan, keys / 3)
        stages, idents = rng.integers(0, 4, size=k), np.arange(k) + 100 * batch
        for row in zip(keys, neg_depths, lowers, stages, gs, idents, strict=True):
            one.push(float(row[0]), int(row[1]), float(row[2]), int(row[3]), float(row[4]), int(row[5]))
        many.push_many(keys, neg_depths, lowers, stages, gs, idents)
        for _ in range(int(rng.integers(0, 4))):
            if len(one):
                assert _same(one.pop(), many.pop())
    assert len(one) == len(many) > 0
    while len(one):
        assert _same(one.pop(), many.pop())
