"""Best-first search over super-contact grasps: A*, weighted A* and Dijkstra (paper Sec. III-IV).

:class:`GraspPlanner` is the entry point; :mod:`ogcp.planner.search.best_first` runs one search
over the states of :mod:`ogcp.planner.search.search_space`, whose children come from the
partitions of :mod:`ogcp.planner.search.partitions` (Γ^ru, Γ^fc).
"""

from ogcp.planner.search.grasp_planner import DEFAULT_WASTAR_EPS, HEURISTICS, METHODS, GraspPlanner
from ogcp.planner.search.partitions import (
    SUCCESSORS,
    KMeansPartitioner,
    PartitionTree,
    RandomPartitioner,
    make_partitioner,
)
from ogcp.planner.search.result import SearchResult, SearchStats, SearchTree, effective_branching_factor
from ogcp.planner.search.symmetry import SymmetryFilter

__all__ = [
    "DEFAULT_WASTAR_EPS",
    "HEURISTICS",
    "METHODS",
    "SUCCESSORS",
    "GraspPlanner",
    "KMeansPartitioner",
    "PartitionTree",
    "RandomPartitioner",
    "SearchResult",
    "SearchStats",
    "SearchTree",
    "SymmetryFilter",
    "effective_branching_factor",
    "make_partitioner",
]
