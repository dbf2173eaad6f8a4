"""Best-first search over super-contact grasps: A*, weighted A* and Dijkstra (paper Sec. III-IV).

A state is a tuple of m super-contacts, each a node of the :class:`PartitionTree` that the
expansion successor function Γ induces on C. With q(s) = Q1 of the union of the
super-contacts (Eq. 9) and arc cost d(s, s') = q(s) - q(s') (Eq. 10), the path cost is
g(s) = q(s0) - q(s) whatever the path, and the heuristic of Eq. 11 gives
f(s) = g(s) + (1 + eps) h(s) with h(s) = q(s) - max_{s' in Γh(s)} q(s').

Design points:

* Finger order is irrelevant to Q1 and to every constraint, so states are kept as
  sorted tuples (exact; disable with ``ordered=True`` to reproduce the paper's raw tree).
  Every sorted state then has exactly one parent, so no closed list is needed.
* Exact values are computed lazily (:mod:`ogcp.planner.search.best_first`). A successor enters the
  open list keyed by a lower bound of its f: q(s0) - U(s'), where U is a cheap
  support-function upper bound of q (:mod:`ogcp.planner.grasp.support_bound`), raised to its parent's f
  when Γh = Γ (the heuristic is then consistent, Thm. III.2b); where its parent's branch and
  bound already tightened that bound (Γh = Γ: the children it bounded are the successors), it
  enters with that facet bound or exact value as its g instead. Each time a state
  reaches the front its bound is tightened one step: its exact g (one Q1 evaluation),
  then branch and bound over Γh(s'), children in order of decreasing U, one exact value
  at a time, the state going back to the list whenever its bound
  q(s0) - max(best so far, next U) is no longer the smallest. A finished branch and
  bound gives the exact f, and only then is the state expanded. Terminal states are
  always evaluated exactly before they can be returned, so A* stays optimal.
* WA* orders exactly scored states by the paper's g + (1 + eps) h and the others by
  (1 + eps) times their lower bound of f. Both are at most (1 + eps) f, so the open
  state on an optimal path never has a key above (1 + eps) C* and the returned cost is
  within (1 + eps) of optimal; states whose bound already exceeds the returned cost
  divided by 1 + eps are never evaluated. At the goal test WA* returns the best grasp
  it has evaluated exactly (often a terminal child met in a branch and bound), which
  only improves on the popped goal; A*'s popped goal is already optimal.
* The open list also yields the certificate: when the search stops, every unexplored
  grasp lies below an open state, so q(s0) minus the smallest unweighted f on the list is
  an upper bound on the optimum.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from tqdm import tqdm

from ogcp.planner.config.methods import (
    DEFAULT_METHOD,
    DEFAULT_WASTAR_EPS,
    HEURISTICS,
    SEARCH_CONFIGS,
    SearchConfig,
    WAStarConfig,
)
from ogcp.planner.config.options import JOBS, MEMORY_LIMIT, TIME_LIMIT, options_of
from ogcp.planner.grasp.constraints import Constraint, DistinctContacts
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.infra.provenance import provenance
from ogcp.planner.search.best_first import Search
from ogcp.planner.search.memory import states_budget
from ogcp.planner.search.parts import search_in_parts
from ogcp.planner.search.result import SearchResult

METHODS = tuple(sorted(SEARCH_CONFIGS))
__all__ = ["DEFAULT_WASTAR_EPS", "HEURISTICS", "METHODS", "GraspPlanner"]


class GraspPlanner:
    """Optimal and bounded-suboptimal m-contact grasp planner.

    The constructor only stores parameters; :meth:`plan` validates them and searches.

    Args:
        method: ``astar`` (optimal), ``wastar`` (cost within 1 + eps of optimal) or
            ``dijkstra`` (uniform cost, h = 0).
        eps: WA* inflation; default :data:`~ogcp.planner.config.methods.DEFAULT_WASTAR_EPS` for
            ``wastar`` and 0 otherwise.
        branching: Branching factor b of the expansion successor function.
        successor: Expansion successor function Γ: ``fc`` (k-means) or ``ru`` (random).
        heuristic: Γh for the heuristic: ``fc``, ``ru`` or ``none``; default ``fc``
            (``none`` for Dijkstra).
        heuristic_branching: b of Γh; default ``branching``.
        symmetry: Approximate geometric symmetry removal (Sec. IV-D); may lose optimality.
        ordered: Keep finger order (the paper's raw tree) instead of sorted states.
        seed: Seed of every random choice (k-means init, random splits).
        kmeans_iterations: t for Γ^fc.
        position_weight: Weight of positions against normals in Γ^fc features.
        constraints: Extra grasp constraints; distinct contacts is always enforced.
        record_tree: Keep the search tree (every created state's parent, level, f and
            whether it was expanded, and the solution path) in ``SearchResult.tree``,
            e.g. for the paper's circular plot (Fig. 5).
        time_limit: Wall-clock budget of :meth:`plan` [s]; past it the search returns the
            best grasp found with status ``stopped`` and the certified upper bound on the
            optimum (``bound``, ``gap``). None: unlimited.
        jobs: Processes for one search (:mod:`ogcp.planner.search.parts`): the grasps are dealt to
            ``jobs`` parts searched side by side. A* returns an optimal grasp either way.
        memory_limit: Most memory of the search, all its processes together [GiB]. Past it a
            search forgets its least promising open states, and once it would have to expand
            one no better than a forgotten state it returns its best grasp with status
            ``memory`` and the certified bound (:mod:`ogcp.planner.search.memory`). None: unlimited.
    """

    def __init__(
        self,
        method: str = DEFAULT_METHOD,
        eps: float | None = None,
        branching: int = SearchConfig.branching,
        successor: str = SearchConfig.successor,
        heuristic: str | None = None,
        heuristic_branching: int | None = None,
        symmetry: bool = SearchConfig.symmetry,
        ordered: bool = SearchConfig.ordered,
        seed: int = SearchConfig.seed,
        kmeans_iterations: int = SearchConfig.kmeans_iterations,
        position_weight: float = SearchConfig.position_weight,
        constraints: Sequence[Constraint] = (),
        record_tree: bool = SearchConfig.record_tree,
        time_limit: float | None = None,
        jobs: int = 1,
        memory_limit: float | None = MEMORY_LIMIT.default,
    ) -> None:
        self.method = method
        self.eps = eps
        self.branching = branching
        self.successor = successor
        self.heuristic = heuristic
        self.heuristic_branching = heuristic_branching
        self.symmetry = symmetry
        self.ordered = ordered
        self.seed = seed
        self.kmeans_iterations = kmeans_iterations
        self.position_weight = position_weight
        self.constraints = constraints
        self.record_tree = record_tree
        self.time_limit = time_limit
        self.jobs = jobs
        self.memory_limit = memory_limit

    def resolved_config(self) -> dict[str, Any]:
        """Validate the parameters (by the method's configuration class) and fill in its defaults.

        Raises:
            OgcpError: For any invalid parameter, naming the valid values.
        """
        if self.method not in METHODS:
            raise choice_error("method", self.method, METHODS)
        # The constructor's arguments are named as the configuration's fields.
        values: dict[str, Any] = {name: getattr(self, name) for name in options_of(SearchConfig)}
        if values["heuristic"] is None:
            del values["heuristic"]  # the method's own default
        eps = 0.0
        if self.method == WAStarConfig.method:
            if self.eps is not None:
                values["eps"] = self.eps
        elif self.eps is not None:
            eps = options_of(WAStarConfig)["eps"].check("eps", self.eps)
            if eps != 0:  # eps = 0 is every search's inflation, so it is accepted everywhere
                raise OgcpError(f"eps applies to method 'wastar' only (method {self.method!r} got eps={eps:g})")
        config = SEARCH_CONFIGS[self.method](**values)
        return {
            "method": self.method,
            "eps": float(getattr(config, "eps", eps)),
            "branching": config.branching,
            "successor": config.successor,
            "heuristic": config.heuristic,
            "heuristic_branching": config.heuristic_branching,
            "symmetry": config.symmetry,
            "ordered": config.ordered,
            "seed": config.seed,
            "kmeans_iterations": config.kmeans_iterations,
            "position_weight": config.position_weight,
            "constraints": [c.describe() for c in self.constraints],
        }

    def plan(
        self,
        contacts: ContactSet,
        m: int,
        progress: bool = False,
        stop: threading.Event | None = None,
        lines: Callable[[str], None] | None = None,
    ) -> SearchResult:
        """Find the best m-contact grasp (or one within the WA* bound).

        Args:
            contacts: The contact set C.
            m: Number of contacts (fingers), 2 <= m <= |C|.
            progress: Show expansions, the best Q1 so far, the certified bound and the gap
                on stderr (tqdm).
            stop: An event that stops the search when set (from another thread or a signal
                handler); the result then has status ``interrupted``.
            lines: Where a progress line goes at most every :data:`PROGRESS_LINE_SECONDS`
                (a log, off a terminal): expansions, best Q1, bound, gap and time; None: none.

        Returns:
            The :class:`SearchResult`; its ``status`` says what it certifies (``optimal``,
            ``bounded``, ``approximate``, ``stopped`` or ``interrupted``).

        Raises:
            OgcpError: For invalid parameters, or when no grasp satisfies the constraints.
            SearchTimeout: When the search stops (time limit or ``stop``) before any valid
                grasp was found (a subclass of OgcpError).
        """
        provenance()  # recorded now: the commit and versions of the code that runs
        config = self.resolved_config()
        if not isinstance(m, (int, np.integer)) or m < 2:
            raise OgcpError(f"number of contacts m must be an integer >= 2, got {m!r}")
        if m > len(contacts):
            raise OgcpError(f"m = {m} exceeds the number of contacts |C| = {len(contacts)}")
        config["m"] = int(m)
        limit = self.time_limit
        if limit is not None and not (isinstance(limit, (int, float)) and math.isfinite(limit) and limit > 0):
            raise OgcpError(f"time_limit must be a number of seconds > 0 or None, got {limit!r}")
        if limit is not None:
            TIME_LIMIT.check("time_limit", limit)
        jobs = JOBS.check("jobs", self.jobs)
        memory = None if self.memory_limit is None else MEMORY_LIMIT.check("memory_limit", self.memory_limit)
        budget = states_budget(memory, jobs)
        if jobs > 1 and self.record_tree:
            raise OgcpError("record_tree needs jobs = 1: each part of a search keeps a tree of its own")
        with tqdm(desc=config["method"], unit=" expansions", disable=not progress, leave=False) as bar:
            meter = _Progress(config["method"], bar, lines)
            if jobs > 1:
                return search_in_parts(
                    contacts,
                    int(m),
                    config,
                    [DistinctContacts(), *self.constraints],
                    jobs,
                    None if limit is None else float(limit),
                    stop,
                    on_expand=meter.expanded,
                    on_progress=meter.progressed,
                    memory_limit=budget,
                )
            search = Search(
                contacts,
                int(m),
                config,
                [DistinctContacts(), *self.constraints],
                self.record_tree,
                None if limit is None else float(limit),
                stop,
                memory_limit=budget,
            )
            search.on_expand, search.on_progress = meter.expanded, meter.progressed
            return search.run()


#: [s] Least time between two progress lines of a search run off a terminal.
PROGRESS_LINE_SECONDS = 30.0


class _Progress:
    """A search's progress: the bar on a terminal, and off one a line at most every
    :data:`PROGRESS_LINE_SECONDS` (the first after as long) to ``say``."""

    def __init__(self, method: str, bar: tqdm, say: Callable[[str], None] | None) -> None:
        self.method, self.bar, self.say = method, bar, say
        self.start = self.last = time.perf_counter()
        self.expansions = 0

    def expanded(self, f: float) -> None:
        self.expansions += 1
        self.bar.update()

    def progressed(self, best: float | None, bound: float) -> None:
        self.bar.set_postfix_str(progress_text(best, bound))
        now = time.perf_counter()
        if self.say is None or now - self.last < PROGRESS_LINE_SECONDS:
            return
        self.last = now
        elapsed = now - self.start
        self.say(f"{self.method}: {self.expansions} expansions, {progress_text(best, bound)}, {elapsed:.0f} s elapsed")


def progress_text(best: float | None, bound: float) -> str:
    """``best``, ``bound`` and relative ``gap`` of a running search, for a progress line."""
    if best is None:
        return f"best -, bound {bound:.6f}"
    gap = (bound - best) / bound if bound > 0 else 0.0
    return f"best {best:.6f}, bound {bound:.6f}, gap {100 * gap:.2f} %"
