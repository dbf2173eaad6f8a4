"""A state's f from its heuristic children: branch and bound over upper bounds of their Q1.

The half of :class:`ogcp.planner.search.best_first.Search` that turns a state's Γh children into its
f (:meth:`ChildRefinement.refine`), and the open-list stages both halves share. A
child's bound climbs the ladder of :meth:`ogcp.planner.grasp.subset_quality.GraspQuality.tighten`;
where the children are listed by the compiled listing, the loop itself is compiled too
(:mod:`ogcp.planner.search.refine_kernel`) and returns to Python only for exact values.
"""

from __future__ import annotations

import math
from typing import TypeGuard, cast

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel.geometry import CUT_MARGIN
from ogcp.planner.grasp.subset_quality import EXACT as EXACT_Q1
from ogcp.planner.grasp.subset_quality import MAX_DIRECTIONS
from ogcp.planner.infra.tolerance import TOL
from ogcp.planner.search.children_kernel import decode_children
from ogcp.planner.search.deal import Part
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.refine_kernel import NEEDS_EXACT, NEEDS_ROWS, SETTLED, YIELD, mask_support
from ogcp.planner.search.refine_kernel import branch_and_bound as compiled_branch_and_bound
from ogcp.planner.search.search_space import SearchSpace, State
from ogcp.planner.search.storage import IdPool, WaitingStore

#: Open-list stages (see :mod:`ogcp.planner.search.best_first`).
BOUND, EXACT_G, PARTIAL, EXACT = 0, 1, 2, 3
#: Heuristic children waiting in a state's branch and bound: their keys
#: (:data:`~ogcp.planner.search.search_space.ChildKey`), one row each, shape (children, m). Masks
#: and vectors are looked up again when one is tightened: at m >= 5 millions wait, most
#: never touched, and 4 bytes per node keep them small.
Children = NDArray[np.int32]
#: A state's branch and bound under way: its children, their upper bounds of Q1 [-], the
#: level of each bound and the direction of D of each support bound (-1: not known; arrays
#: of shape (children,): 13 bytes a child, where a heap of tuples took 90, and the largest
#: is found by argmax).
Pending = tuple[Children, NDArray[np.float64], NDArray[np.int8], NDArray[np.int32]]
#: Bytes of one child waiting in a compiled branch and bound (:func:`pack_waiting`): its upper
#: bound (float64), level (int8), support bound's direction (int16) and number in the listing's
#: product order (uint8: the compiled listing runs where b^m <= 256). A third of a row of
#: :data:`Pending` at m = 6, and one buffer per state instead of four arrays: at m = 6 tens of
#: millions wait, and they held half of a search's memory.
CHILD_BYTES = 12
#: What waits of a state's branch and bound: :data:`Pending` rows (the Python loop) or a
#: :func:`pack_waiting` record (the compiled one).
Waiting = Pending | NDArray[np.uint8]
#: A settled record's successors (:meth:`ChildRefinement.settled_successors`): their sorted nodes,
#: shape (k, m); whether each is a grasp; depths; upper bounds of Q1 [-]; the levels of those bounds.
Settled = tuple[NDArray[np.int32], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64], NDArray[np.int8]]
assert MAX_DIRECTIONS < 2**15, "directions of D are numbered in int16"


def pack_waiting(
    codes: NDArray[np.int64], bounds: NDArray[np.float64], levels: NDArray[np.int8], starts: NDArray[np.int32]
) -> NDArray[np.uint8]:
    """One buffer holding a compiled branch and bound's waiting children (see :data:`CHILD_BYTES`)."""
    record = np.empty(CHILD_BYTES * len(bounds), dtype=np.uint8)
    values, levels_out, starts_out, codes_out = unpack_waiting(record)
    values[:], levels_out[:], starts_out[:], codes_out[:] = bounds, levels, starts, codes
    return record


def unpack_waiting(
    record: NDArray[np.uint8],
) -> tuple[NDArray[np.float64], NDArray[np.int8], NDArray[np.int16], NDArray[np.uint8]]:
    """Views of a :func:`pack_waiting` buffer: bounds [-], levels, start directions, numbers."""
    k = len(record) // CHILD_BYTES
    return (
        record[: 8 * k].view(np.float64),
        record[8 * k : 9 * k].view(np.int8),
        record[9 * k : 11 * k].view(np.int16),
        record[11 * k :],
    )


class ChildRefinement(SearchSpace):
    """The branch and bound over a state's Γh children that gives its f (a base of
    :class:`ogcp.planner.search.best_first.Search`, which provides the open list and the incumbent).

    Attributes:
        q0: Q1 of all contacts [-].
        eps: WA*'s eps (0 for A*).
        children_can_win: Whether a grasp child may become the incumbent.
        share_normals: Whether the branch and bound lowers the other children's bounds
            along each new facet bound's normal
            (:func:`ogcp.planner.search.refine_kernel.share_normal`).
        keep_settled: Whether a compiled branch and bound that settles a state about to be
            expanded keeps its children's bounds for the expansion (:meth:`settled_successors`).
    """

    q0: float
    eps: float
    children_can_win: bool
    share_normals: bool = True
    keep_settled: bool = True
    part: Part | None
    forgotten_key: float
    _pending: WaitingStore
    _ids: IdPool

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
        """Enter a state in the open list (:meth:`ogcp.planner.search.best_first.Search.push`)."""
        raise NotImplementedError

    def offer(self, q: float, state: State, parent: State | None, ident: int) -> None:
        """Offer a grasp's exact Q1 as the incumbent (:meth:`ogcp.planner.search.best_first.Search.offer`)."""
        raise NotImplementedError

    def state_of(self, ident: int) -> State:
        """The state stored under an id (:meth:`ogcp.planner.search.best_first.Search.state_of`)."""
        raise NotImplementedError

    def refine(self, open_list: OpenList, state: State, depth: int, lower: float, g: float, ident: int) -> None:
        """Branch and bound over the heuristic children, on ever tighter upper bounds of their Q1.

        The children wait with upper bounds, each at a level of
        :meth:`ogcp.planner.grasp.subset_quality.GraspQuality.tighten`: the support bound, then
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
        (:meth:`compiled_refine`), step for step the same. Each new facet bound's normal also
        lowers the other children's bounds (:meth:`share_normal`, :attr:`share_normals`).
        """
        q0 = self.q0
        if self.is_terminal(state) or self.heuristic_kind == "none":
            self.push(open_list, max(lower, g), depth, EXACT, g, ident, key=g)
            return
        pending = self._pending.take(ident)
        if self.child_bounds is not None:
            assert pending is None or isinstance(pending, np.ndarray)
            self.compiled_refine(open_list, state, depth, lower, g, ident, pending)
            return
        if pending is None:
            children, bounds, starts, terminal = self.heuristic_bounds(state)
            if not len(bounds):
                self._ids.give(ident)
                return  # no valid grasp below this state: the state is dead
            levels = self.start_levels(terminal)
        else:
            assert isinstance(pending, tuple)
            children, bounds, levels, starts = pending
        while True:
            i = int(bounds.argmax())  # the first of equal bounds: the lowest index
            bound, level = float(bounds[i]), int(levels[i])
            # Children's q lie in [0, q0]: clip the bound like the successor bounds.
            lower = max(lower, q0 - min(q0, max(0.0, bound)))
            if level == EXACT_Q1:
                break
            if (1.0 + self.eps) * lower > min(open_list.first_key(), self.forgotten_key):
                self._pending.put(ident, (children, bounds, levels, starts))
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
            normal = self.oracle.last_normal
            if normal is not None and self.share_normals:
                self.share_normal(normal, children, bounds, levels, i)
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
        self,
        open_list: OpenList,
        state: State,
        depth: int,
        lower: float,
        g: float,
        ident: int,
        record: NDArray[np.uint8] | None,
    ) -> None:
        """:meth:`refine`'s loop, compiled between exact values (:meth:`branch_and_bound`),
        on the children's :func:`pack_waiting` record (None: list them first)."""
        if record is None:
            numbers, listed, directions, terminal = self.numbered_children(state)
            if not len(listed):
                self._ids.give(ident)
                return  # no valid grasp below this state: the state is dead
            record = pack_waiting(numbers, listed, self.start_levels(terminal), directions)
        waiting = unpack_waiting(record)
        bounds, levels, _, codes = waiting
        nodes = np.array(state, dtype=np.int64)
        q0 = self.q0
        while True:
            first_key = min(open_list.first_key(), self.forgotten_key)
            outcome, i, lower = self.branch_and_bound(
                nodes, waiting, lower, q0, first_key, self.eps, self.children_can_win
            )
            if outcome == SETTLED:
                break
            if outcome == YIELD:
                self._pending.put(ident, record)
                self.push(open_list, lower, depth, PARTIAL, g, ident)
                return
            child = self.child_of_number(state, int(codes[i]))
            if outcome == NEEDS_ROWS:
                self.node_vectors(child)  # directions learned since the listing
                continue
            if outcome == NEEDS_EXACT and levels[i] == EXACT_Q1 - 1 and self.settles_on_bounds(child):
                break
            if outcome == NEEDS_EXACT:
                masks, vectors = self.child_masks(child), self.child_vectors(child)
                value, _ = self.oracle.tighten(masks, vectors, EXACT_Q1 - 1, float(bounds[i]))
                bounds[i], levels[i] = value, EXACT_Q1
                self.store_child_bound(np.array(child, dtype=np.int32), value)
            if self.wins(child):
                self.offer(float(bounds[i]), child, state, ident)
        f = max(lower, q0 - float(bounds[i]))
        key = f if self.eps == 0 else g + (1.0 + self.eps) * (f - g)
        if self.keep_settled and key <= open_list.first_key():
            # Expanded next: its children enter with these bounds (:meth:`settled_successors`);
            # a state that waits keeps nothing, like a finished branch and bound always did.
            self._pending.put(ident, record)
        self.push(open_list, f, depth, EXACT, g, ident, key=key)

    def settled_successors(self, ident: int, state: State) -> Settled | None:
        """The successors of a state about to be expanded, with what its settled branch and
        bound knows of them (None: it kept no record, see :meth:`compiled_refine`).

        Γh is the expansion tree where the compiled loop runs, so the children it bounded are
        the successors, in the same order: a child whose bound is a facet bound or exact enters
        with its g, sparing the facet bound that its first pop would compute.

        Returns:
            (keys, terminal, depths, bounds, levels): the children's sorted nodes, shape (k, m);
            whether each is a grasp; its depth; its upper bound of Q1 [-] and that bound's level,
            each of shape (k,).
        """
        record = self._pending.take(ident)
        if record is None or self.symmetry is not None or self.config["ordered"]:
            return None  # the successors are filtered or ordered: not the listed children
        assert isinstance(record, np.ndarray)
        bounds, levels, _, numbers = unpack_waiting(record)
        nodes = np.array(state, dtype=np.int64)
        codes = numbers.astype(np.int64)
        keys, terminal, depths, rejected = decode_children(
            nodes, codes, self._table, self._widths, self._sizes, self._depths
        )
        self.pruned += rejected
        return keys, terminal, depths, bounds, levels

    def share_normal(
        self,
        u: NDArray[np.float64],
        children: Children,
        bounds: NDArray[np.float64],
        levels: NDArray[np.int8],
        source: int,
    ) -> None:
        """The Python loop's :func:`ogcp.planner.search.refine_kernel.share_normal`: lower every
        child's bound but ``source``'s and the exact ones to its support along u (shape (6,)),
        plus the facet bounds' margin; the same values, bit for bit."""
        wrenches = self.contacts.wrenches
        supports: dict[int, float] = {}
        for r, row in enumerate(children.tolist()):
            if r == source or levels[r] == EXACT_Q1:
                continue
            h = -math.inf
            for part, mask in zip(row, self.child_masks(tuple(row)), strict=True):
                support = supports.get(part)
                if support is None:
                    support = supports[part] = float(mask_support(u, mask, wrenches))
                h = max(h, support)
            h += CUT_MARGIN
            bounds[r] = min(bounds[r], h)

    def waiting(self, ident: int) -> Pending | None:
        """The children waiting in a state's branch and bound as :data:`Pending` rows (either
        record), or None when none wait."""
        pending = self._pending.get(ident)
        if pending is None or isinstance(pending, tuple):
            return cast(Pending | None, pending)
        bounds, levels, starts, codes = unpack_waiting(pending)
        state = self.state_of(ident)
        rows = np.array([self.child_of_number(state, int(code)) for code in codes.tolist()], dtype=np.int32)
        return rows.reshape(len(codes), self.m), bounds, levels, starts.astype(np.int32)

    def branch_and_bound(
        self,
        state: NDArray[np.int64],
        waiting: tuple[NDArray[np.float64], NDArray[np.int8], NDArray[np.int16], NDArray[np.uint8]],
        lower: float,
        q0: float,
        first_key: float,
        eps: float,
        report_grasps: bool,
    ) -> tuple[int, int, float]:
        """One compiled run of a state's branch and bound (:func:`ogcp.planner.search.refine_kernel.branch_and_bound`).

        Args:
            state: The state's nodes, as listed by :meth:`numbered_children`, shape (m,).
            waiting: Its Γh children's upper bounds [-], levels, start directions and numbers
                (:func:`ogcp.planner.search.refine.unpack_waiting`); bounds and levels updated in place.
            lower: The state's lower bound of f so far [-].
            q0: Q1 of all contacts [-].
            first_key: The open list's first key (inf when empty).
            eps: WA*'s eps.
            report_grasps: Return when a grasp child becomes exact.

        Returns:
            (outcome, child index, lower bound of f [-]).
        """
        table = self.child_bounds
        assert table is not None
        bounds = self.oracle.bounds
        values, levels, starts, codes = waiting
        outcome, index, lower = compiled_branch_and_bound(
            codes,
            values,
            levels,
            starts,
            state,
            self._table,
            self._widths,
            lower,
            q0,
            first_key,
            eps,
            report_grasps,
            self.share_normals,
            self.contacts.wrenches,
            bounds.directions,
            bounds.count,
            self._masks,
            self._node_vectors,
            self._filled,
            self._sizes,
            table.keys,
            table.values,
            table.levels,
            table.counters,
        )
        return int(outcome), int(index), float(lower)

    def store_child_bound(self, key: NDArray[np.int32], value: float) -> None:
        """Remember a Γh child's exact Q1 [-] for the compiled branch and bound."""
        assert self.child_bounds is not None
        self.child_bounds.store(key, value, EXACT_Q1)

    def start_levels(self, terminal: NDArray[np.bool_]) -> NDArray[np.int8]:
        """The level each child's bound starts at, given which children are grasps.

        WA* returns the best grasp it has evaluated: its terminal children skip the facet
        bounds (the next tightening of a bound one level below exact is the exact value), so
        every one the branch and bound reaches becomes a candidate.
        """
        levels = np.zeros(len(terminal), dtype=np.int8)
        if self.eps > 0 and self.children_can_win:
            levels[terminal] = EXACT_Q1 - 1
        return levels

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
