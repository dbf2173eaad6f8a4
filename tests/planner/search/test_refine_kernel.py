"""The compiled branch and bound over a state's Γh children (ogcp.planner.search.refine_kernel)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ogcp.planner.grasp import subset_quality
from ogcp.planner.grasp.kernel.geometry import CUT_MARGIN
from ogcp.planner.grasp.subset_quality import EXACT
from ogcp.planner.search import GraspPlanner, search_space
from ogcp.planner.search import best_first as search_run
from ogcp.planner.search.refine_kernel import ChildBounds, share_normal
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


def test_a_shared_normal_lowers_each_child_to_its_own_support_along_it():
    # State (node 0, node 1); node 0 splits into nodes 2, 3 and node 1 into 4, 5, so the
    # children in product order are (2, 4), (2, 5), (3, 4), (3, 5).
    rng = np.random.default_rng(3)
    wrenches = rng.normal(size=(12, 4, 6))
    members = {2: [0, 1, 2], 3: [3, 4], 4: [5, 6, 7, 8], 5: [9, 10, 11]}
    masks = np.zeros((6, 2), dtype=np.uint8)
    for node, contacts in members.items():
        flags = np.zeros(12, dtype=bool)
        flags[contacts] = True
        masks[node] = np.packbits(flags)
    table = np.full((6, 2), -1, dtype=np.int64)
    table[0], table[1] = (2, 3), (4, 5)
    widths = np.array([2, 2, 0, 0, 0, 0])
    codes = np.arange(4, dtype=np.uint8)
    bounds = np.array([9.0, 9.0, -5.0, 9.0])
    levels = np.array([0, 1, 0, EXACT], dtype=np.int8)
    u = rng.normal(size=6)
    u /= np.linalg.norm(u)
    counters = np.zeros(5, dtype=np.int64)
    share_normal(u, np.array([0, 1]), table, widths, codes, bounds, levels, 0, wrenches, masks, counters)

    def support(nodes):
        return max(float(np.max(wrenches[members[n]] @ u)) for n in nodes) + CUT_MARGIN

    assert bounds[1] == pytest.approx(support((2, 5)), abs=1e-15)  # lowered, whatever its level
    assert bounds[0] == 9.0 and bounds[3] == 9.0  # the source child and an exact value stay
    assert bounds[2] == -5.0 < support((3, 4))  # a bound already lower stays
    assert counters[3] == 1 and counters[4] == 1


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize(("name", "n", "seed"), [("amphora", 40, 0), ("box", 36, 1), ("donut", 40, 2)])
def test_sharing_normals_keeps_astar_optimal_with_fewer_facet_bounds(
    object_contacts, monkeypatch, compiled, name, n, seed
):
    if not compiled:
        monkeypatch.setattr(search_space, "ChildBounds", lambda m: None)  # the Python loop
    contacts = object_contacts(name, n, seed)
    shared = GraspPlanner(seed=seed).plan(contacts, 3)
    monkeypatch.setattr(search_run.Search, "share_normals", False)
    alone = GraspPlanner(seed=seed).plan(contacts, 3)
    best = exhaustive_best(contacts, 3)
    for result in (shared, alone):
        assert result.q1 == pytest.approx(best, abs=1e-9)
        assert result.bound == result.q1 and result.status == "optimal"
    f = [value for _, value in shared.stats.trace]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(f))
    assert shared.stats.facet_bounds < alone.stats.facet_bounds


@pytest.mark.parametrize(("name", "n", "seed", "m"), [("amphora", 40, 0, 3), ("box", 30, 1, 4), ("donut", 40, 2, 3)])
def test_children_entering_with_their_parents_bounds_keep_astar_optimal(object_contacts, monkeypatch, name, n, seed, m):
    contacts = object_contacts(name, n, seed)
    entered = []  # (upper bound the child entered with, its contacts)
    original = search_run.Search.settled_successors

    def recording(self, ident, state):
        settled = original(self, ident, state)
        if settled is not None:
            keys, terminal, _, bounds, levels = settled
            for key, grasp, bound, level in zip(keys.tolist(), terminal, bounds, levels, strict=True):
                assert grasp == self.is_terminal(tuple(key))
                if level > 0 and not grasp:
                    entered.append((bound, np.concatenate(self.members(tuple(key)))))
        return settled

    monkeypatch.setattr(search_run.Search, "settled_successors", recording)
    kept = GraspPlanner(seed=seed).plan(contacts, m)
    monkeypatch.setattr(search_run.Search, "keep_settled", False)
    fresh = GraspPlanner(seed=seed).plan(contacts, m)
    best = exhaustive_best(contacts, m)
    for result in (kept, fresh):
        assert result.q1 == pytest.approx(best, abs=1e-9)
        assert result.bound == result.q1 and result.status == "optimal"
    f = [value for _, value in kept.stats.trace]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(f))
    # Each child that skipped its first pop's facet bound entered with an upper bound of its Q1.
    oracle = subset_quality.GraspQuality(contacts, seed)
    assert len(entered) > 10
    for bound, members in entered:
        assert bound >= oracle.of_masks([oracle.mask_of(np.unique(members))]) - 1e-12
    assert kept.stats.facet_bounds < fresh.stats.facet_bounds
