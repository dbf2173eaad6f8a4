"""One best-first search run: the open list, lazily exact values, statistics (see :mod:`ogcp.planner.search.grasp_planner`).

Open-list entries pass through stages, each keyed by a lower bound of the state's f that
only rises: ``BOUND`` (from the support bound U), ``EXACT_G`` (g, exact for terminal
states, else from a facet bound: see :meth:`~ogcp.planner.search.search_space.SearchSpace.g_quality`),
``PARTIAL`` (branch and bound over the heuristic children under way) and ``EXACT`` (f as
final as it gets: exact, or, once the support bound's directions are all learned, from the best
child's facet bounds; see :mod:`ogcp.planner.search.refine`). A state is expanded only from ``EXACT``. With WA* (eps > 0) a state's exact key is the
paper's ``g + (1 + eps) h`` (with that g, which can only raise it); the key of a state not
yet scored is ``(1 + eps)`` times its lower bound of f. Both are at most ``(1 + eps) f``,
which is all the WA* guarantee needs
(the open state on an optimal path keeps a key <= (1 + eps) C*), and the inflated lower
bounds spare WA* the exact evaluation of every state with g below the returned cost,
which unweighted lower bounds would demand.

The incumbent is the best grasp whose exact Q1 the search has computed, as a created
terminal state or as a terminal heuristic child. When a goal is popped the incumbent is
returned: the goal itself, or (WA* only; A*'s goal is optimal) a strictly better grasp,
which keeps the guarantee and costs nothing but the expansion of the state whose branch
and bound found it, so that the returned grasp is a state of the tree.

A* and Dijkstra also take grasps from local search (:mod:`ogcp.planner.search.polish`), run for
a share of the time at progress reports: they only lower the cutoff below which states are
dropped, which such a search would never pop, so its expansions and finished result stay the
same. A search stopped by its time limit or by a stop request is a result too: the incumbent
(or, when none was evaluated yet, the first valid grasp of a depth-first dive below the
most promising open states), climbed from once more, with the certificate the open list
gives at that moment.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ogcp.planner.grasp.constraints import Constraint
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import NoGraspError, SearchTimeout
from ogcp.planner.search.deal import Board, Part, PartDone
from ogcp.planner.search.expansion import Expansion
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.outcome import Incumbent
from ogcp.planner.search.polish import Polisher
from ogcp.planner.search.refine import BOUND, EXACT, EXACT_G
from ogcp.planner.search.result import SearchResult
from ogcp.planner.search.search_space import State
from ogcp.planner.search.storage import IdPool, WaitingStore

#: Iterations between two looks at the clock for progress reports (a report costs nothing
#: but a clock reading; the clock is read every iteration for the deadline anyway).
PROGRESS_SECONDS = 0.5
#: [-] A state is dropped once its lower bound of f exceeds the best grasp's cost by this much:
#: its bounds come from other arithmetic than the grasp's exact Q1, and the state that holds the
#: best grasp must never go.
DROP_MARGIN = 1e-9
#: Iterations between two looks at the memory a search's open states take (a look costs a few
#: additions; between two, a search creates at most a few hundred kilobytes of states).
MEMORY_CHECK_ITERATIONS = 256
#: [-] Share of a run's time that local search from its best grasps may take
#: (:mod:`ogcp.planner.search.polish`).
POLISH_SHARE = 0.1
#: [s] Time a search runs before local search starts (a stopped search climbs once anyway):
#: the cutoff pays in memory only for searches of minutes, while a tenth of a short search's time
#: is simply lost (homer, 300 contacts, m = 5: 18.9 s with it from 10 s on, against 17.2 s).
POLISH_AFTER = 30.0
#: [s] Most time local search may take in all: a long search's certificate needs the time more.
POLISH_SECONDS = 30.0
#: [s] Time one child takes to list, bound and keep (compiled listing, measured at m = 20: about
#: 1.7 µs, with margin): a search with a time limit starts no expansion or bound that cannot end in time.
SUCCESSOR_SECONDS = 3e-6
#: [B] Memory one listed child takes per finger (its nodes, twice) on top of ~32 B of its bounds.
SUCCESSOR_BYTES_PER_FINGER = 8
#: [s] Local search a search stopped without any grasp still takes (large m: no expansion fits).
STOP_POLISH_SECONDS = 0.5
#: Chunks of candidates the local search of a search stopped by its memory limit evaluates: a
#: count, not a time, so that the same limit gives the same grasp (7 ms each at m = 4 on 40 contacts).
STOP_POLISH_CHUNKS = 32
#: [s] Longest one call of local search runs: progress reports, the deadline and the other
#: parts wait meanwhile.
POLISH_SLICE = 2.0


class Search(Expansion):
    """One search run: the open list, the incumbent, the statistics and the tree record.

    Args:
        contacts: The contact set C.
        m: Number of fingers.
        config: Resolved configuration (:meth:`ogcp.planner.search.grasp_planner.GraspPlanner.resolved_config`).
        constraints: Grasp constraints, distinct contacts included.
        record_tree: Keep every created state for :attr:`SearchResult.tree`.
        time_limit: Wall-clock budget [s]; None: unlimited.
        stop: Set by another thread (or a signal handler) to stop the search; it then
            returns like at its time limit, with status ``interrupted``.
        part: Search only this part of the grasps (:mod:`ogcp.planner.search.parts`); None: all.
        memory_limit: Most bytes its open states may take (:mod:`ogcp.planner.search.memory`); past
            it the search forgets those of the largest keys, and returns with status
            ``memory`` once it would have to expand a state no better than one it forgot.
            None: unlimited.
    """

    def __init__(
        self,
        contacts: ContactSet,
        m: int,
        config: dict[str, Any],
        constraints: list[Constraint],
        record_tree: bool = False,
        time_limit: float | None = None,
        stop: threading.Event | Board | None = None,
        part: Part | None = None,
        memory_limit: float | None = None,
    ) -> None:
        super().__init__(contacts, m, config, constraints)
        self.part = part
        self.eps = config["eps"]
        self.time_limit = time_limit
        self.stop = stop
        #: Called about every :data:`PROGRESS_SECONDS` with (best Q1 or None, certified bound) [-].
        self.on_progress: Callable[[float | None, float], object] = lambda best, bound: None
        self._pending = WaitingStore()  # by state id: an int key, not a tuple of nodes
        self.memory_limit = memory_limit
        #: The smallest key and lower bound of f of the states forgotten for memory (inf: none
        #: that could hold a grasp better than the best one found).
        self.forgotten_key = self.forgotten_lower = math.inf
        self.forgotten = 0
        # Heuristic children are successors only on the expansion tree and without the
        # symmetry filter; otherwise only created terminal states become incumbents.
        self.children_can_win = self.heuristic_shares_tree and self.symmetry is None
        self.incumbent: Incumbent | None = None
        self.on_expand: Callable[[float], object] = lambda f: None
        self.record_tree = record_tree
        self._parent: list[int] = [-1]
        self._level: list[int] = [0]
        self._visited: list[bool] = [False]
        self._f: list[float] = [0.0]
        self._ids = IdPool(recycle=not record_tree)
        #: The state of each id, one row each: open-list entries hold the id only (at m >= 5
        #: millions are open, and a tuple of node ids took half of each entry's 500 bytes).
        self._states = np.zeros((1024, m), dtype=np.int32)
        self.q0 = math.nan
        self.created: dict[int, int] = {0: 1}
        self.visited: dict[int, int] = {}
        #: f of each expanded state [-], in order: 8 bytes an expansion where (iteration, f)
        #: tuples took 116, a tenth of a gigabyte a million expansions.
        self.trace = np.zeros(1024)
        self.expansions = 0
        #: States whose lower bound of f exceeds this hold no grasp better than the best one found.
        self.cutoff = math.inf
        self.dropped = 0
        self._purged = (math.inf, -math.inf)  # (cutoff, clock) of the last purge
        # Local search's grasps are no states of the tree (which a recorded tree's path needs),
        # may beat a symmetry-reduced optimum, and are sorted (constraints that read the finger
        # order judge the tree's order).
        polish = not (record_tree or config["symmetry"] or config["ordered"])
        rank = 0 if part is None else part.rank
        self.polisher = Polisher(contacts, m, constraints, config["seed"], rank) if polish else None
        self._barren = False  # local search found no valid grasp to climb from
        self._clock = (time.perf_counter(), time.process_time())  # (wall, cpu) at the start of run [s]

    def push(
        self,
        open_list: OpenList,
        lower: float,
        depth: int,
        stage: int,
        g: float,
        ident: int,
        key: float | None = None,
    ) -> None:
        """Enter a state by its id (:meth:`remember` holds the state); the key defaults to (1 + eps)
        times its lower bound of f. A state past :attr:`cutoff` is dropped instead, with any
        branch and bound it had under way: at m >= 5 most states end up there, and the
        certificate needs none of them (every grasp below them is no better than the best one)."""
        if lower > self.cutoff:
            self._pending.take(ident)
            self._ids.give(ident)
            self.dropped += 1
            return
        if self.record_tree:
            self._f[ident] = lower
        key = (1.0 + self.eps) * lower if key is None else key
        open_list.push(key, -depth, lower, stage, g, ident)

    def state_of(self, ident: int) -> State:
        """The state stored under an id."""
        return tuple(self._states[ident].tolist())

    def offer(self, q: float, state: State, parent: State | None, ident: int) -> None:
        """A terminal state's exact Q1: keep it if it beats the incumbent (ties: the first)."""
        if self.incumbent is None or q > self.incumbent.q:
            self.take(Incumbent(q, state, parent, ident))
            self._barren = False  # local search may climb from it

    def take(self, incumbent: Incumbent) -> None:
        """Make a better grasp the incumbent: drop what it beats, tell the other parts."""
        self.incumbent = incumbent
        self.lower_cutoff(self.q0 - incumbent.q + DROP_MARGIN)
        if self.part is not None:
            self.part.publish(incumbent.q)

    def polish(self, now: float, stopping: bool = False, chunks: int | None = None) -> None:
        """Local search from the search's grasps and from random ones (:mod:`ogcp.planner.search.polish`),
        after :data:`POLISH_AFTER` (at once when ``stopping``), within :data:`POLISH_SHARE` of the
        time so far and :data:`POLISH_SECONDS` in all; a better grasp becomes the incumbent.
        ``chunks``: a count of candidate chunks instead of the clock (a stop that no clock forced)."""
        polisher, inc = self.polisher, self.incumbent
        elapsed = now - self._clock[0]
        if polisher is None or self._barren or (elapsed < POLISH_AFTER and not stopping):
            return
        deadline = math.inf
        if chunks is None:
            budget = min(POLISH_SECONDS, POLISH_SHARE * elapsed)
            if stopping and self.incumbent is None:
                budget = max(budget, polisher.seconds + STOP_POLISH_SECONDS)  # a grasp is owed, if any is found
            allowance = min(POLISH_SLICE, budget - polisher.seconds)
            if allowance <= 0:
                return
            deadline = now + allowance
        start = None if inc is None or inc.state is None else (self.grasp_of(inc), inc.q)
        grasp, q, self._barren = polisher.climb(start, deadline, chunks)
        if grasp and (inc is None or q > inc.q):
            self.take(Incumbent(q, None, None, -1, grasp))

    def run(self) -> SearchResult:
        wall0, cpu0 = time.perf_counter(), time.process_time()
        root: State = (0,) * self.m
        q0 = self.q0 = self.exact(root)
        open_list = OpenList()
        self.remember(0, root)
        self.push(open_list, 0.0, 0, EXACT_G, 0.0, 0)
        deadline = math.inf if self.time_limit is None else wall0 + self.time_limit
        next_report = wall0 + PROGRESS_SECONDS
        stop, part = self.stop, self.part
        self._clock = (wall0, cpu0)
        for iteration in itertools.count():
            if not open_list:
                break
            now = time.perf_counter()  # one reading per iteration (tests drive a fake clock)
            if now > deadline or (stop is not None and stop.is_set()):
                return self.stopped(open_list)
            if now >= next_report:
                next_report = now + PROGRESS_SECONDS
                if self.eps == 0:  # WA* may pop a state A* never would: its cutoff must not move with the clock
                    self.polish(now)
                self.report_progress(open_list)
                self.purge(open_list, now)
            if iteration % MEMORY_CHECK_ITERATIONS == 0:  # by count, not clock: the same states go every run
                self.forget(open_list, -1 if self.incumbent is None else self.incumbent.ident)
            if part is not None and part.beaten(q0 - self.frontier(open_list) / (1.0 + self.eps)):
                # Nothing left in this part beats a grasp some part has found.
                if self.incumbent is None:
                    raise PartDone(self.q0 - self.lowest_lower(open_list))
                return self.finish(open_list)
            if open_list.first_key() > self.forgotten_key:
                # A forgotten state comes first: the search cannot go on exactly.
                return self.stopped(open_list, "memory")
            entry = open_list.pop()
            key, neg_depth, _, lower, stage, g, ident = entry
            state = self.state_of(ident)
            depth = -neg_depth
            if stage == BOUND:
                q = self.g_quality(state)
                # A facet bound may exceed q0; g >= 0 keeps WA*'s keys at most (1 + eps) f.
                g = q0 - min(q0, q)
                if self.is_terminal(state):
                    self.offer(q, state, None, ident)
                if self.is_terminal(state) or self.heuristic_kind == "none":
                    self.push(open_list, max(lower, g), depth, EXACT, g, ident, key=g)
                else:
                    self.push(open_list, max(lower, g), depth, EXACT_G, g, ident)
                continue
            listed = self.successor_count(state)
            if listed * SUCCESSOR_SECONDS > deadline - now:
                # Listing this state's children (up to b^m of them) would outlast the limit.
                open_list.restore(entry)
                return self.stopped(open_list)
            if (
                self.memory_limit is not None
                and listed * (SUCCESSOR_BYTES_PER_FINGER * self.m + 32) > self.memory_limit
            ):
                open_list.restore(entry)  # ... or take more memory than the search may
                return self.stopped(open_list, "memory")
            if stage != EXACT:
                self.refine(open_list, state, depth, lower, g, ident)
                continue
            if self.is_terminal(state):
                # The goal test of A* / WA*: return this grasp unless one strictly better
                # has been evaluated (never for A*: this one is optimal).
                q = self.exact(state)
                if self.incumbent is None or not self.incumbent.q > q:
                    self.incumbent = Incumbent(q, state, None, ident)
                open_list.restore(entry)  # still open unless returned: the certificate counts it
                return self.finish(open_list)
            self.expand(open_list, state, depth, key, lower, g, ident)
            self._ids.give(ident)  # expanded: nothing refers to the state any more
        if self.forgotten_key < math.inf:
            return self.stopped(open_list, "memory")  # forgotten states may hold every grasp left
        if part is not None:
            raise PartDone(0.0)  # no valid grasp in this part
        raise NoGraspError("no grasp satisfies the constraints")

    def report_progress(self, open_list: OpenList) -> None:
        """Call :attr:`on_progress` with the best Q1 and the certified bound (of all parts) [-]."""
        bound = self.quick_bound(open_list)
        if self.part is None:
            self.on_progress(None if self.incumbent is None else self.incumbent.q, bound)
            return
        self.part.report(bound)
        best, overall = self.part.overall()
        if best is not None:  # another part's grasp may drop states here too
            self.lower_cutoff(self.q0 - best + DROP_MARGIN)
        self.on_progress(best, min(self.q0, overall))  # inf until every part has reported

    def quick_bound(self, open_list: OpenList) -> float:
        """A certified upper bound on the optimum in O(1), looser than the final one for WA*.

        Every open key is at most (1 + eps) times its state's lower bound of f, so the
        smallest key over 1 + eps bounds the smallest f from below.
        """
        best = 0.0 if self.incumbent is None else self.incumbent.q
        frontier = self.frontier(open_list)
        if frontier == math.inf:
            return best
        return min(self.q0, max(best, self.q0 - frontier / (1.0 + self.eps)))

    def stopped(self, open_list: OpenList, status: str | None = None) -> SearchResult:
        """The result of a search stopped before its goal test: the best grasp and its certificate.

        Args:
            open_list: The open states.
            status: Why it stopped; None: its time limit or its stop request.

        Raises:
            SearchTimeout: When no valid grasp could be found in time (none was evaluated
                and the dive found none).
        """
        if status is None:
            status = "interrupted" if self.stop is not None and self.stop.is_set() else "stopped"
        if self.incumbent is None:
            self.dive(open_list)
        if status == "memory":  # no clock stopped it: the same climb on any machine, so the same grasp
            self.polish(time.perf_counter(), stopping=True, chunks=STOP_POLISH_CHUNKS)
        elif status != "interrupted":  # the user is waiting
            self.polish(time.perf_counter(), stopping=True)
        inc = self.incumbent
        if inc is None:
            # Every unexplored grasp lies below an open or forgotten state, so q0 - min bounds the optimum.
            upper = self.q0 - self.lowest_lower(open_list)
            seconds = None if status != "stopped" or self.time_limit is None else float(self.time_limit)
            visited = sum(self.visited.values())
            raise SearchTimeout(self.config["method"], seconds, visited, None, upper, status == "memory")
        result = self.result(inc, self.q0 - inc.q, open_list)
        # The incumbent may already beat every open bound: then it is proven optimal.
        if result.bound <= result.q1:
            return result  # the incumbent already beats every open bound: proven, as if finished
        return dataclasses.replace(result, status=status)

    def finish(self, open_list: OpenList) -> SearchResult:
        """Return the incumbent, expanding the state that found it if it is not created yet."""
        inc = self.incumbent
        assert inc is not None
        if inc.state is None:  # local search's grasp: no state to count as the goal
            return self.result(inc, self.q0 - inc.q, open_list)
        if inc.parent is not None and open_list.holds(inc.ident):
            # The parent is still on the open list (not expanded; dropped only for a better
            # grasp of another part, and then this part's grasp is not the result).
            key, neg_depth, _, lower, _, g, ident = open_list.first_of(inc.ident)
            state = self.state_of(ident)
            self.expand(open_list, state, -neg_depth, key, lower, g, ident)
            # Expanding the parent created the grasp's state and re-offered it.
            inc = self.incumbent
            assert inc is not None
        goal_depth = self.incumbent_depth(inc)
        g = self.q0 - inc.q
        self.visited[goal_depth] = self.visited.get(goal_depth, 0) + 1
        self.record_expansion(g)
        self.on_expand(g)
        if self.record_tree:
            self._visited[inc.ident] = True
            self._f[inc.ident] = g
        return self.result(inc, g, open_list)
