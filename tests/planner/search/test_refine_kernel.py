"""The compiled branch and bound over a state's Γh children (planner.search.refine_kernel)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from planner.grasp import subset_quality
from planner.search import GraspPlanner, search_space
from planner.search import best_first as search_run
from planner.search.refine_kernel import ChildBounds
from tests.conftest import exhaustive_best


def _summary(result):
    """What a run decides: grasp, values, status and the states it created and expanded."""
    s = result.stats
    return result.grasp, result.q1, result.bound, result.status, s.created_per_level, s.visited_per_level


@pytest.mark.parametrize(
    ("name", "method", "eps"), [("box", "astar", None), ("amphora", "astar", None), ("donut", "wastar", 0.4)]
)
def test_compiled_branch_and_bound_is_the_python_loop(object_contacts, monkeypatch, name, method, eps):
    contacts = object_contacts(name, 150, 0)
    compiled = GraspPlanner(method=method, eps=eps).plan(contacts, 3)
    monkeypatch.setattr(search_space, "ChildBounds", lambda m: None)  # the Python loop
    python = GraspPlanner(method=method, eps=eps).plan(contacts, 3)
    assert _summary(compiled) == _summary(python)


@pytest.fixture
def few_directions(monkeypatch):
    """A support bound that is full of directions after a dozen exact values."""
    monkeypatch.setattr(subset_quality, "MIN_DIRECTIONS", 140)
    monkeypatch.setattr(subset_quality, "MAX_DIRECTIONS", 140)
    settled = []
    original = search_run.Search.settles_on_bounds

    def counting(self, child):
        answer = original(self, child)
        settled.append(answer)
        return answer

    monkeypatch.setattr(search_run.Search, "settles_on_bounds", counting)
    return settled


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize(
    ("name", "n", "seed"), [("box", 30, 0), ("amphora", 26, 2), ("sphere", 30, 1), ("donut", 28, 3)]
)
def test_settling_on_facet_bounds_keeps_astar_optimal(
    object_contacts, few_directions, monkeypatch, compiled, name, n, seed
):
    # Once D is full, f may come from the best child's facet bound: a lower bound, so A*
    # still returns the brute-force optimum, with a certificate, expanding in nondecreasing f.
    if not compiled:
        monkeypatch.setattr(search_space, "ChildBounds", lambda m: None)
    contacts = object_contacts(name, n, seed)
    result = GraspPlanner(seed=seed).plan(contacts, 3)
    assert any(few_directions)  # the rule did settle some states
    assert result.q1 == pytest.approx(exhaustive_best(contacts, 3), abs=1e-9)
    assert result.bound == result.q1 and result.status == "optimal"
    f = [value for _, value in result.stats.trace]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(f))


@pytest.mark.parametrize("name", ["box", "sphere"])
def test_settling_on_facet_bounds_keeps_the_wastar_bound(object_contacts, few_directions, name):
    contacts = object_contacts(name, 30, 0)
    best = exhaustive_best(contacts, 3)
    result = GraspPlanner(method="wastar", eps=0.4).plan(contacts, 3)
    assert any(few_directions)
    assert result.q_ows - result.q1 <= 1.4 * (result.q_ows - best) + 1e-9
    assert result.q1 <= best + 1e-12 <= result.bound + 1e-12


def test_child_bounds_remember_by_node_tuple_and_start_afresh_when_half_full():
    table = ChildBounds(m=3, slots=8)
    keys = [np.array(k, dtype=np.int32) for k in ([1, 2, 3], [1, 2, 4], [0, 0, 7], [5, 9, 11])]
    for i, key in enumerate(keys[:3]):
        table.store(key, 0.1 * (i + 1), 1 + i % 3)
    assert table.get(keys[0]) == (0.1, 1)
    assert table.get(keys[2]) == (pytest.approx(0.3), 3)
    assert table.get(keys[3]) is None
    assert table.get(np.array([3, 2, 1], dtype=np.int32)) is None  # keys are sorted tuples, not sets
    table.store(keys[0], 0.05, 2)  # an update takes no new slot
    assert table.get(keys[0]) == (0.05, 2)
    table.store(keys[3], 0.4, 1)
    table.store(np.array([6, 6, 6], dtype=np.int32), 0.5, 1)  # half full before this: a fresh table
    assert table.get(keys[0]) is None and table.get(np.array([6, 6, 6], dtype=np.int32)) == (0.5, 1)
    with pytest.raises(ValueError, match="power of two"):
        ChildBounds(m=3, slots=12)
