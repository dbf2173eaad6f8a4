"""The search space of one run: super-contact states, their validity, bounds and heuristic children.

See :mod:`ogcp.planner.search.grasp_planner` for the design; :mod:`ogcp.planner.search.best_first` runs the search on it.
"""

from __future__ import annotations

import collections
import itertools
import time
from collections.abc import Hashable, Iterator, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.constraints import Constraint, DistinctContacts
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.subset_quality import GraspQuality, PackedMask
from ogcp.planner.grasp.support_bound import Vector
from ogcp.planner.search.children_kernel import shared_tree_children, stale_children, support_bounds
from ogcp.planner.search.partitions import Indices, PartitionTree, make_partitioner
from ogcp.planner.search.refine_kernel import ChildBounds, state_bound
from ogcp.planner.search.symmetry import SymmetryFilter

State = tuple[int, ...]
#: A heuristic child: its state, or ``node * b_h + part`` per super-contact when Γh has
#: its own partitioner (of branching b_h, so at most b_h parts per node).
ChildKey = tuple[int, ...]


class SearchSpace:
    """States (tuples of partition-tree nodes), successors, exact Q1 and support bounds.

    Args:
        contacts: The contact set C.
        m: Number of fingers.
        config: Resolved configuration (:meth:`ogcp.planner.search.grasp_planner.GraspPlanner.resolved_config`).
        constraints: Grasp constraints, distinct contacts included.
    """

    def __init__(self, contacts: ContactSet, m: int, config: dict[str, Any], constraints: list[Constraint]) -> None:
        self.contacts = contacts
        self.m = m
        self.config = config
        self.constraints = constraints
        self._distinct = any(isinstance(c, DistinctContacts) for c in constraints)
        self._other_constraints = [c for c in constraints if not isinstance(c, DistinctContacts)]
        self.oracle = GraspQuality(contacts, config["seed"])

        def partitioner(kind: str, branching: int) -> Any:
            return make_partitioner(
                kind, contacts, branching, config["seed"], config["kmeans_iterations"], config["position_weight"]
            )

        self.tree = PartitionTree(len(contacts), partitioner(config["successor"], config["branching"]))
        self.heuristic_kind = config["heuristic"]
        self.heuristic_shares_tree = (
            self.heuristic_kind == config["successor"] and config["heuristic_branching"] == config["branching"]
        )
        self.heuristic_partitioner = (
            None
            if self.heuristic_kind == "none" or self.heuristic_shares_tree
            else partitioner(self.heuristic_kind, config["heuristic_branching"])
        )
        self._heuristic_parts: dict[int, list[tuple[Indices, PackedMask]]] = {}
        #: Support vectors of Γh's own parts, by key (tree nodes' live in ``_node_vectors``).
        self._vectors: dict[Any, Vector] = {}
        # Per tree node, grown as the tree grows: support vectors (rows filled up to
        # ``_filled`` directions), sizes, child nodes; the compiled listing of Γh children reads them.
        branching = config["branching"]
        self._node_vectors = np.zeros((0, self.oracle.bounds.capacity))
        self._filled = np.zeros(0, dtype=np.int64)
        self._sizes = np.zeros(0, dtype=np.int64)
        self._depths = np.zeros(0, dtype=np.int64)
        self._table = np.zeros((0, branching), dtype=np.int64)
        self._widths = np.zeros(0, dtype=np.int64)
        self._masks = np.zeros((0, (len(contacts) + 7) // 8), dtype=np.uint8)
        # One call per state lists Γh's children where they are combinations of tree nodes
        # and distinct contacts is the only constraint (other constraints judge in Python).
        self._compiled_children = (
            self.heuristic_shares_tree and self._distinct and not self._other_constraints and branching**m <= 256
        )
        # The branch and bound over those children then runs compiled between exact values.
        self.child_bounds = ChildBounds(m) if self._compiled_children else None
        self.symmetry = SymmetryFilter(contacts) if config["symmetry"] else None
        self.pruned = 0
        self.bound_evaluations = 0

    # -- states -----------------------------------------------------------------------

    def members(self, state: State) -> list[Indices]:
        return [self.tree.members[node] for node in state]

    def depth(self, state: State) -> int:
        return max(self.tree.depth[node] for node in state)

    def first_contacts(self, state: State) -> list[int]:
        """The first (smallest) contact of each node: the same in every process, unlike node ids."""
        return [int(self.tree.members[node].min()) for node in state]

    def is_terminal(self, state: State) -> bool:
        return self.tree.leaves.issuperset(state)

    def valid(self, parts: Sequence[Indices], terminal: bool, keys: Sequence[Hashable] | None = None) -> bool:
        """Whether the state (or, if terminal, the grasp) of these super-contacts passes every constraint.

        Args:
            parts: Contact indices of each super-contact.
            terminal: Every part is one contact.
            keys: One key per part, equal exactly when the parts are the same set, where
                parts with different keys are disjoint: true of the partition-tree nodes of
                one state (a node and a leaf left above its depth never nest) and of the
                parts a partitioner splits them into. Distinct contacts then come down to
                a count (no part used more often than it has contacts) instead of Hall's
                matching.
        """
        constraints = self.constraints
        if keys is not None and self._distinct:
            counts: dict[Hashable, int] = {}
            for key, part in zip(keys, parts, strict=True):
                count = counts[key] = counts.get(key, 0) + 1
                if count > len(part):
                    return False
            constraints = self._other_constraints
        if terminal:
            grasp = [int(p[0]) for p in parts]
            return all(c.accepts(grasp, self.contacts) for c in constraints)
        return all(c.admits(parts, self.contacts) for c in constraints)

    def successors(self, state: State, limit: int | None = None, deadline: float | None = None) -> list[State]:
        """Γ restricted to valid states (Eq. 15), sorted unless finger order is kept.

        Args:
            state: The state to expand.
            limit: Stop after this many valid successors, listing each multiset once (a dive
                needs a few, and Γ lists up to b^m); None: all, in product order.
            deadline: ``time.perf_counter()`` reading after which the listing stops (a dive
                runs after the search's time limit; at large m nearly every combination is
                invalid); None: none.
        """
        seen: set[State] = set()
        result: list[State] = []
        for tried, combo in enumerate(self._combinations(state, distinct=limit is not None)):
            if deadline is not None and tried % 1024 == 1023 and time.perf_counter() > deadline:
                break
            child = combo if self.config["ordered"] else tuple(sorted(combo))
            if child in seen:
                continue
            seen.add(child)
            if not self.valid(self.members(child), self.is_terminal(child), child):
                self.pruned += 1
                continue
            if self.symmetry is not None and not self.symmetry.is_new(self.depth(child), self.members(child)):
                continue
            result.append(child)
            if limit is not None and len(result) >= limit:
                break
        return result

    def _combinations(self, state: State, distinct: bool) -> Iterator[tuple[int, ...]]:
        """Γ's combinations of a state's children, in product order; with ``distinct``, the
        multisets only (a super-contact that appears k times picks k of its children without
        order), which lists a few hundred children of the root instead of its b^m."""
        if not distinct or self.config["ordered"]:
            yield from itertools.product(*(self.tree.children(node) for node in state))
            return
        picks = [
            list(itertools.combinations_with_replacement(self.tree.children(node), times))
            for node, times in sorted(collections.Counter(state).items())
        ]
        for chosen in itertools.product(*picks):
            yield tuple(itertools.chain.from_iterable(chosen))

    def successor_count(self, state: State) -> int:
        """How many children expanding or bounding a state lists at most: Γ's and Γh's products [-].

        Γ replaces every super-contact at once, so a state has up to b^m successors: at large m
        one expansion outlasts any time limit, and the search checks this count first.
        """
        # From the sizes alone: splitting a node here would number the tree's nodes in another order.
        spread = max(int(self.config["branching"]), int(self.config.get("heuristic_branching") or 1))
        count = 1
        for node in state:
            count *= min(spread, len(self.tree.members[node]))
        return count

    # -- quality: exact values and cheap upper bounds ---------------------------------

    def vector(self, key: Any, members: Indices) -> Vector:
        vec = self.oracle.bounds.vector(members, self._vectors.get(key))
        self._vectors[key] = vec
        return vec

    def node_vectors(self, state: State) -> list[Vector]:
        count = self.oracle.bounds.count
        rows = self._node_vectors
        filled = self._filled
        vectors = []
        for node in state:
            if node >= len(filled) or filled[node] != count:  # new, or directions were learned since
                self._fill(node)
                rows, filled = self._node_vectors, self._filled
            vectors.append(rows[node, :count])
        return vectors

    def _fill(self, node: int) -> None:
        """Bring a tree node's support vector up to the current directions (rows grow with the tree)."""
        if node >= len(self._filled):
            self._grow(len(self.tree.members))
        bounds = self.oracle.bounds
        done = int(self._filled[node])
        members = self.tree.members[node]
        if done == 0:
            self._sizes[node] = len(members)
            self._depths[node] = self.tree.depth[node]
            self._masks[node] = self.tree.masks[node]
        bounds.extend(members, self._node_vectors[node], done)
        self._filled[node] = bounds.count

    def _grow(self, nodes: int) -> None:
        """Room for at least ``nodes`` tree nodes in the per-node arrays (doubling)."""
        old = len(self._filled)
        size = max(nodes, 2 * old, 64)

        def grown(array: np.ndarray, fill: int) -> np.ndarray:
            new = np.full((size, *array.shape[1:]), fill, dtype=array.dtype)
            new[:old] = array
            return new

        self._node_vectors = grown(self._node_vectors, 0)
        self._filled = grown(self._filled, 0)
        self._sizes = grown(self._sizes, 0)
        self._depths = grown(self._depths, 0)
        self._table = grown(self._table, -1)
        self._widths = grown(self._widths, 0)
        self._masks = grown(self._masks, 0)

    def successors_with_bounds(self, state: State) -> tuple[list[State], list[float]]:
        """:meth:`successors` and the support bound U [-] of each.

        Where Γh's compiled listing applies and successors are neither symmetry-filtered nor
        ordered, they are its children (the same states in the same order): one compiled
        call. Otherwise U of the Python successors in one compiled call where it applies.
        """
        if self._compiled_children and self.symmetry is None and not self.config["ordered"]:
            keys, bounds, _, _, rejected, _ = self._listing(state)
            self.pruned += rejected
            return [tuple(key) for key in keys.tolist()], bounds.tolist()
        children = self.successors(state)
        if not self._compiled_children or not children:
            return children, [self.upper(self.node_vectors(child)) for child in children]
        self.fill_child_nodes(state)
        self.bound_evaluations += len(children)
        keys = np.array(children, dtype=np.int64)
        return children, support_bounds(keys, self._node_vectors, self.oracle.bounds.count).tolist()

    def upper(self, vectors: Sequence[Vector]) -> float:
        self.bound_evaluations += 1
        return self.oracle.bounds.bound(vectors)

    def exact(self, state: State) -> float:
        return self.oracle.of_masks([self.tree.masks[node] for node in state], self.node_vectors(state))

    def g_quality(self, state: State) -> float:
        """Q1 of a state's union for its g, or, where an upper bound of it serves, a facet bound [-].

        A non-terminal state's g only bounds its f from below before the heuristic makes f
        exact, so q0 minus an upper bound of its Q1 (10 µs instead of 100-300) serves: for
        A* it is a lower bound like any other, and WA*'s key g + (1 + eps)(f - g) only
        rises with a smaller g, staying at most (1 + eps) f, all its guarantee needs.
        Exact values remain for terminal states (grasps' Q1) and Dijkstra (f is g).
        """
        if self.heuristic_kind == "none" or self.is_terminal(state):
            return self.exact(state)
        vectors = self.node_vectors(state)
        self.bound_evaluations += 1
        table = self.child_bounds
        if table is not None:
            bounds = self.oracle.bounds
            value, level = state_bound(
                np.array(sorted(state), dtype=np.int32),
                self.contacts.wrenches,
                bounds.directions,
                bounds.count,
                self._masks,
                self._node_vectors,
                table.keys,
                table.values,
                table.levels,
                table.counters,
            )
            if level > 0:
                return float(value)
        bound, start = self.oracle.bounds.lowest(vectors)
        q = self.oracle.tighten([self.tree.masks[node] for node in state], vectors, 0, bound, start)[0]
        return min(q, bound)

    def heuristic_children(self, state: State) -> list[tuple[ChildKey, list[Vector]]]:
        """Valid Γh children as (key, support vectors); never symmetry-filtered (admissibility).

        A key (:data:`ChildKey`) is the child's state (sorted node tuple) when Γh is the
        expansion tree. It is all a caller needs to keep: the search holds
        millions of children waiting at m >= 5, and :meth:`child_masks` and
        :meth:`child_vectors` give the rest back when a child is tightened.
        """
        children: list[tuple[ChildKey, list[Vector]]] = []
        if self.heuristic_shares_tree:
            combos = dict.fromkeys(tuple(sorted(c)) for c in itertools.product(*(self.tree.children(n) for n in state)))
            for child in combos:
                if self.valid(self.members(child), self.is_terminal(child), child):
                    children.append((child, self.node_vectors(child)))
            return children
        options = []
        for node in state:
            parts = self._heuristic_parts.get(node)
            if parts is None:
                assert self.heuristic_partitioner is not None
                split = self.heuristic_partitioner.split(self.tree.members[node])
                parts = [(p, self.oracle.mask_of(p)) for p in split]
                self._heuristic_parts[node] = parts
            stride = self.config["heuristic_branching"]
            assert len(parts) <= stride, "a partitioner splits into at most b parts"
            options.append([node * stride + i for i in range(len(parts))])
        for combo in itertools.product(*options):
            members = [self._heuristic_part(key)[0] for key in combo]
            if self.valid(members, all(len(p) == 1 for p in members), combo):
                children.append((combo, self.child_vectors(combo)))
        return children

    def heuristic_bounds(
        self, state: State
    ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.int32], NDArray[np.bool_]]:
        """Γh children as arrays: keys (shape (k, m)), support bounds U [-], the direction of D
        that gives each bound (-1: not known) and whether each is a grasp state.

        The same children in the same order as :meth:`heuristic_children`; listed by
        :func:`ogcp.planner.search.children_kernel.shared_tree_children` where it applies.
        """
        if not self._compiled_children:
            found = self.heuristic_children(state)
            keys = np.array([key for key, _ in found], dtype=np.int32).reshape(len(found), self.m)
            bounds = np.array([self.upper(vectors) for _, vectors in found], dtype=np.float64)
            shared = self.heuristic_shares_tree
            terminal = np.array([shared and self.is_terminal(key) for key, _ in found], dtype=np.bool_)
            return keys, bounds, np.full(len(bounds), -1, dtype=np.int32), terminal
        keys, bounds, starts, terminal, _, _ = self._listing(state)
        return keys, bounds, starts, terminal

    def numbered_children(
        self, state: State
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int32], NDArray[np.bool_]]:
        """:meth:`heuristic_bounds` where the compiled listing applies, with each child's number in
        its product order (:meth:`child_of_number`) in place of its nodes."""
        _, bounds, starts, terminal, _, codes = self._listing(state)
        return codes, bounds, starts, terminal

    def child_of_number(self, state: State, code: int) -> State:
        """The sorted nodes of a state's Γh child numbered ``code`` by :meth:`numbered_children`."""
        nodes = []
        for node in reversed(state):
            width = int(self._widths[node])
            nodes.append(int(self._table[node, code % width]))
            code //= width
        return tuple(sorted(nodes))

    def _listing(
        self, state: State
    ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.int32], NDArray[np.bool_], int, NDArray[np.int64]]:
        """:func:`ogcp.planner.search.children_kernel.shared_tree_children` of a state."""
        nodes = np.array(state, dtype=np.int64)
        count = self.oracle.bounds.count
        listing = shared_tree_children(
            nodes, self._table, self._widths, self._sizes, self._node_vectors, self._filled, count
        )
        if listing[4] < 0:  # child rows to fill first (new nodes, or directions learned since)
            self.fill_child_nodes(state)
            listing = shared_tree_children(
                nodes, self._table, self._widths, self._sizes, self._node_vectors, self._filled, count
            )
        self.bound_evaluations += len(listing[1])
        return listing

    def fill_child_nodes(self, state: State) -> None:
        """Bring the per-node rows of every child node of the state up to the current directions."""
        count = self.oracle.bounds.count
        for node in state:
            if node >= len(self._widths) or self._widths[node] == 0:
                children = self.tree.children(node)
                if len(self._widths) < len(self.tree.members):
                    self._grow(len(self.tree.members))
                self._table[node, : len(children)] = children
                self._widths[node] = len(children)
        for child in stale_children(np.array(state), self._table, self._widths, self._filled, count).tolist():
            self._fill(child)

    def child_state(self, key: ChildKey) -> State | None:
        """The state of a Γh child, or None when Γh is not the expansion tree."""
        return key if self.heuristic_shares_tree else None

    def child_masks(self, key: ChildKey) -> list[PackedMask]:
        """Packed masks of a Γh child's super-contacts."""
        if self.heuristic_shares_tree:
            return [self.tree.masks[node] for node in key]
        return [self._heuristic_part(part)[1] for part in key]

    def child_vectors(self, key: ChildKey) -> list[Vector]:
        """Support vectors of a Γh child's super-contacts."""
        if self.heuristic_shares_tree:
            return self.node_vectors(key)
        return [self.vector(("h", part), self._heuristic_part(part)[0]) for part in key]

    def _heuristic_part(self, part: int) -> tuple[Indices, PackedMask]:
        """Members and mask of a part of Γh's own partitioner, by its key ``node * b_h + i``."""
        node, i = divmod(part, self.config["heuristic_branching"])
        return self._heuristic_parts[node][i]
