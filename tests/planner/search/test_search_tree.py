"""The recorded search tree (paper Fig. 5): shape, solution path, JSON form."""

from __future__ import annotations

import itertools
import json

import pytest

from ogcp.planner.search import GraspPlanner


# box 100 with eps = 1: WA* returns a better grasp met in a branch and bound, whose state
# is created by expanding its parent at the end (the path must still be a chain).
@pytest.mark.parametrize("method, eps, n", [("astar", None, 40), ("wastar", 0.4, 40), ("wastar", 1.0, 100)])
def test_tree_is_consistent_with_the_statistics_and_the_path(method, eps, n, object_contacts):
    result = GraspPlanner(method=method, eps=eps, record_tree=True).plan(
        object_contacts("box", n, 2 if n == 100 else 0), 3
    )
    tree, stats = result.tree, result.stats
    assert tree is not None
    assert len(tree.parent) == len(tree.level) == len(tree.visited) == len(tree.f) == stats.created
    assert sum(tree.visited) == stats.visited
    assert tree.parent[0] == -1 and tree.level[0] == 0
    for child, parent in enumerate(tree.parent[1:], start=1):
        assert 0 <= parent < child  # parents precede their children
        assert tree.visited[parent] and tree.level[child] >= tree.level[parent]
    for level in range(len(stats.created_per_level)):
        assert sum(lv == level for lv in tree.level) == stats.created_per_level[level]
    path = tree.path
    assert path[0] == 0 and tree.level[path[-1]] == stats.solution_depth
    assert all(tree.parent[b] == a for a, b in itertools.pairwise(path))  # a chain from the root
    assert all(tree.visited[i] for i in path)
    assert tree.f[path[-1]] == pytest.approx(result.q_ows - result.q1, abs=1e-12)
    if method == "astar":  # consistent heuristic: f never decreases along a path
        assert all(tree.f[b] >= tree.f[a] - 1e-12 for a, b in itertools.pairwise(path))


def test_recording_changes_nothing_and_json_has_the_tree_only_when_recorded(object_contacts):
    contacts = object_contacts("amphora", 26, 2)
    plain = GraspPlanner().plan(contacts, 3)
    recorded = GraspPlanner(record_tree=True).plan(contacts, 3)
    assert (plain.grasp, plain.q1, plain.stats.created, plain.stats.visited, plain.stats.trace) == (
        recorded.grasp,
        recorded.q1,
        recorded.stats.created,
        recorded.stats.visited,
        recorded.stats.trace,
    )
    assert plain.tree is None and "tree" not in plain.to_dict()
    record = json.loads(json.dumps(recorded.to_dict()))
    tree = record["tree"]
    assert set(tree) == {"parent", "level", "visited", "f", "path"}
    assert len(tree["parent"]) == record["stats"]["created"] and sum(tree["visited"]) == record["stats"]["visited"]
    assert tree["path"][-1] in range(len(tree["parent"]))
