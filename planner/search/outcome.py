"""What a search run returns: the incumbent, the certified result, its statistics and tree.

The half of :class:`planner.search.best_first.Search` that turns the state of a run (its
incumbent, its open list, its counters) into a :class:`~planner.search.result.SearchResult`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from planner.search.open_list import OpenList
from planner.search.refine import ChildRefinement
from planner.search.result import (
    SearchResult,
    SearchStats,
    SearchTree,
    effective_branching_factor,
    peak_rss_bytes,
)
from planner.search.search_space import State


@dataclass(frozen=True)
class Incumbent:
    """The best grasp evaluated so far.

    Attributes:
        q: Its exact Q1 [-].
        state: Its terminal state (sorted node tuple).
        parent: The unexpanded state whose branch and bound found it; None once the
            grasp is a created state.
        ident: Id of the created state, or of the parent.
    """

    q: float
    state: State
    parent: State | None
    ident: int


class SearchOutcome(ChildRefinement):
    """Results of a run (a base of :class:`planner.search.best_first.Search`, which holds the
    counters and the tree record read here)."""

    record_tree: bool
    created: dict[int, int]
    visited: dict[int, int]
    trace: list[tuple[int, float]]
    dropped: int
    _clock: tuple[float, float]
    _parent: list[int]
    _level: list[int]
    _visited: list[bool]
    _f: list[float]

    def result(self, inc: Incumbent, g: float, open_list: OpenList) -> SearchResult:
        q0, q, state = self.q0, inc.q, inc.state
        # Every unexplored grasp lies below an open state, whose stored value bounds its cost.
        lowest_f = min(g, open_list.lowest_lower())
        # Nothing open below the returned cost: the grasp is optimal (q0 - (q0 - q) may
        # round above q, so do not recompute it).
        bound = q if lowest_f >= g else max(q, q0 - lowest_f)
        eps_bound = q0 - (q0 - q) / (1.0 + self.eps)
        grasp = tuple(sorted(int(self.tree.members[node][0]) for node in state))
        idx = np.array(grasp, dtype=np.intp)
        return SearchResult(
            method=self.config["method"],
            grasp=grasp,
            positions=self.contacts.positions[idx].copy(),
            normals=self.contacts.normals[idx].copy(),
            q1=q,
            q_ows=q0,
            bound=bound,
            eps=self.eps,
            eps_bound=eps_bound,
            stats=self.statistics(self.depth(state)),
            config=self.config,
            contact_source=self.contacts.source,
            tree=self.search_tree(inc.ident) if self.record_tree else None,
            status=self.finished_status(q, bound),
        )

    def statistics(self, solution_depth: int) -> SearchStats:
        """The statistics of the run so far, for a solution at this depth."""
        wall0, cpu0 = self._clock
        created, visited = self.created, self.visited
        levels = max(max(created), max(visited, default=0)) + 1
        table = self.child_bounds
        table_facet_bounds, table_rejections = (0, 0) if table is None else (table.facet_bounds, table.rejections)
        return SearchStats(
            created=sum(created.values()),
            visited=sum(visited.values()),
            created_per_level=tuple(created.get(i, 0) for i in range(levels)),
            visited_per_level=tuple(visited.get(i, 0) for i in range(levels)),
            q1_evaluations=self.oracle.evaluations,
            q1_cache_hits=self.oracle.cache_hits,
            bound_evaluations=self.bound_evaluations,
            bound_rejections=self.oracle.bound_rejections + table_rejections,
            hull_calls=self.oracle.hull_calls,
            pruned=self.pruned,
            symmetric_removed=self.symmetry.removed if self.symmetry else 0,
            effective_branching_factor=effective_branching_factor(sum(created.values()) - 1, solution_depth),
            solution_depth=solution_depth,
            trace=tuple(self.trace),
            wall_seconds=time.perf_counter() - wall0,
            cpu_seconds=time.process_time() - cpu0,
            peak_rss_bytes=peak_rss_bytes(),
            facet_bounds=self.oracle.facet_bounds + table_facet_bounds,
            dropped=self.dropped,
        )

    def finished_status(self, q1: float, bound: float) -> str:
        """What a finished search certifies (see :data:`~planner.search.result.SEARCH_STATUSES`)."""
        if self.symmetry is not None:
            return "approximate"  # the bound covers the symmetry-reduced space only
        return "optimal" if bound <= q1 else "bounded"

    def search_tree(self, goal: int) -> SearchTree:
        """The recorded tree, with the path from the root to ``goal``."""
        path = [goal]
        while self._parent[path[-1]] >= 0:
            path.append(self._parent[path[-1]])
        return SearchTree(
            parent=tuple(self._parent),
            level=tuple(self._level),
            visited=tuple(self._visited),
            f=tuple(self._f),
            path=tuple(reversed(path)),
        )
