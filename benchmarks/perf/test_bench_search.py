"""Search and exhaustive-search speed on fixed inputs."""

from __future__ import annotations

from ogcp.planner.baselines.es import _chunk_task
from ogcp.planner.search.grasp_planner import GraspPlanner


def test_es_chunk(benchmark, box200):
    import numpy as np

    edges = np.linspace(0.0, 1.0, 51)
    result = benchmark.pedantic(_chunk_task, args=(box200, 3, 0, 5000, edges, False), rounds=1, iterations=1)
    assert result.evaluated == 5000


def test_astar_200(benchmark, box200):
    result = benchmark.pedantic(GraspPlanner().plan, args=(box200, 3), rounds=1, iterations=1)
    assert result.bound == result.q1 > 0


def test_wastar_200(benchmark, box200):
    result = benchmark.pedantic(GraspPlanner(method="wastar", eps=0.4).plan, args=(box200, 3), rounds=1, iterations=1)
    assert result.q1 > 0


def _m5_states(contacts, count: int = 300):
    """A search space at m = 5 and the first ``count`` states of a breadth-first walk of it."""
    from ogcp.planner.grasp.constraints import DistinctContacts
    from ogcp.planner.search.search_space import SearchSpace

    config = GraspPlanner().resolved_config()
    config["m"] = 5
    space = SearchSpace(contacts, 5, config, [DistinctContacts()])
    states = [(0,) * 5]
    for state in states:
        if len(states) >= count:
            break
        states.extend(space.successors(state))
    return space, states[:count]


def test_children_listing_python(benchmark, sphere1000):
    """Γh children and their support bounds listed in Python (the reference for the compiled call)."""
    benchmark.group = "children"
    space, states = _m5_states(sphere1000)

    def listing():
        return sum(len([space.upper(v) for _, v in space.heuristic_children(s)]) for s in states)

    assert benchmark(listing) > len(states)


def test_children_listing_compiled(benchmark, sphere1000):
    """The same children and bounds by one compiled call per state (what the search uses)."""
    benchmark.group = "children"
    space, states = _m5_states(sphere1000)
    space.heuristic_bounds(states[0])  # compile or load outside the timing

    def listing():
        return sum(len(space.heuristic_bounds(s)[1]) for s in states)

    assert benchmark(listing) > len(states)
