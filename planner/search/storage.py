"""What a search holds by state id: recycled ids, and the waiting children of branches and bounds.

Both are counted for :mod:`ogcp.planner.search.memory`: :class:`WaitingStore` the bytes of the children
waiting in the branch and bound of each state that has one under way
(:mod:`ogcp.planner.search.refine`), :class:`IdPool` the rows of states in use, which it keeps from
growing with every state ever created by handing the ids of dead states out again.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.arrays import grow_rows

#: A state's waiting children: one packed record (the compiled branch and bound) or a tuple of
#: arrays (the Python one); see :data:`ogcp.planner.search.refine.Waiting`.
Waiting = NDArray[np.uint8] | tuple[NDArray[Any], ...]
#: [bytes] What a waiting record costs beside its arrays' data, per array: its object and a
#: share of the dictionary slot (200 k records of one 768-byte array each took 228 bytes a
#: record of resident memory beyond their data).
WAITING_OVERHEAD = 120


def waiting_bytes(waiting: Waiting) -> int:
    """Bytes a state's waiting children hold (either form of :data:`ogcp.planner.search.refine.Waiting`)."""
    if isinstance(waiting, np.ndarray):
        return waiting.nbytes + 2 * WAITING_OVERHEAD
    return sum(a.nbytes for a in waiting) + (len(waiting) + 1) * WAITING_OVERHEAD


class WaitingStore:
    """The children waiting in states' branches and bounds, by state id, with their bytes counted.

    Attributes:
        nbytes: Bytes of every record held (:func:`waiting_bytes`).
    """

    def __init__(self) -> None:
        self._records: dict[int, Waiting] = {}
        self.nbytes = 0

    def __len__(self) -> int:
        return len(self._records)

    def __bool__(self) -> bool:
        return bool(self._records)

    def items(self) -> Iterator[tuple[int, Waiting]]:
        return iter(self._records.items())

    def put(self, ident: int, waiting: Waiting) -> None:
        """Hold a state's waiting children (replacing any it had)."""
        self.take(ident)
        self._records[ident] = waiting
        self.nbytes += waiting_bytes(waiting)

    def get(self, ident: int) -> Waiting | None:
        return self._records.get(ident)

    def take(self, ident: int) -> Waiting | None:
        """Remove and return a state's waiting children (None: it had none)."""
        waiting = self._records.pop(ident, None)
        if waiting is not None:
            self.nbytes -= waiting_bytes(waiting)
        return waiting


class IdPool:
    """State ids: new ones in order, and, when recycling, those of dead states first.

    A state is dead once it was expanded, dropped or forgotten: nothing refers to its id any
    more, and the row it held serves the next state. Recycling is off where a search records
    its tree, whose ids number the states in creation order.

    Args:
        recycle: Hand out dead states' ids again.

    Attributes:
        high: One more than the largest id handed out: the rows in use.
    """

    def __init__(self, recycle: bool) -> None:
        self.recycle = recycle
        self.high = 1  # the root is 0
        self._free = np.zeros(1024, dtype=np.int64)
        self._count = 0

    def take(self) -> int:
        """An id for a new state."""
        if self._count:
            self._count -= 1
            return int(self._free[self._count])
        ident = self.high
        self.high += 1
        return ident

    def take_many(self, count: int) -> NDArray[np.int64]:
        """Ids for ``count`` new states: those ``count`` calls of :meth:`take` would give, in order."""
        reused = min(count, self._count)
        ids = np.empty(count, dtype=np.int64)
        ids[:reused] = self._free[self._count - reused : self._count][::-1]
        self._count -= reused
        ids[reused:] = np.arange(self.high, self.high + count - reused)
        self.high += count - reused
        return ids

    def give(self, ident: int) -> None:
        """Return a dead state's id."""
        if not self.recycle:
            return
        if self._count == len(self._free):
            grow_rows(self._free, self._count + 1)
        self._free[self._count] = ident
        self._count += 1

    def give_many(self, idents: NDArray[np.int64]) -> None:
        """Return dead states' ids."""
        if not self.recycle or not len(idents):
            return
        end = self._count + len(idents)
        if end > len(self._free):
            grow_rows(self._free, end)
        self._free[self._count : end] = idents
        self._count = end
