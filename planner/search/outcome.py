"""What a search run returns: the incumbent, the certified result, its statistics and tree.

The half of :class:`ogcp.planner.search.best_first.Search` that turns the state of a run (its
incumbent, its open list, its counters) into a :class:`~ogcp.planner.search.result.SearchResult`,
and the dive that finds a grasp for a search stopped before it evaluated one.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ogcp.planner.search.memory import Forgetting
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.polish import Polisher
from ogcp.planner.search.result import (
    SearchResult,
    SearchStats,
    SearchTree,
    effective_branching_factor,
    peak_rss_bytes,
)
from ogcp.planner.search.search_space import State

#: States a dive may visit before it gives up (each costs one successor generation).
DIVE_BUDGET = 20_000
#: Open states a dive starts from, most promising first.
DIVE_STARTS = 16
#: Children a dive ranks at each step (Γ lists up to b^m; a dive wants one good path down).
DIVE_CHILDREN = 64
#: [s] Most time a dive takes: it runs after a search's time limit.
DIVE_SECONDS = 1.0


@dataclass(frozen=True)
class Incumbent:
    """The best grasp evaluated so far.

    Attributes:
        q: Its exact Q1 [-].
        state: Its terminal state (sorted node tuple); None for a grasp found by local search
            (:mod:`ogcp.planner.search.polish`), which is no state of the tree.
        parent: The unexpanded state whose branch and bound found it; None once the
            grasp is a created state, and for local search's grasps.
        ident: Id of the created state, or of the parent (-1 for local search's grasps).
        contacts: The grasp's sorted contact indices where ``state`` is None.
    """

    q: float
    state: State | None
    parent: State | None
    ident: int
    contacts: tuple[int, ...] = ()


class SearchOutcome(Forgetting):
    """Results of a run (a base of :class:`ogcp.planner.search.best_first.Search`, which holds the
    counters and the tree record read here)."""

    record_tree: bool
    created: dict[int, int]
    visited: dict[int, int]
    trace: np.ndarray
    expansions: int
    dropped: int
    polisher: Polisher | None
    _clock: tuple[float, float]
    _parent: list[int]
    _level: list[int]
    _visited: list[bool]
    _f: list[float]

    def result(self, inc: Incumbent, g: float, open_list: OpenList) -> SearchResult:
        q0, q = self.q0, inc.q
        # Every unexplored grasp lies below an open state, whose stored value bounds its cost.
        lowest_f = min(g, self.lowest_lower(open_list))
        # Nothing open below the returned cost: the grasp is optimal (q0 - (q0 - q) may
        # round above q, so do not recompute it).
        bound = q if lowest_f >= g else max(q, q0 - lowest_f)
        eps_bound = q0 - (q0 - q) / (1.0 + self.eps)
        grasp = self.grasp_of(inc)
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
            stats=self.statistics(self.incumbent_depth(inc)),
            config=self.config,
            contact_source=self.contacts.source,
            tree=self.search_tree(inc.ident) if self.record_tree else None,
            status=self.finished_status(q, bound),
        )

    def grasp_of(self, inc: Incumbent) -> tuple[int, ...]:
        """The incumbent's sorted contact indices."""
        if inc.state is None:
            return inc.contacts
        return tuple(sorted(int(self.tree.members[node][0]) for node in inc.state))

    def incumbent_depth(self, inc: Incumbent) -> int:
        """The depth of the incumbent's state; the deepest created for local search's grasps."""
        return max(self.created) if inc.state is None else self.depth(inc.state)

    def dive(self, open_list: OpenList) -> None:
        """Find valid grasps below the most promising open states: depth first, highest U first.

        Each of the :data:`DIVE_STARTS` open states with the smallest bounds is descended
        until its first valid terminal state, which is offered as the incumbent (found by
        the open state it lies below, so the certificate is unchanged), ranking at most
        :data:`DIVE_CHILDREN` children of each state. The incumbent stays None when
        :data:`DIVE_BUDGET` states, or :data:`DIVE_SECONDS`, hold no valid grasp.
        """
        budget = DIVE_BUDGET
        deadline = time.perf_counter() + DIVE_SECONDS
        for entry in open_list.smallest_lower(DIVE_STARTS):
            start = self.state_of(entry[6])
            stack = [start]
            while stack and budget > 0 and time.perf_counter() < deadline:
                state = stack.pop()
                budget -= 1
                if self.is_terminal(state):
                    self.offer(self.exact(state), tuple(sorted(state)), start, entry[6])
                    break
                children = self.successors(state, limit=DIVE_CHILDREN, deadline=deadline)
                # Ascending U, so the child with the highest bound is popped next.
                stack.extend(sorted(children, key=lambda child: self.upper(self.node_vectors(child))))

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
            trace=tuple(enumerate(self.trace[: self.expansions].tolist())),
            wall_seconds=time.perf_counter() - wall0,
            cpu_seconds=time.process_time() - cpu0,
            peak_rss_bytes=peak_rss_bytes(),
            facet_bounds=self.oracle.facet_bounds + table_facet_bounds,
            dropped=self.dropped,
            local_search_evaluations=0 if self.polisher is None else self.polisher.evaluations,
            local_search_seconds=0.0 if self.polisher is None else self.polisher.seconds,
            forgotten=self.forgotten,
        )

    def finished_status(self, q1: float, bound: float) -> str:
        """What a finished search certifies (see :data:`~ogcp.planner.search.result.SEARCH_STATUSES`)."""
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
