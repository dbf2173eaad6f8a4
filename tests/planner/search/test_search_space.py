"""The search space's own shortcuts agree with the generic constraint tests they replace."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ogcp.planner.grasp.constraints import DistinctContacts, MaxFingerSpread
from ogcp.planner.search import GraspPlanner
from ogcp.planner.search.best_first import Search
from ogcp.planner.search.children_kernel import decode_children, first_lowest
from ogcp.planner.search.search_space import SearchSpace


def _space(contacts, m: int, heuristic_branching: int) -> SearchSpace:
    planner = GraspPlanner(method="astar", heuristic_branching=heuristic_branching)
    config = planner.resolved_config()
    config["m"] = m
    spread = 0.8 * float(np.ptp(contacts.positions, axis=0).max())
    return SearchSpace(contacts, m, config, [DistinctContacts(), MaxFingerSpread(spread)])


def test_distinct_contacts_by_count_agrees_with_halls_condition(object_contacts):
    """Every combination of tree nodes at each level, valid or not, gets the same verdict."""
    contacts = object_contacts("amphora", 40, 0)
    for m in (3, 4):
        space = _space(contacts, m, 2)
        level = [(0,) * m]
        rejected = 0
        for _ in range(7):
            nodes = sorted({child for state in level for node in state for child in space.tree.children(node)})
            states = list(itertools.combinations_with_replacement(nodes, m))[:3000]
            for state in states:
                parts = space.members(state)
                terminal = space.is_terminal(state)
                by_count = space.valid(parts, terminal, state)
                assert by_count == space.valid(parts, terminal), state
                rejected += not by_count
            level = [s for s in states if space.valid(space.members(s), space.is_terminal(s), s)][:200]
        assert rejected > 0  # the check was exercised on both verdicts


def test_heuristic_parts_keyed_by_node_and_part_agree(object_contacts):
    """Γh with its own partitioner: children judged by count are those judged by matching."""
    contacts = object_contacts("box", 40, 0)
    space = _space(contacts, 3, 3)
    assert not space.heuristic_shares_tree
    states = [(0, 0, 0)]
    for state in list(states):
        states.extend(space.successors(state))
    checked = 0

    def generic_valid(parts, terminal, keys=None):
        return SearchSpace.valid(space, parts, terminal)

    for state in states:
        children = space.heuristic_children(state)
        try:
            space.valid = generic_valid  # type: ignore[method-assign]
            generic = space.heuristic_children(state)
        finally:
            del space.valid

        def unions(found):
            return [b"".join(mask.tobytes() for mask in space.child_masks(key)) for key, _ in found]

        assert unions(children) == unions(generic)
        checked += len(children)
    assert checked > 0


@pytest.mark.parametrize("heuristic_branching", [2, 3])
def test_waiting_children_are_compact_and_their_bounds_hold(object_contacts, heuristic_branching):
    """A state's branch and bound left waiting keeps keys and bounds in arrays, and every
    bound it holds is an upper bound of that child's exact Q1 (with Γh on the expansion
    tree and on its own partitioner)."""
    contacts = object_contacts("box", 60, 0)
    planner = GraspPlanner(method="astar", heuristic_branching=heuristic_branching)
    config = planner.resolved_config()
    config["m"] = 4
    search = Search(contacts, 4, config, [DistinctContacts()])
    result = search.run()
    assert result.status == "optimal" and search._pending
    checked = 0
    for ident, record in search._pending.items():
        if heuristic_branching == 2:  # the compiled branch and bound: one buffer per state
            assert isinstance(record, np.ndarray) and record.dtype == np.uint8
        children, bounds, levels, starts = search.waiting(ident)
        assert starts.dtype == np.int32 and len(starts) == len(bounds)
        assert children.dtype == np.int32 and children.shape == (len(bounds), 4)
        assert bounds.dtype == np.float64 and levels.dtype == np.int8 and len(levels) == len(bounds)
        for row, bound, level in zip(children[:4], bounds, levels, strict=False):
            key = tuple(row.tolist())
            exact = search.oracle.of_masks(search.child_masks(key))
            # A negative support bound proves Q1 = 0 (the origin lies outside the hull).
            assert exact <= max(bound, 0.0) + 1e-12, (key, int(level))
            checked += 1
    assert checked > 0


@pytest.mark.parametrize("m", [3, 4, 5])
def test_compiled_children_are_the_python_listing(object_contacts, m):
    """The compiled Γh listing gives the Python listing's children in its order, with the
    bit-identical support bounds, the direction of each bound and the grasp flags."""
    contacts = object_contacts("amphora", 60, 2)
    planner = GraspPlanner(method="astar")
    config = planner.resolved_config()
    config["m"] = m
    space = SearchSpace(contacts, m, config, [DistinctContacts()])
    assert space._compiled_children
    rng = np.random.default_rng(m)
    states = [(0,) * m]
    checked = repeated = 0
    while states and checked < 400:
        state = states.pop(int(rng.integers(len(states))))
        keys, bounds, starts, terminal = space.heuristic_bounds(state)
        found = space.heuristic_children(state)
        assert [tuple(row) for row in keys.tolist()] == [key for key, _ in found]
        # The compact numbers of the children name the same children.
        numbers = space.numbered_children(state)[0]
        assert [space.child_of_number(state, int(c)) for c in numbers] == [key for key, _ in found]
        for key, bound, start, grasp, (_, vectors) in zip(keys.tolist(), bounds, starts, terminal, found, strict=True):
            assert bound == space.oracle.bounds.bound(vectors)
            assert (bound, int(start)) == space.oracle.bounds.lowest(vectors)
            assert grasp == space.is_terminal(tuple(key))
            for node, vector in zip(key, vectors, strict=True):  # rows extended in place = fresh maxima
                assert np.array_equal(vector, space.oracle.bounds.vector(space.tree.members[node])[: len(vector)])
            repeated += len(set(key)) < m
        checked += len(found)
        learned = rng.normal(size=(3, 6))
        space.oracle.bounds.add(learned / np.linalg.norm(learned, axis=1, keepdims=True))  # rows now extend
        states.extend(tuple(key) for key in keys.tolist() if not space.is_terminal(tuple(key)))
    assert checked >= 100 and repeated > 0


@pytest.mark.parametrize("m", [3, 5])
def test_successors_from_the_compiled_listing_are_the_python_successors(object_contacts, m):
    """Expansion takes its successors and their support bounds from the compiled listing:
    the same states in the same order as :meth:`SearchSpace.successors`, U as :meth:`upper`,
    and the same count of combinations pruned by distinct contacts."""
    contacts = object_contacts("box", 40, 1)
    config = GraspPlanner(method="astar").resolved_config()
    config["m"] = m
    compiled = SearchSpace(contacts, m, config, [DistinctContacts()])
    python = SearchSpace(contacts, m, config, [DistinctContacts()])
    python._compiled_children = False
    rng = np.random.default_rng(m)
    states = [(0,) * m]
    checked = 0
    while states and checked < 300:
        state = states.pop(int(rng.integers(len(states))))
        children, bounds = compiled.successors_with_bounds(state)
        expected, uppers = python.successors_with_bounds(state)
        assert children == expected and bounds == uppers
        assert compiled.pruned == python.pruned
        checked += len(children)
        states.extend(child for child in children if not compiled.is_terminal(child))
    assert checked >= 100 and compiled.pruned > 0


@pytest.mark.parametrize("m", [3, 5])
def test_decoded_children_are_the_listed_ones(object_contacts, m):
    """An expansion decodes its children from the numbers its branch and bound kept: the
    listing's children, grasp flags, depths and count of combinations distinct contacts ruled out."""
    contacts = object_contacts("box", 40, 1)
    config = GraspPlanner(method="astar").resolved_config()
    config["m"] = m
    space = SearchSpace(contacts, m, config, [DistinctContacts()])
    rng = np.random.default_rng(m)
    states = [(0,) * m]
    checked = rejected = 0
    while states and checked < 300:
        state = states.pop(int(rng.integers(len(states))))
        keys, _, _, terminal, listed_rejected, codes = space._listing(state)
        nodes = np.array(state, dtype=np.int64)
        decoded, grasps, depths, count = decode_children(
            nodes, codes, space._table, space._widths, space._sizes, space._depths
        )
        assert np.array_equal(decoded, keys) and np.array_equal(grasps, terminal)
        assert depths.tolist() == [space.depth(tuple(key)) for key in keys.tolist()]
        assert count == listed_rejected
        checked += len(keys)
        rejected += count
        states.extend(tuple(key) for key, leaf in zip(keys.tolist(), terminal, strict=True) if not leaf)
    assert checked >= 100 and rejected > 0


@pytest.mark.parametrize("count", [0, 1, 7, 8, 9, 17, 2000])
def test_first_lowest_is_the_first_smallest_value(count):
    rng = np.random.default_rng(count)
    for _ in range(20):
        values = np.round(rng.random(count + 5), 1)  # many ties
        values[rng.random(count + 5) < 0.1] = np.inf
        lowest, index = first_lowest(values, count)
        head = values[:count]
        if not count or np.isinf(head).all():
            assert (lowest, index) == (np.inf, 0)
            continue
        assert lowest == head.min() and index == int(np.argmin(head))
