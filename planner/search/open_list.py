"""The open list of a best-first search: a binary min-heap on arrays.

A search at m >= 5 holds millions of open states. As Python tuples in a ``heapq`` list each
took about 250 bytes; here an entry is six numbers in two arrays (48 bytes), and the heap's
sifts run compiled. Entries order by (key, -depth, tie), the order of the tuples before, and
ties are unique, so the states come out in the same sequence.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.infra.arrays import grow_rows

#: An entry: (key, -depth, tie, lower bound of the unweighted f, stage, g or NaN, state id).
Entry = tuple[float, int, int, float, int, float, int]
#: Stages take two bits of the packed id.
_STAGE_BITS = 2


@cached_njit(inline="always")
def _less(values: np.ndarray, order: np.ndarray, a: int, b: int) -> bool:
    """Whether entry ``a`` comes before entry ``b``: by key, then -depth, then tie."""
    if values[a, 0] != values[b, 0]:
        return values[a, 0] < values[b, 0]
    if order[a, 0] != order[b, 0]:
        return order[a, 0] < order[b, 0]
    return order[a, 1] < order[b, 1]


@cached_njit(inline="always")
def _swap(values: np.ndarray, order: np.ndarray, a: int, b: int) -> None:
    for j in range(3):
        values[a, j], values[b, j] = values[b, j], values[a, j]
        order[a, j], order[b, j] = order[b, j], order[a, j]


@cached_njit()
def _sift_up(values: np.ndarray, order: np.ndarray, pos: int) -> None:
    while pos > 0:
        parent = (pos - 1) // 2
        if not _less(values, order, pos, parent):
            return
        _swap(values, order, pos, parent)
        pos = parent


@cached_njit(inline="always")
def _sift_down(values: np.ndarray, order: np.ndarray, pos: int, size: int) -> None:
    while True:
        child = 2 * pos + 1
        if child >= size:
            return
        if child + 1 < size and _less(values, order, child + 1, child):
            child += 1
        if not _less(values, order, child, pos):
            return
        _swap(values, order, pos, child)
        pos = child


@cached_njit()
def _insert_at(
    values: np.ndarray,
    order: np.ndarray,
    pos: int,
    key: float,
    lower: float,
    g: float,
    neg_depth: int,
    tie: int,
    packed: int,
) -> None:
    """Write an entry into free row ``pos`` and sift it up, in one compiled call (with the rows
    written from Python tuples, an insertion took 2.9 µs in a profile of amphora m = 5; 1.6 µs now)."""
    values[pos, 0], values[pos, 1], values[pos, 2] = key, lower, g
    order[pos, 0], order[pos, 1], order[pos, 2] = neg_depth, tie, packed
    _sift_up(values, order, pos)


@cached_njit()
def _insert_many(
    values: np.ndarray,
    order: np.ndarray,
    size: int,
    keys: np.ndarray,
    lowers: np.ndarray,
    gs: np.ndarray,
    neg_depths: np.ndarray,
    tie: int,
    packed: np.ndarray,
) -> None:
    """:func:`_insert_at` of each entry in turn, from row ``size`` on, with ties from ``tie`` on."""
    for i in range(keys.shape[0]):
        _insert_at(values, order, size + i, keys[i], lowers[i], gs[i], neg_depths[i], tie + i, packed[i])


@cached_njit()
def _pop_top(values: np.ndarray, order: np.ndarray, size: int) -> tuple[float, float, float, int, int, int]:
    """Remove the top of ``size`` entries: move the last to the top and sift it down.

    Returns:
        The top's (key, lower, g, -depth, tie, packed id).
    """
    top = (values[0, 0], values[0, 1], values[0, 2], order[0, 0], order[0, 1], order[0, 2])
    last = size - 1
    for j in range(3):
        values[0, j] = values[last, j]
        order[0, j] = order[last, j]
    _sift_down(values, order, 0, last)
    return top


@cached_njit()
def _purge(
    values: np.ndarray, order: np.ndarray, size: int, column: int, limit: float, keep: int, removed: np.ndarray
) -> int:
    """Move the entries whose value in ``column`` (0: key, 1: lower bound) is <= ``limit``, and the
    entry of packed id ``keep``, to the front in place (no copy of millions of rows), collect the
    others' packed ids in ``removed`` and make the front a heap again."""
    kept = 0
    gone = 0
    for i in range(size):
        if values[i, column] <= limit or order[i, 2] == keep:
            if kept != i:
                for j in range(3):
                    values[kept, j] = values[i, j]
                    order[kept, j] = order[i, j]
            kept += 1
        else:
            removed[gone] = order[i, 2]
            gone += 1
    for pos in range(kept // 2 - 1, -1, -1):
        _sift_down(values, order, pos, kept)
    return kept


@cached_njit()
def _scan_from(
    values: np.ndarray, order: np.ndarray, size: int, threshold: float, keep: int
) -> tuple[int, float, float, int]:
    """(count, smallest key, smallest lower bound) of the entries of key >= ``threshold`` but
    state id ``keep``'s, and the packed id of ``keep``'s entry (-1: none)."""
    count = 0
    key = np.inf
    lowest = np.inf
    keep_packed = -1
    for i in range(size):
        if order[i, 2] >> _STAGE_BITS == keep:
            keep_packed = order[i, 2]
        elif values[i, 0] >= threshold:
            count += 1
            key = min(key, values[i, 0])
            lowest = min(lowest, values[i, 1])
    return count, key, lowest, keep_packed


@cached_njit()
def _key_weights(
    values: np.ndarray, order: np.ndarray, size: int, bins: int, base: float, stage: int, extra: float
) -> tuple[float, float, np.ndarray]:
    """(smallest key, largest key, weight per bin): see :meth:`OpenList.key_weights`."""
    low = np.inf
    high = -np.inf
    for i in range(size):
        low = min(low, values[i, 0])
        high = max(high, values[i, 0])
    weights = np.zeros(bins)
    span = high - low
    for i in range(size):
        b = bins - 1
        if span > 0:
            b = min(int((values[i, 0] - low) / span * bins), bins - 1)
        weight = base
        if order[i, 2] & ((1 << _STAGE_BITS) - 1) == stage:
            weight += extra
        weights[b] += weight
    return low, high, weights


class OpenList:
    """Open states of one search, smallest (key, -depth, tie) first.

    Args:
        capacity: Initial room [entries]; it grows in place when full (:func:`ogcp.planner.infra.arrays.grow_rows`).
    """

    def __init__(self, capacity: int = 1024) -> None:
        self._values = np.empty((capacity, 3))  # key, lower bound of f, g
        self._order = np.empty((capacity, 3), dtype=np.int64)  # -depth, tie, id * 4 + stage
        self._size = 0
        self._tie = 0

    def __len__(self) -> int:
        return self._size

    def push(self, key: float, neg_depth: int, lower: float, stage: int, g: float, ident: int) -> None:
        """Enter a state (the next tie number breaks equal keys and depths first come, first served)."""
        self._insert(key, neg_depth, self._tie, lower, stage, g, ident)
        self._tie += 1

    def push_many(
        self,
        keys: np.ndarray,
        neg_depths: np.ndarray,
        lowers: np.ndarray,
        stages: np.ndarray,
        gs: np.ndarray,
        idents: np.ndarray,
    ) -> None:
        """:meth:`push` of each entry in turn (arrays of shape (k,)), in one compiled call."""
        count = len(keys)
        if self._size + count > len(self._values):
            grow_rows(self._values, self._size + count)
            grow_rows(self._order, len(self._values))
        packed = (idents.astype(np.int64) << _STAGE_BITS) | stages
        _insert_many(self._values, self._order, self._size, keys, lowers, gs, neg_depths, self._tie, packed)
        self._size += count
        self._tie += count

    def restore(self, entry: Entry) -> None:
        """Enter a popped entry again, with its own tie number."""
        key, neg_depth, tie, lower, stage, g, ident = entry
        self._insert(key, neg_depth, tie, lower, stage, g, ident)

    def _insert(self, key: float, neg_depth: int, tie: int, lower: float, stage: int, g: float, ident: int) -> None:
        if self._size == len(self._values):
            grow_rows(self._values, self._size + 1)
            grow_rows(self._order, len(self._values))
        _insert_at(self._values, self._order, self._size, key, lower, g, neg_depth, tie, (ident << _STAGE_BITS) | stage)
        self._size += 1

    def pop(self) -> Entry:
        """Remove and return the first entry."""
        if not self._size:
            raise IndexError("pop from an empty open list")
        key, lower, g, neg_depth, tie, packed = _pop_top(self._values, self._order, self._size)
        self._size -= 1
        return key, neg_depth, tie, lower, packed & ((1 << _STAGE_BITS) - 1), g, packed >> _STAGE_BITS

    def purge(self, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
        """Remove every entry whose lower bound of f exceeds ``cutoff``.

        The others come out in the same order as before (the order is total).

        Returns:
            The removed entries' state ids and stages, shape (removed,) each.
        """
        size = self._size
        packed = np.empty(int(np.count_nonzero(self._values[:size, 1] > cutoff)), dtype=np.int64)
        if len(packed):
            self._size = _purge(self._values, self._order, size, 1, cutoff, -1, packed)
        return packed >> _STAGE_BITS, packed & ((1 << _STAGE_BITS) - 1)

    def forget(self, threshold: float, keep: int = -1) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Remove every entry whose key is >= ``threshold``, except those of state id ``keep``.

        The others come out in the same order as before. Compiled passes, with no array of the
        open list's size: a search forgets at its memory limit.

        Returns:
            The removed entries' state ids and stages, shape (removed,) each, and their smallest
            key and smallest lower bound of f (inf when none was removed).
        """
        size = self._size
        count, key, lowest, keep_packed = _scan_from(self._values, self._order, size, threshold, keep)
        packed = np.empty(count, dtype=np.int64)
        if count:
            below = float(np.nextafter(threshold, -np.inf))
            self._size = _purge(self._values, self._order, size, 0, below, keep_packed, packed)
        return packed >> _STAGE_BITS, packed & ((1 << _STAGE_BITS) - 1), float(key), float(lowest)

    def key_weights(self, bins: int, base: float, stage: int, extra: float) -> tuple[np.ndarray, np.ndarray]:
        """What the entries weigh by key: a histogram of ``bins`` equal bins from the smallest
        key to the largest, each entry weighing ``base``, plus ``extra`` at ``stage``.

        Returns:
            The bins' edges, shape (bins + 1,), and weights, shape (bins,).
        """
        low, high, weights = _key_weights(self._values, self._order, self._size, bins, base, stage, extra)
        return np.linspace(low, high, bins + 1), weights

    def first_key(self) -> float:
        """The first entry's key (inf when empty)."""
        return float(self._values[0, 0]) if self._size else np.inf

    def lowest_lower(self) -> float:
        """The smallest lower bound of f over the open states (inf when empty)."""
        return float(self._values[: self._size, 1].min()) if self._size else np.inf

    def smallest_lower(self, count: int) -> list[Entry]:
        """The ``count`` entries of smallest lower bounds of f, smallest first (ties in heap order)."""
        ranked = np.argsort(self._values[: self._size, 1], kind="stable")[:count]
        return [self._entry(int(i)) for i in ranked]

    def holds(self, ident: int) -> bool:
        """Whether a state id has an entry."""
        return bool(((self._order[: self._size, 2] >> _STAGE_BITS) == ident).any())

    def first_of(self, ident: int) -> Entry:
        """The first entry of a state id (by the open list's order)."""
        slots = np.flatnonzero((self._order[: self._size, 2] >> _STAGE_BITS) == ident)
        if not len(slots):
            raise KeyError(f"state {ident} is not open")
        best = int(slots[0])
        for slot in slots[1:].tolist():
            if _less(self._values, self._order, slot, best):
                best = slot
        return self._entry(best)

    def _entry(self, slot: int) -> Entry:
        key, lower, g = self._values[slot].tolist()
        neg_depth, tie, packed = self._order[slot].tolist()
        return key, neg_depth, tie, lower, packed & ((1 << _STAGE_BITS) - 1), g, packed >> _STAGE_BITS
