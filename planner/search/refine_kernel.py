"""A state's branch and bound over its Γh children, in numba, up to the next exact value.

:meth:`ogcp.planner.search.refine.ChildRefinement.refine` tightens the child of the largest
upper bound, one level at a time (support bound, first facet bound, more facet bounds, exact
Q1: :meth:`ogcp.planner.grasp.subset_quality.GraspQuality.tighten`), until the largest is
exact or the state must go back to the open list. Most steps are facet bounds of 5-40 µs,
which Python wrapped in 20 µs of dictionaries, tuples and small numpy calls, hundreds of
thousands of times a minute. Here one call runs the loop until it needs an exact value,
which stays with the Python oracle (its cache, its learned directions), or the caller lets
f settle on the facet bound instead.

Facet bounds are remembered per child (its sorted node tuple) in :class:`ChildBounds`, an
open-addressing table, the compiled counterpart of the oracle's store of facet bounds:
a child of one state is often a child of the next. Each new facet bound's normal also
lowers the other children's bounds (:func:`share_normal`), as the Python loop does.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel.geometry import CUT_MARGIN, FC_TOL
from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.grasp.kernel.ray_bound import union_facet_bound, union_facet_bound_along
from ogcp.planner.grasp.subset_quality import EXACT, FACET_STARTS
from ogcp.planner.search.children_kernel import decode_child, first_lowest, row_equals

#: Outcomes of :func:`branch_and_bound`: the largest bound is exact (the state's f is
#: known); the state's lower bound of f passed the open list's first key (it goes back);
#: the largest bound's next level is the exact value (the caller computes it); a grasp
#: child became exact from the table or a zero proof (the caller may take it as incumbent);
#: the support vectors of the largest bound's nodes lack directions learned since (the
#: caller fills them; only the ranked facet bounds read them).
SETTLED, YIELD, NEEDS_EXACT, GRASP_EXACT, NEEDS_ROWS = 0, 1, 2, 3, 4
#: Slots of the table (a power of two); it starts afresh when half full, which costs
#: recomputation only. 9 bytes a slot plus 4 per finger.
TABLE_SLOTS = 1 << 20


class ChildBounds:
    """Remembered upper bounds of Γh children's Q1, by their sorted node tuple.

    Args:
        m: Nodes per key (the number of fingers).
        slots: Table size, a power of two.

    Attributes:
        facet_bounds: Facet bounds computed by :func:`branch_and_bound` so far.
        rejections: Children it settled as Q1 = 0 by a facet bound.
    """

    def __init__(self, m: int, slots: int = TABLE_SLOTS) -> None:
        if slots & (slots - 1):
            raise ValueError(f"slots must be a power of two, got {slots}")
        self.keys = np.empty((slots, m), dtype=np.int32)
        self.values = np.empty(slots)
        self.levels = np.full(slots, -1, dtype=np.int8)  # -1: empty
        #: (entries in use, facet bounds computed, children settled as zero, facet normals
        #: shared with siblings, siblings' bounds they lowered)
        self.counters = np.zeros(5, dtype=np.int64)

    @property
    def facet_bounds(self) -> int:
        return int(self.counters[1])

    @property
    def rejections(self) -> int:
        return int(self.counters[2])

    @property
    def lowered(self) -> int:
        """Children's bounds lowered by a sibling's facet normal (:func:`share_normal`)."""
        return int(self.counters[4])

    def get(self, key: NDArray[np.int32]) -> tuple[float, int] | None:
        """A child's remembered (bound [-], level), or None."""
        slot = _slot(self.keys, self.levels, np.asarray(key, dtype=np.int32))
        level = int(self.levels[slot])
        return None if level < 0 else (float(self.values[slot]), level)

    def store(self, key: NDArray[np.int32], value: float, level: int) -> None:
        """Remember a child's bound [-] at a level (:data:`EXACT` for its Q1)."""
        _store(self.keys, self.values, self.levels, self.counters, key, value, level)


@cached_njit(inline="always")
def _slot(keys: np.ndarray, levels: np.ndarray, key: np.ndarray) -> int:
    """The slot holding ``key``, or the empty slot where it would go."""
    h = np.uint64(0)
    for j in range(key.shape[0]):
        h = (h ^ np.uint64(key[j])) * np.uint64(0x9E3779B97F4A7C15)
        h ^= h >> np.uint64(29)  # murmur-style mixing: node ids are small, neighbours close
    h = (h ^ (h >> np.uint64(32))) * np.uint64(0xFF51AFD7ED558CCD)
    h ^= h >> np.uint64(29)
    mask = levels.shape[0] - 1
    s = np.int64(h >> np.uint64(1)) & mask
    while levels[s] >= 0:
        if row_equals(keys, s, key):
            return s
        s = (s + 1) & mask
    return s


@cached_njit()
def _store(
    keys: np.ndarray,
    values: np.ndarray,
    levels: np.ndarray,
    counters: np.ndarray,
    key: np.ndarray,
    value: float,
    level: int,
) -> None:
    if 2 * counters[0] >= levels.shape[0]:
        levels[:] = -1
        counters[0] = 0
    s = _slot(keys, levels, key)
    if levels[s] < 0:
        counters[0] += 1
        keys[s] = key
    values[s] = value
    levels[s] = level


@cached_njit()
def branch_and_bound(
    codes: np.ndarray,
    bounds: np.ndarray,
    levels: np.ndarray,
    starts: np.ndarray,
    state: np.ndarray,
    table: np.ndarray,
    widths: np.ndarray,
    lower: float,
    q0: float,
    first_key: float,
    eps: float,
    report_grasps: bool,
    share: bool,
    wrenches: np.ndarray,
    directions: np.ndarray,
    count: int,
    node_masks: np.ndarray,
    node_vectors: np.ndarray,
    filled: np.ndarray,
    sizes: np.ndarray,
    table_keys: np.ndarray,
    table_values: np.ndarray,
    table_levels: np.ndarray,
    counters: np.ndarray,
) -> tuple[int, int, float]:
    """Tighten the largest of the children's upper bounds until the caller must act.

    The loop of :meth:`ogcp.planner.search.refine.ChildRefinement.refine`, step for step: the child
    of the largest bound (the first of equal ones) is tightened by one level, as
    :meth:`ogcp.planner.grasp.subset_quality.GraspQuality.tighten` would, with the table in
    place of the oracle's store of facet bounds.

    Args:
        codes: The children's numbers in the listing's product order
            (:func:`ogcp.planner.search.children_kernel.decode_child`), shape (k,).
        bounds: Their upper bounds of Q1 [-], shape (k,); updated in place.
        levels: The level of each bound (0 to :data:`EXACT`), shape (k,); updated in place.
        starts: Direction of D of each support bound, where the first facet bound starts,
            shape (k,).
        state: The state's nodes as listed, shape (m,).
        table: Child nodes of each tree node, padded, shape (nodes, b).
        widths: Number of children of each tree node, shape (nodes,).
        lower: The state's lower bound of f so far [-].
        q0: Q1 of all contacts [-].
        first_key: The open list's first key (inf when empty).
        eps: WA*'s eps (0 for A*).
        report_grasps: Return when a grasp child becomes exact here.
        share: Lower the other children's bounds along each new facet bound's normal
            (:func:`share_normal`).
        wrenches: Cone-edge wrenches of every contact, shape (n, k_edges, 6).
        directions: Unit directions of D, shape (>= count, 6).
        count: |D|; every child node's support vector holds that many entries.
        node_masks: Packed membership mask of each tree node, shape (nodes, ceil(n / 8)).
        node_vectors: Support vector of each tree node, shape (nodes, >= count).
        filled: Directions each node's support vector holds, shape (nodes,).
        sizes: Contacts in each tree node, shape (nodes,).
        table_keys: :class:`ChildBounds` arrays, updated in place.
        table_values: See ``table_keys``.
        table_levels: See ``table_keys``.
        counters: See ``table_keys``.

    Returns:
        (outcome, child, lower): one of :data:`SETTLED`, :data:`YIELD`,
        :data:`NEEDS_EXACT`, :data:`GRASP_EXACT`, :data:`NEEDS_ROWS`; the child of the largest bound (or the
        grasp that became exact); the state's lower bound of f [-].
    """
    m = state.shape[0]
    union = np.empty(node_masks.shape[1], dtype=np.uint8)
    rows = np.empty((m, count))
    key = np.empty(m, dtype=np.int32)
    while True:
        i = 0
        for r in range(1, bounds.shape[0]):
            if bounds[r] > bounds[i]:
                i = r
        bound = bounds[i]
        level = levels[i]
        lower = max(lower, q0 - min(q0, max(0.0, bound)))
        if level == EXACT:
            return SETTLED, i, lower
        if (1.0 + eps) * lower > first_key:
            return YIELD, i, lower
        if level >= EXACT - 1 or bound <= FC_TOL:
            return NEEDS_EXACT, i, lower
        decode_child(state, table, widths, codes[i], key)
        s = _slot(table_keys, table_levels, key)
        known_level = table_levels[s]
        if known_level > level:
            known = table_values[s]
            if known_level == EXACT:
                bounds[i] = known
            else:
                bounds[i] = min(known, bound)
            levels[i] = known_level
            if known_level == EXACT and report_grasps and _is_grasp(sizes, key):
                return GRASP_EXACT, i, lower
            continue
        union[:] = 0
        for j in range(m):
            for b in range(union.shape[0]):
                union[b] |= node_masks[key[j], b]
        if level == 0 and starts[i] >= 0:
            raw, normal = union_facet_bound_along(wrenches, union, directions[starts[i]])
            counters[1] += 1
        else:
            for j in range(m):
                if filled[key[j]] < count:
                    return NEEDS_ROWS, i, lower
            for j in range(m):
                rows[j] = node_vectors[key[j], :count]
            first, last = (0, 1) if level == 0 else (1, FACET_STARTS)
            raw, normal = union_facet_bound(wrenches, union, rows, directions, count, first, last)
            counters[1] += last - first
        if share and FC_TOL < raw < np.inf:
            share_normal(normal, state, table, widths, codes, bounds, levels, i, wrenches, node_masks, counters)
        if known_level >= 0:
            raw = min(raw, table_values[s] - CUT_MARGIN)
        if raw <= FC_TOL:
            counters[2] += 1
            _store(table_keys, table_values, table_levels, counters, key, 0.0, EXACT)
            bounds[i] = 0.0
            levels[i] = EXACT
            if report_grasps and _is_grasp(sizes, key):
                return GRASP_EXACT, i, lower
            continue
        value = raw + CUT_MARGIN
        _store(table_keys, table_values, table_levels, counters, key, value, level + 1)
        bounds[i] = min(value, bound)
        levels[i] = level + 1


@cached_njit()
def share_normal(
    u: np.ndarray,
    state: np.ndarray,
    table: np.ndarray,
    widths: np.ndarray,
    codes: np.ndarray,
    bounds: np.ndarray,
    levels: np.ndarray,
    source: int,
    wrenches: np.ndarray,
    node_masks: np.ndarray,
    counters: np.ndarray,
) -> None:
    """Lower the children's bounds to their support along a sibling's facet normal.

    Q1 <= h(u) for every unit u, and the facet normal found for one child is a direction
    along which that child's union is weak; its siblings share most of their nodes with it,
    so most are weak there too. Their support along u costs one pass over the
    state's child nodes (m b supports) and a max of m of them per child, where a facet
    bound of each costs a walk over its whole union (amphora, 1000 contacts, m = 4: 0.71 M
    facet bounds instead of 1.01 M for the proof).

    Args:
        u: Unit direction, shape (6,): the facet normal of child ``source``.
        state: See :func:`branch_and_bound`; so are ``table``, ``widths``, ``codes``,
            ``bounds`` (updated in place), ``levels``, ``wrenches``, ``node_masks`` and ``counters``.
        source: The child whose bound u came from (left as it is).
    """
    m = state.shape[0]
    support = np.empty((m, table.shape[1]))
    for j in range(m):
        for c in range(widths[state[j]]):
            support[j, c] = mask_support(u, node_masks[table[state[j], c]], wrenches)
    counters[3] += 1
    for r in range(bounds.shape[0]):
        if r == source or levels[r] == EXACT:
            continue
        code = codes[r]
        h = -np.inf
        for j in range(m - 1, -1, -1):  # decode_child's order: the last node varies fastest
            width = widths[state[j]]
            h = max(h, support[j, code % width])
            code //= width
        # The margin facet bounds carry: canonical Q1 may sit a rounding error above the true value.
        h += CUT_MARGIN
        if h < bounds[r]:
            bounds[r] = h
            counters[4] += 1


@cached_njit(inline="always")
def mask_support(u: np.ndarray, mask: np.ndarray, wrenches: np.ndarray) -> float:
    """Support along the unit direction u of the contacts in a packed mask [-]: the largest
    ``w . u`` over their cone-edge wrenches (-inf for no contact).

    Args:
        u: Unit direction, shape (6,).
        mask: Packed membership flags (``numpy.packbits``), shape (ceil(n / 8),).
        wrenches: Cone-edge wrenches of every contact, shape (n, k, 6).
    """
    best = -np.inf
    for byte in range(mask.shape[0]):
        bits = mask[byte]
        if bits == 0:
            continue
        for bit in range(8):
            if bits & (128 >> bit):  # packbits order: the first contact in the high bit
                contact = 8 * byte + bit
                for e in range(wrenches.shape[1]):
                    s = 0.0
                    for d in range(6):
                        s += wrenches[contact, e, d] * u[d]
                    best = max(best, s)
    return best


@cached_njit(inline="always")
def _is_grasp(sizes: np.ndarray, key: np.ndarray) -> bool:
    for j in range(key.shape[0]):
        if sizes[key[j]] != 1:
            return False
    return True


@cached_njit()
def state_bound(
    state: np.ndarray,
    wrenches: np.ndarray,
    directions: np.ndarray,
    count: int,
    node_masks: np.ndarray,
    node_vectors: np.ndarray,
    table_keys: np.ndarray,
    table_values: np.ndarray,
    table_levels: np.ndarray,
    counters: np.ndarray,
) -> tuple[float, int]:
    """An upper bound of Q1 of a state's union: the best of its support bound and its table
    entry, else its first facet bound, which is then remembered ([-], level).

    What :meth:`ogcp.planner.search.search_space.SearchSpace.g_quality` asks of
    :meth:`ogcp.planner.grasp.subset_quality.GraspQuality.tighten` at level 0: a child's bounds
    from its parent's branch and bound serve its g at no cost.

    Args:
        state: The state's nodes, sorted, shape (m,), int32; their support vectors hold
            ``count`` directions.
        wrenches: See :func:`branch_and_bound`; so are the other arguments.

    Returns:
        (bound, level): the level is :data:`EXACT` when the bound is the exact value.
    """
    m = state.shape[0]
    joint = node_vectors[state[0], :count].copy()
    for j in range(1, m):  # row by row: the loops vectorise
        row = node_vectors[state[j]]
        for d in range(count):
            joint[d] = max(joint[d], row[d])
    support, start = first_lowest(joint, count)
    s = _slot(table_keys, table_levels, state)
    known_level = table_levels[s]
    if known_level == EXACT:
        return table_values[s], EXACT
    if known_level > 0:
        return min(table_values[s], support), known_level
    if support <= FC_TOL:
        return support, 0  # the caller settles it exactly (a cheap rejection there)
    union = np.zeros(node_masks.shape[1], dtype=np.uint8)
    for j in range(m):
        for b in range(union.shape[0]):
            union[b] |= node_masks[state[j], b]
    raw = union_facet_bound_along(wrenches, union, directions[start])[0]
    counters[1] += 1
    if raw <= FC_TOL:
        counters[2] += 1
        _store(table_keys, table_values, table_levels, counters, state, 0.0, EXACT)
        return 0.0, EXACT
    value = raw + CUT_MARGIN
    _store(table_keys, table_values, table_levels, counters, state, value, 1)
    return min(value, support), 1
