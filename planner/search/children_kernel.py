"""Γh children of a state on the expansion tree with their support bounds, in numba.

The search's branch and bound starts by listing a state's heuristic children (the sorted,
distinct combinations of one child node per super-contact that keep distinct contacts
possible) and the support bound U of each. In Python that costs a few microseconds per
child in tuples, dictionaries and small numpy calls, over a million times at m >= 5; here
it is one call per state. The children come out in the order of the Python listing
(``itertools.product`` order, first occurrence of each sorted combination), so the search
is the same either way.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.jit import cached_njit


@cached_njit(inline="always")
def row_equals(rows: np.ndarray, r: int, key: np.ndarray) -> bool:
    """Whether row ``r`` of ``rows`` equals ``key`` (node tuples, shape (m,))."""
    for j in range(key.shape[0]):
        if rows[r, j] != key[j]:
            return False
    return True


@cached_njit(inline="always")
def first_lowest(values: np.ndarray, count: int) -> tuple[float, int]:
    """The smallest of the first ``count`` values and the index of its first occurrence
    ((inf, 0) when none is below inf).

    Eight running minima instead of one: a single one chains every comparison on the last,
    and this scan over |D| = 2000 support values, once per listed child, took over half a listing.
    """
    lanes = np.full(8, np.inf)
    whole = count - count % 8
    for d in range(0, whole, 8):
        for lane in range(8):
            lanes[lane] = min(lanes[lane], values[d + lane])
    lowest = np.inf
    for lane in range(8):
        lowest = min(lowest, lanes[lane])
    for d in range(whole, count):
        lowest = min(lowest, values[d])
    for d in range(count):
        if values[d] == lowest:
            return lowest, d
    return lowest, 0


@cached_njit(inline="always")
def _repeats_fit(combo: np.ndarray, sizes: np.ndarray) -> bool:
    """Whether distinct contacts are possible in a sorted combination of nodes: the nodes of a
    state are equal or disjoint, so a node may be repeated at most as often as it has contacts."""
    run = 1
    for j in range(1, combo.shape[0]):
        run = run + 1 if combo[j] == combo[j - 1] else 1
        if run > sizes[combo[j]]:
            return False
    return True


@cached_njit(inline="always")
def _listed(rows: np.ndarray, count: int, combo: np.ndarray) -> bool:
    """Whether ``combo`` equals one of the first ``count`` rows."""
    for r in range(count):
        if row_equals(rows, r, combo):
            return True
    return False


@cached_njit()
def shared_tree_children(
    state: np.ndarray,
    table: np.ndarray,
    widths: np.ndarray,
    sizes: np.ndarray,
    vectors: np.ndarray,
    filled: np.ndarray,
    count: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, np.ndarray]:
    """Valid Γh children of a state and their support bounds.

    Args:
        state: Node of each super-contact, shape (m,).
        table: Child nodes of each node, padded, shape (nodes, b); a leaf's only child is itself.
        widths: Number of children of each node, shape (nodes,).
        sizes: Number of contacts in each node, shape (nodes,).
        vectors: Support vector of each node over the directions D, shape (nodes, >= count).
        filled: Directions each node's support vector holds, shape (nodes,).
        count: |D|.

    Returns:
        (keys, bounds, starts, terminal, rejected, codes): the children's sorted nodes, shape
        (k, m), int32; their support bounds U [-], shape (k,); the direction of D that gives
        each bound (the first of equal ones), where its first facet bound starts; whether each
        is a grasp (every node one contact); how many distinct combinations distinct contacts
        ruled out, or -1, with nothing listed, when a node of the state has no row of
        ``table`` yet or a child node's vector lacks some of the ``count`` directions (the
        caller fills them and asks again); each child's number in product order, shape (k,),
        int64 (:func:`decode_child` turns it back into the child's nodes).
    """
    m = state.shape[0]
    for j in range(m):
        if state[j] >= widths.shape[0] or widths[state[j]] == 0:
            return _nothing(m)
        for c in range(widths[state[j]]):
            if filled[table[state[j], c]] != count:
                return _nothing(m)
    total = 1
    for j in range(m):
        total *= widths[state[j]]
    keys = np.empty((total, m), dtype=np.int32)
    bounds = np.empty(total)
    terminal = np.empty(total, dtype=np.bool_)
    starts = np.empty(total, dtype=np.int32)
    codes = np.empty(total, dtype=np.int64)
    index = np.zeros(m, dtype=np.int64)
    combo = np.empty(m, dtype=np.int64)
    # prefix[j] = the support vector of the first j + 1 nodes of the current combination (in
    # product order, whose maximum is the sorted one's); rows from ``fresh_from`` on are
    # stale. Neighbours in product order share all but the last few nodes, so a child costs
    # about 2 |D| maxima instead of m |D| (b = 2).
    prefix = np.empty((m, count))
    fresh_from = 0
    k = 0
    rejected = np.empty((total, m), dtype=np.int32)
    nrejected = 0
    for code in range(total):
        for j in range(m):
            combo[j] = table[state[j], index[j]]
        combo.sort()
        fresh = not _listed(keys, k, combo)
        valid = fresh and _repeats_fit(combo, sizes)
        if fresh and not valid and not _listed(rejected, nrejected, combo):
            rejected[nrejected] = combo
            nrejected += 1
        if valid:
            for j in range(fresh_from, m):
                row = vectors[table[state[j], index[j]]]
                if j == 0:
                    for d in range(count):
                        prefix[0, d] = row[d]
                else:
                    for d in range(count):
                        prefix[j, d] = max(prefix[j - 1, d], row[d])
            fresh_from = m
            bound, lowest = first_lowest(prefix[m - 1], count)
            leaf = True
            for j in range(m):
                keys[k, j] = combo[j]
                leaf = leaf and sizes[combo[j]] == 1
            bounds[k] = bound
            starts[k] = lowest
            terminal[k] = leaf
            codes[k] = code
            k += 1
        # Next index in itertools.product order (the last position fastest).
        j = m - 1
        while j >= 0:
            index[j] += 1
            if index[j] < widths[state[j]]:
                break
            index[j] = 0
            j -= 1
        fresh_from = min(fresh_from, max(j, 0))
    return keys[:k], bounds[:k], starts[:k], terminal[:k], nrejected, codes[:k]


@cached_njit(inline="always")
def _nothing(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, np.ndarray]:
    """The listing's answer when rows are missing (see :func:`shared_tree_children`)."""
    return (
        np.empty((0, m), np.int32),
        np.empty(0),
        np.empty(0, np.int32),
        np.empty(0, np.bool_),
        -1,
        np.empty(0, np.int64),
    )


@cached_njit(inline="always")
def decode_child(state: np.ndarray, table: np.ndarray, widths: np.ndarray, code: int, key: np.ndarray) -> None:
    """Write into ``key`` (shape (m,)) the sorted nodes of the child numbered ``code`` in
    :func:`shared_tree_children`'s product order (the last position fastest)."""
    for j in range(state.shape[0] - 1, -1, -1):
        width = widths[state[j]]
        key[j] = table[state[j], code % width]
        code //= width
    key.sort()


@cached_njit()
def decode_children(
    state: np.ndarray, codes: np.ndarray, table: np.ndarray, widths: np.ndarray, sizes: np.ndarray, depths: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The children of a state numbered ``codes`` by :func:`shared_tree_children`, without
    listing them again.

    Args:
        state: Node of each super-contact, shape (m,), as listed.
        codes: Children's numbers in product order, shape (k,).
        table: Child nodes of each node, padded, shape (nodes, b).
        widths: Number of children of each node, shape (nodes,).
        sizes: Number of contacts in each node, shape (nodes,).
        depths: Depth of each node in the partition tree, shape (nodes,).

    Returns:
        (keys, terminal, depth, rejected): the children's sorted nodes, shape (k, m), int32;
        whether each is a grasp (every node one contact), shape (k,); each one's depth (its
        deepest node's), shape (k,); how many distinct combinations distinct contacts ruled
        out (the listing's count).
    """
    m = state.shape[0]
    keys = np.empty((codes.shape[0], m), dtype=np.int32)
    terminal = np.empty(codes.shape[0], dtype=np.bool_)
    deepest = np.zeros(codes.shape[0], dtype=np.int64)
    key = np.empty(m, dtype=np.int64)
    for k in range(codes.shape[0]):
        decode_child(state, table, widths, codes[k], key)
        leaf = True
        for j in range(m):
            keys[k, j] = key[j]
            leaf = leaf and sizes[key[j]] == 1
            deepest[k] = max(deepest[k], depths[key[j]])
        terminal[k] = leaf
    total = 1
    for j in range(m):
        total *= widths[state[j]]
    # Validity depends on the sorted combination alone: count the distinct invalid ones.
    rejected = np.empty((total, m), dtype=np.int32)
    nrejected = 0
    for code in range(total):
        decode_child(state, table, widths, code, key)
        if not _repeats_fit(key, sizes) and not _listed(rejected, nrejected, key):
            rejected[nrejected] = key
            nrejected += 1
    return keys, terminal, deepest, nrejected


@cached_njit()
def stale_children(
    state: np.ndarray, table: np.ndarray, widths: np.ndarray, filled: np.ndarray, count: int
) -> np.ndarray:
    """Child nodes of a state whose support vectors lack some of the ``count`` directions.

    Args:
        state: Node of each super-contact, shape (m,); every one has its row of ``table``.
        table: Child nodes of each node, padded, shape (nodes, b).
        widths: Number of children of each node, shape (nodes,).
        filled: Directions each node's support vector holds, shape (nodes,).
        count: |D|.

    Returns:
        The stale nodes, each once, shape (s,).
    """
    stale = np.empty(state.shape[0] * table.shape[1], dtype=np.int64)
    s = 0
    for j in range(state.shape[0]):
        for c in range(widths[state[j]]):
            node = table[state[j], c]
            if filled[node] != count:
                seen = False
                for r in range(s):
                    if stale[r] == node:
                        seen = True
                        break
                if not seen:
                    stale[s] = node
                    s += 1
    return stale[:s]


@cached_njit()
def support_bounds(children: np.ndarray, vectors: np.ndarray, count: int) -> np.ndarray:
    """Support bound U [-] of each of the given states, shape (k,).

    Args:
        children: Nodes of each state, shape (k, m).
        vectors: Support vector of each node over the directions D, shape (nodes, >= count),
            filled up to ``count`` for every node named.
        count: |D|.
    """
    bounds = np.empty(children.shape[0])
    joint = np.empty(count)
    for k in range(children.shape[0]):
        first = vectors[children[k, 0]]
        for d in range(count):
            joint[d] = first[d]
        for j in range(1, children.shape[1]):  # row by row: the loops vectorise
            row = vectors[children[k, j]]
            for d in range(count):
                joint[d] = max(joint[d], row[d])
        bound = np.inf
        for d in range(count):
            bound = min(bound, joint[d])
        bounds[k] = bound
    return bounds
