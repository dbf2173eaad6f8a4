"""Search and exhaustive-search speed on fixed inputs."""

from __future__ import annotations

from planner.baselines.es import _chunk_task
from planner.search.grasp_planner import GraspPlanner


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
