"""Lexicographic m-combinations of range(n) by rank range, for deterministic ES chunks."""

from __future__ import annotations

from math import comb

import numpy as np
from numpy.typing import NDArray


def count(n: int, m: int) -> int:
    """Number of m-combinations of n items."""
    return comb(n, m)


def combinations_range(n: int, m: int, start: int, stop: int) -> NDArray[np.int64]:
    """The combinations with lexicographic ranks in [start, stop), shape (stop - start, m).

    Equivalent to ``list(itertools.combinations(range(n), m))[start:stop]`` without
    enumerating the ones before ``start``.
    """
    stop = min(stop, comb(n, m))
    if start >= stop:
        return np.zeros((0, m), dtype=np.int64)
    return _range(0, n, m, start, stop)


def _range(low: int, n: int, m: int, start: int, stop: int) -> NDArray[np.int64]:
    """Combinations of range(low, n) of size m with ranks [start, stop) among them."""
    if m == 1:
        return np.arange(low + start, low + stop, dtype=np.int64)[:, None]
    blocks = []
    offset = 0
    for first in range(low, n - m + 1):
        size = comb(n - first - 1, m - 1)
        lo, hi = max(start - offset, 0), min(stop - offset, size)
        if lo < hi:
            tail = _range(first + 1, n, m - 1, lo, hi)
            blocks.append(np.hstack([np.full((len(tail), 1), first, dtype=np.int64), tail]))
        offset += size
        if offset >= stop:
            break
    return np.vstack(blocks)
