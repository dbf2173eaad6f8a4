"""A state's f from its heuristic children: branch and bound over upper bounds of their Q1.

The half of :class:`planner.search.best_first.Search` that turns a state's Γh children into its
f (:meth:`ChildRefinement.refine`), and the open-list stages both halves share. A
child's bound climbs the ladder of :meth:`planner.grasp.subset_quality.GraspQuality.tighten`;
where the children are listed by the compiled listing, the loop itself is compiled too
(:mod:`planner.search.refine_kernel`) and returns to Python only for exact values.
"""

from __future__ import annotations

from typing import TypeGuard

import numpy as np
from numpy.typing import NDArray

from planner.grasp.subset_quality import EXACT as EXACT_Q1
from planner.infra.tolerance import TOL
from planner.search.deal import Part
from planner.search.open_list import OpenList
from planner.search.refine_kernel import NEEDS_EXACT, NEEDS_ROWS, SETTLED, YIELD
from planner.search.search_space import SearchSpace, State

#: Open-list stages (see :mod:`planner.search.best_first`).
BOUND, EXACT_G, PARTIAL, EXACT = 0, 1, 2, 3
#: Heuristic children waiting in a state's branch and bound: their keys
#: (:data:`~planner.search.search_space.ChildKey`), one row each, shape (children, m). Masks
#: and vectors are looked up again when one is tightened: at m >= 5 millions wait, most
#: never touched, and 4 bytes per node keep them small.
Children = NDArray[np.int32]
#: A state's branch and bound under way: its children, their upper bounds of Q1 [-], the
#: level of each bound and the direction of D of each support bound (-1: not known; arrays
#: of shape (children,): 13 bytes a child, where a heap of tuples took 90, and the largest
#: is found by argmax).
Pending = tuple[Children, NDArray[np.float64], NDArray[np.int8], NDArray[np.int32]]


class ChildRefinement(SearchSpace):
    """The branch and bound over a state's Γh children that gives its f (a base of
    :class:`planner.search.best_first.Search`, which provides the open list and the incumbent).

    Attributes:
        q0: Q1 of all contacts [-].
        eps: WA*'s eps (0 for A*).
        children_can_win: Whether a grasp child may become the incumbent.
    """

    q0: float
    eps: float
    children_can_win: bool
    part: Part | None
    _pending: dict[int, Pending]

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
        """Enter a state in the open list (:meth:`planner.search.best_first.Search.push`)."""
        raise NotImplementedError

    def offer(self, q: float, state: State, parent: State | None, ident: int) -> None:
        """Offer a grasp's exact Q1 as the incumbent (:meth:`planner.search.best_first.Search.offer`)."""
        raise NotImplementedError

    def refine(self, open_list: OpenList, state: State, depth: int, lower: float, g: float, ident: int) -> None:
        """Branch and bound over the heuristic children, on ever tighter upper bounds of their Q1.

        The children wait with upper bounds, each at a level of
        :meth:`planner.grasp.subset_quality.GraspQuality.tighten`: the support bound, then
        facet bounds, then the exact value. The child of the largest bound is tightened by
        one level until the largest is an exact value: that is the best child, and
        f = q0 - its Q1. Meanwhile f >= q0 - (the largest bound) is a valid lower bound, and the state returns
        to the open list with it as soon as it would no longer be the first there, so a
        state whose f turns out above the final frontier stops costing evaluations as
        soon as its bound says so. Most children settle on a facet bound below the best
        value, at a tenth of the cost of an exact one. Once the support bound holds all its
        directions, the loop also stops at a largest bound that has only its exact value left
        to climb (:meth:`settles_on_bounds`): f is then q0 - that facet bound, a lower bound.
        WA*'s terminal children skip the facet bounds: an exact value makes each one it
        reaches a candidate for the grasp it returns. A state with no valid child below it
        is dropped. Where the children come from the compiled listing, the loop runs compiled
        (:meth:`compiled_refine`), step for step the same.
        """
        q0 = self.q0
        if self.is_terminal(state) or self.heuristic_kind == "none":
            self.push(open_list, max(lower, g), depth, EXACT, g, ident, key=g)
            return
        pending = self._pending.pop(ident, None)
        if pending is None:
            children, bounds, starts, terminal = self.heuristic_bounds(state)
            if not len(bounds):
                return  # no valid grasp below this state
            levels = np.zeros(len(bounds), dtype=np.int8)
            if self.eps > 0 and self.children_can_win:
                # WA* returns the best grasp it has evaluated: its terminal children skip the facet
                # bounds (the next tightening of a bound one level below exact is the exact value),
                # so every one the branch and bound reaches becomes a candidate.
                levels[terminal] = EXACT_Q1 - 1
        else:
            children, bounds, levels, starts = pending
        if self.child_bounds is not None:
            self.compiled_refine(open_list, state, depth, lower, g, ident, (children, bounds, levels, starts))
            return
        while True:
            i = int(bounds.argmax())  # the first of equal bounds: the lowest index
            bound, level = float(bounds[i]), int(levels[i])
            # Children's q lie in [0, q0]: clip the bound like the successor bounds.
            lower = max(lower, q0 - min(q0, max(0.0, bound)))
            if level == EXACT_Q1:
                break
            if (1.0 + self.eps) * lower > open_list.first_key():
                self._pending[ident] = (children, bounds, levels, starts)
                self.push(open_list, lower, depth, PARTIAL, g, ident)
                return
            child_key = tuple(children[i].tolist())
            child = self.child_state(child_key)
            if level == EXACT_Q1 - 1 and self.settles_on_bounds(child):
                break
            # The first facet bound starts from the listing's direction (directions learned
            # since may rank lower, but any direction bounds Q1): vectors serve only the later
            # levels (ranking more starts, the exact value's cheap rejection).
            start = int(starts[i]) if level == 0 and starts[i] >= 0 else None
            needed = start is None or bound <= TOL.force_closure
            vectors = self.child_vectors(child_key) if needed else None
            value, level = self.oracle.tighten(self.child_masks(child_key), vectors, level, bound, start)
            if level == EXACT_Q1:
                if self.wins(child):
                    self.offer(value, child, state, ident)
            else:
                value = min(value, bound)  # both bound Q1
            bounds[i], levels[i] = value, level
        f = max(lower, q0 - bound)  # settled on a facet bound, f may lie below the lower bound held
        # With eps = 0 the key is f itself, not g + (f - g), which can round below f.
        key = f if self.eps == 0 else g + (1.0 + self.eps) * (f - g)
        self.push(open_list, f, depth, EXACT, g, ident, key=key)

    def compiled_refine(
        self, open_list: OpenList, state: State, depth: int, lower: float, g: float, ident: int, pending: Pending
    ) -> None:
        """:meth:`refine`'s loop, compiled between exact values (:meth:`SearchSpace.branch_and_bound`)."""
        children, bounds, levels, _ = pending
        q0 = self.q0
        while True:
            first_key = open_list.first_key()
            outcome, i, lower = self.branch_and_bound(
                state, pending, lower, q0, first_key, self.eps, self.children_can_win
            )
            if outcome == SETTLED:
                break
            if outcome == YIELD:
                self._pending[ident] = pending
                self.push(open_list, lower, depth, PARTIAL, g, ident)
                return
            if outcome == NEEDS_ROWS:
                self.node_vectors(tuple(children[i].tolist()))  # directions learned since the listing
                continue
            child_key = tuple(children[i].tolist())
            child = self.child_state(child_key)
            if outcome == NEEDS_EXACT and levels[i] == EXACT_Q1 - 1 and self.settles_on_bounds(child):
                break
            if outcome == NEEDS_EXACT:
                masks, vectors = self.child_masks(child_key), self.child_vectors(child_key)
                value, _ = self.oracle.tighten(masks, vectors, EXACT_Q1 - 1, float(bounds[i]))
                bounds[i], levels[i] = value, EXACT_Q1
                self.store_child_bound(children[i], value)
            if self.wins(child):
                self.offer(float(bounds[i]), child, state, ident)
        f = max(lower, q0 - float(bounds[i]))
        key = f if self.eps == 0 else g + (1.0 + self.eps) * (f - g)
        self.push(open_list, f, depth, EXACT, g, ident, key=key)

    def settles_on_bounds(self, child: State | None) -> bool:
        """Whether the largest bound, a facet bound, may stand for the child's exact Q1 in f.

        Once the directions of D are all learned, exact values stop tightening the support
        bounds, and f = q0 - (the largest facet bound) is a lower bound that costs no hull:
        the state is expanded a little earlier than its exact f would allow, which costs
        less than the exact values (sphere, m = 3: 1.4 times the expansions, 40 % of the
        exact values, a fifth less time). Grasps that may become the incumbent stay exact.
        """
        bounds = self.oracle.bounds
        return bounds.count >= bounds.capacity and not self.wins(child)

    def wins(self, child: State | None) -> TypeGuard[State]:
        """Whether a heuristic child is a grasp that may become the incumbent (one of this
        part's: the incumbent must become a state of this part's tree)."""
        if child is None or not self.children_can_win or not self.is_terminal(child):
            return False
        part = self.part
        return part is None or self.depth(child) != part.depth or part.owns(self.first_contacts(child))
