"""Search results: the grasp, its certificate, statistics and the search tree.

Their JSON form is the ``ogcp.plan/1`` record of :mod:`ogcp.planner.records.plan`.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.records.plan import check_result, plan_record

#: What a search result certifies. ``optimal``: no grasp beats it (bound = Q1);
#: ``bounded``: WA* finished, its cost within 1 + eps of the optimum's; ``approximate``:
#: optimal over the symmetry-reduced space only; ``stopped``: the time limit ran out, the
#: best grasp found so far is returned with the certified bound; ``memory``: the same, stopped
#: at its memory limit (:mod:`ogcp.planner.search.memory`); ``interrupted``: the same, stopped by a
#: request (Ctrl-C in the CLI).
SEARCH_STATUSES = ("optimal", "bounded", "approximate", "stopped", "memory", "interrupted")
#: The statuses of a search that did not finish.
UNFINISHED = ("stopped", "memory", "interrupted")


@dataclass(frozen=True)
class SearchStats:
    """Search statistics.

    Attributes:
        created: States generated and put on the open list (root included).
        visited: States expanded.
        created_per_level: Created states per tree level (index = depth).
        visited_per_level: Expanded states per tree level.
        q1_evaluations: Q1 computations (cache misses).
        q1_cache_hits: Q1 lookups answered from the cache.
        bound_evaluations: Support-function upper bounds computed.
        bound_rejections: Q1 = 0 settled by a negative support bound (no hull).
        hull_calls: qhull invocations.
        pruned: Successors rejected by a constraint.
        symmetric_removed: Successors dropped by approximate symmetry removal.
        effective_branching_factor: b* with N + 1 = 1 + b* + ... + b*^d (N = created
            states below the root, d = solution depth).
        solution_depth: Depth of the returned terminal state.
        trace: (iteration, f of the expanded state) per expansion.
        wall_seconds: Wall-clock time [s].
        cpu_seconds: CPU time of this process [s].
        peak_rss_bytes: Peak resident memory of the process when the search ended [bytes]
            (the operating system's high-water mark: it includes whatever the process held
            before the search; 0 where the platform does not report it).
        facet_bounds: Facet bounds of Q1 computed (each settles a state's child, or its g
            for A*, without an exact value when it is low enough).
        dropped: Open-list entries not kept because their lower bound of f showed that no
            grasp below the state beats the best grasp found (memory only: A* would never
            pop them before its goal).
        local_search_evaluations: Grasps scored by local search (:mod:`ogcp.planner.search.polish`).
        local_search_seconds: Wall-clock time local search took, part of ``wall_seconds`` [s].
        forgotten: Open states forgotten at the memory limit (:mod:`ogcp.planner.search.memory`).
    """

    created: int
    visited: int
    created_per_level: tuple[int, ...]
    visited_per_level: tuple[int, ...]
    q1_evaluations: int
    q1_cache_hits: int
    bound_evaluations: int
    bound_rejections: int
    hull_calls: int
    pruned: int
    symmetric_removed: int
    effective_branching_factor: float
    solution_depth: int
    trace: tuple[tuple[int, float], ...]
    wall_seconds: float
    cpu_seconds: float
    peak_rss_bytes: int = 0
    facet_bounds: int = 0
    dropped: int = 0
    local_search_evaluations: int = 0
    local_search_seconds: float = 0.0
    forgotten: int = 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "created": self.created,
            "visited": self.visited,
            "created_per_level": list(self.created_per_level),
            "visited_per_level": list(self.visited_per_level),
            "q1_evaluations": self.q1_evaluations,
            "q1_cache_hits": self.q1_cache_hits,
            "bound_evaluations": self.bound_evaluations,
            "bound_rejections": self.bound_rejections,
            "hull_calls": self.hull_calls,
            "pruned": self.pruned,
            "symmetric_removed": self.symmetric_removed,
            "effective_branching_factor": self.effective_branching_factor,
            "solution_depth": self.solution_depth,
            "trace": [[i, f] for i, f in self.trace],
            "wall_seconds": self.wall_seconds,
            "cpu_seconds": self.cpu_seconds,
            "peak_rss_bytes": self.peak_rss_bytes,
            "facet_bounds": self.facet_bounds,
            "dropped": self.dropped,
            "local_search_evaluations": self.local_search_evaluations,
            "local_search_seconds": self.local_search_seconds,
            "forgotten": self.forgotten,
        }


def peak_rss_bytes() -> int:
    """The process's peak resident memory so far [bytes]; 0 where it is not reported."""
    try:
        import resource  # POSIX only
    except ImportError:
        return 0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # Linux reports kilobytes, macOS bytes.
    return int(peak if sys.platform == "darwin" else peak * 1024)


@dataclass(frozen=True)
class SearchTree:
    """The search tree of one run (paper Fig. 5), as parallel per-state lists.

    State ids number the created states in creation order; the root is 0.

    Attributes:
        parent: Parent id per state; -1 for the root. Parents precede their children.
        level: Tree level (depth) per state; 0 for the root.
        visited: Whether the state was expanded.
        f: Unweighted f per state: exact for states whose heuristic was finished (every
            expanded state), otherwise the lower bound the search had reached [-].
        path: Ids of the returned solution path, root first, goal last.
    """

    parent: tuple[int, ...]
    level: tuple[int, ...]
    visited: tuple[bool, ...]
    f: tuple[float, ...]
    path: tuple[int, ...]

    def to_dict(self) -> dict[str, Any]:
        """Compact JSON form: parallel lists (``visited`` as 0/1)."""
        return {
            "parent": list(self.parent),
            "level": list(self.level),
            "visited": [int(v) for v in self.visited],
            "f": list(self.f),
            "path": list(self.path),
        }


@dataclass(frozen=True, eq=False)
class SearchResult:
    """The grasp a search returned, with its quality certificate.

    Attributes:
        method: ``astar``, ``wastar`` or ``dijkstra``.
        grasp: Sorted contact indices, length m.
        positions: Contact points of the grasp, shape (m, 3) [m].
        normals: Inward unit normals of the grasp, shape (m, 3).
        q1: Exact Q1 of the grasp [-].
        q_ows: Q1 of the whole contact set (object wrench space) [-].
        bound: Certified upper bound on the optimal Q1 when the search stopped [-]:
            equals ``q1`` for A* and Dijkstra.
        eps: WA* inflation (0 for A* and Dijkstra).
        eps_bound: Upper bound on the optimum implied by the (1 + eps) guarantee on path
            cost, ``q_ows - (q_ows - q1) / (1 + eps)`` [-].
        stats: Search statistics.
        config: Resolved search parameters (seed included).
        contact_source: Provenance of the contact set.
        tree: The search tree, when the planner was asked to record it.
        status: What the result certifies, one of :data:`SEARCH_STATUSES`.
    """

    method: str
    grasp: tuple[int, ...]
    positions: NDArray[np.float64]
    normals: NDArray[np.float64]
    q1: float
    q_ows: float
    bound: float
    eps: float
    eps_bound: float
    stats: SearchStats
    config: dict[str, Any] = field(default_factory=dict)
    contact_source: dict[str, Any] = field(default_factory=dict)
    tree: SearchTree | None = None
    status: str = "optimal"

    def __post_init__(self) -> None:
        """Refuse impossible values: OgcpError unless 0 <= q1 <= bound <= q_ows (``check_result``)."""
        check_result(self.method, self.q1, self.q_ows, self.bound)

    @property
    def gap(self) -> float:
        """Certified optimality gap: ``bound - q1`` [-]; 0 for a proven optimum."""
        return max(0.0, self.bound - self.q1)

    def to_dict(self, contact_set: dict[str, Any] | None = None) -> dict[str, Any]:
        """JSON form, schema ``ogcp.plan/1``.

        Args:
            contact_set: Optional description of the contact set (COM, rho, mu, k) so the
                plan can be evaluated without re-sampling.
        """
        return plan_record(
            self.method,
            self.grasp,
            self.q1,
            self.q_ows,
            self.bound,
            self.positions,
            self.normals,
            stats=self.stats.to_dict(),
            config=self.config,
            contact_set=contact_set,
            eps=self.eps,
            eps_bound=self.eps_bound,
            source=self.contact_source,
            status=self.status,
            gap=self.gap,
            **({} if self.tree is None else {"tree": self.tree.to_dict()}),
        )


def effective_branching_factor(created_below_root: int, depth: int) -> float:
    """Solve N + 1 = sum_{i=0}^{d} b^i for b (bisection); NaN when d = 0."""
    if depth <= 0:
        return math.nan
    target = created_below_root + 1

    def total(b: float) -> float:
        return float(sum(b**i for i in range(depth + 1)))

    lo, hi = 0.0, max(1.0, float(target))
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if total(mid) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
