"""Expanding a state: its successors enter the open list (a base of :class:`ogcp.planner.search.best_first.Search`).

Most expansions follow the branch and bound that settled the state, whose record holds every
successor with an upper bound of its Q1 (:meth:`ogcp.planner.search.refine.ChildRefinement.settled_successors`):
those successors enter in one pass over arrays and one compiled insertion
(:meth:`Expansion.create_settled`), at m >= 5 some thirty an expansion, where a Python loop
took a few microseconds each. The others are listed and enter one by one
(:meth:`Expansion.create_listed`), in the same order and with the same entries.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.infra.arrays import grow_rows
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.outcome import Incumbent, SearchOutcome
from ogcp.planner.search.refine import BOUND, EXACT_G, Settled
from ogcp.planner.search.search_space import State


@cached_njit()
def settled_entries(
    bounds: np.ndarray,
    levels: np.ndarray,
    terminal: np.ndarray,
    depths: np.ndarray,
    keep: np.ndarray,
    q0: float,
    inherited: float,
    cutoff: float,
    eps: float,
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The open-list entries of a settled record's successors (:meth:`Expansion.create_listed`'s
    arithmetic, child by child).

    Args:
        bounds: Upper bounds of the children's Q1 [-], shape (k,).
        levels: Their levels (0: support bound), shape (k,).
        terminal: Whether each is a grasp, shape (k,).
        depths: Their depths, shape (k,).
        keep: Which are this search's (its part's), shape (k,).
        q0: Q1 of all contacts [-].
        inherited: The lower bound of f every child inherits [-].
        cutoff: Children whose lower bound of f exceeds it are dropped [-].
        eps: WA*'s eps.

    Returns:
        (alive, dropped, keys, -depths, lowers, stages, gs): which children enter, shape (k,);
        how many kept ones were dropped; then, for those that enter, shape (e,) each, their
        keys, negated depths, lower bounds of f [-], stages and g [-] (NaN at ``BOUND``).
    """
    k = bounds.shape[0]
    alive = np.zeros(k, dtype=np.bool_)
    keys, lowers, gs = np.empty(k), np.empty(k), np.empty(k)
    neg_depths, stages = np.empty(k, dtype=np.int64), np.empty(k, dtype=np.int64)
    entered = dropped = 0
    for i in range(k):
        if not keep[i]:
            continue
        # U may be negative (then q = 0): clip so the bound never exceeds the true f.
        clipped = min(q0, max(0.0, bounds[i]))
        lower = max(q0 - clipped, inherited)
        if lower > cutoff:
            dropped += 1
            continue
        alive[i] = True
        keys[entered] = (1.0 + eps) * lower
        lowers[entered] = lower
        neg_depths[entered] = -depths[i]
        # A facet bound or the exact value: the g its first pop would compute (grasps, whose
        # levels WA* may start higher, are scored there as ever).
        if levels[i] > 0 and not terminal[i]:
            stages[entered], gs[entered] = EXACT_G, q0 - clipped
        else:
            stages[entered], gs[entered] = BOUND, np.nan
        entered += 1
    e = entered
    return alive, dropped, keys[:e], neg_depths[:e], lowers[:e], stages[:e], gs[:e]


class Expansion(SearchOutcome):
    """Expansions of a search run (a base of :class:`ogcp.planner.search.best_first.Search`, which
    holds the open list, the counters and the rows of states used here)."""

    incumbent: Incumbent | None
    on_expand: Callable[[float], object]
    _states: NDArray[np.int32]

    def record_expansion(self, f: float) -> None:
        """Add an expansion's f [-] to the trace."""
        if self.expansions == len(self.trace):
            grow_rows(self.trace, self.expansions + 1)
        self.trace[self.expansions] = f
        self.expansions += 1

    def remember(self, ident: int, state: State) -> None:
        """Store a created state under its id."""
        if ident >= len(self._states):
            grow_rows(self._states, ident + 1)
        self._states[ident] = state

    def expand(
        self, open_list: OpenList, state: State, depth: int, key: float, lower: float, g: float, ident: int
    ) -> None:
        """Count the expansion and create the successors."""
        self.visited[depth] = self.visited.get(depth, 0) + 1
        self.record_expansion(key)
        self.on_expand(key)
        if self.record_tree:
            self._visited[ident] = True
        if self.is_terminal(state):
            return
        # Every child's f is at least the parent's g (Q1 is monotone), and at least its
        # f when the heuristic uses the expansion tree (consistency, Thm. III.2b).
        inherited = lower if self.heuristic_shares_tree else g
        settled = self.settled_successors(ident, state)
        if settled is not None and not self.record_tree:
            rows, idents = self.create_settled(open_list, inherited, settled)
            created = None
        else:
            created = self.create_listed(open_list, state, ident, inherited, settled)
        inc = self.incumbent
        if inc is not None and inc.parent == state:
            # The incumbent is a created state now (first ordering of its contacts); its lower
            # bound is at most its cost, below the cutoff, so it was not dropped (-1 if it were).
            if created is None:
                created = list(zip(map(tuple, rows.tolist()), idents.tolist(), strict=True))
            child_id = next((i for c, i in created if tuple(sorted(c)) == inc.state), -1)
            self.incumbent = Incumbent(inc.q, inc.state, None, child_id)

    def create_settled(
        self, open_list: OpenList, inherited: float, settled: Settled
    ) -> tuple[NDArray[np.int32], NDArray[np.int64]]:
        """Enter the successors of a settled record: :meth:`create_listed`'s entries, in one pass.

        Args:
            open_list: The open states.
            inherited: The lower bound of f every child inherits [-].
            settled: The record's successors.

        Returns:
            The nodes of the successors entered, shape (k, m), and their ids, shape (k,).
        """
        keys, terminal, depths, bounds, levels = settled
        part = self.part
        keep = np.ones(len(keys), dtype=np.bool_)
        if part is not None:
            for r in np.flatnonzero(depths == part.depth).tolist():
                keep[r] = part.owns(self.first_contacts(tuple(keys[r].tolist())))
        for level in depths[keep].tolist():
            self.created[level] = self.created.get(level, 0) + 1
        alive, dropped, entry_keys, neg_depths, lowers, stages, gs = settled_entries(
            bounds, levels, terminal, depths, keep, self.q0, inherited, self.cutoff, self.eps
        )
        self.dropped += dropped
        idents = self._ids.take_many(len(lowers))
        rows = keys[alive]
        if len(idents):
            top = int(idents.max())
            if top >= len(self._states):
                grow_rows(self._states, top + 1)
            self._states[idents] = rows
        open_list.push_many(entry_keys, neg_depths, lowers, stages, gs, idents)
        return rows, idents

    def create_listed(
        self, open_list: OpenList, state: State, ident: int, inherited: float, settled: Settled | None
    ) -> list[tuple[State, int]]:
        """Enter the successors one by one, listed (or from a settled record where the tree is
        recorded); returns each one entered with its id."""
        q0, part = self.q0, self.part
        if settled is None:
            children, uppers = self.successors_with_bounds(state)
            levels = None
        else:
            keys, _, _, bounds, known_levels = settled
            children = [tuple(key) for key in keys.tolist()]
            uppers, levels = bounds.tolist(), known_levels.tolist()
        created = []
        for k, (child, upper) in enumerate(zip(children, uppers, strict=True)):
            child_depth = self.depth(child)
            if part is not None and child_depth == part.depth and not part.owns(self.first_contacts(child)):
                continue
            self.created[child_depth] = self.created.get(child_depth, 0) + 1
            child_lower = max(q0 - min(q0, max(0.0, upper)), inherited)
            if child_lower > self.cutoff and not self.record_tree:
                self.dropped += 1  # as push would, without taking an id and a row
                continue
            child_id = self._ids.take()
            created.append((child, child_id))
            self.remember(child_id, child)
            if self.record_tree:
                self._parent.append(ident)
                self._level.append(child_depth)
                self._visited.append(False)
                self._f.append(0.0)
            if levels is not None and levels[k] > 0 and not self.is_terminal(child):
                g_child = q0 - min(q0, max(0.0, upper))
                self.push(open_list, child_lower, child_depth, EXACT_G, g_child, child_id)
            else:
                self.push(open_list, child_lower, child_depth, BOUND, math.nan, child_id)
        return created
