"""A search's memory kept under a limit: the open states it forgets, and the certificate that counts them.

At m >= 5 a search's memory is its open states: an open-list entry (48 bytes) and a row of nodes
(4 bytes a finger) each, and the children waiting in the branch and bound of the states that
have one under way (:mod:`ogcp.planner.search.refine`), counted by :mod:`ogcp.planner.search.storage`.
Past its limit a search forgets the open states of the largest keys (:func:`forget_threshold`),
which A* would pop last. A forgotten state's lower bound of f still bounds the grasps below it,
so the certificate stays sound, and the search stays exact while its next key is no larger
than the smallest forgotten one (:meth:`Forgetting.forget`); past that it stops with status
``memory``. Forgetting costs nothing where the optimum lies below that key, which holds
whenever the best grasp found beats every forgotten state.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.arrays import GROWTH
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.refine import PARTIAL, ChildRefinement
from ogcp.planner.search.storage import IdPool, WaitingStore

#: Bytes of one open-list entry (:class:`ogcp.planner.search.open_list.OpenList`).
ENTRY_BYTES = 48
#: Share of the limit a search keeps once it has forgotten states: room to grow before the
#: next forgetting, which passes over every open entry twice.
FORGET_TO = 0.75
#: [s] Least time between two purges of the open list (each costs O(open states)).
PURGE_SECONDS = 10.0
#: Bins of keys by which a search past its limit weighs its open states (a histogram in one
#: compiled pass instead of sorting millions of keys, which took as much memory as the keys again).
FORGET_BINS = 1 << 14
#: [bytes] What a search process holds beside its open states: the interpreter and its
#: libraries (about 270 MiB), the tree's support vectors, the table of children's bounds, the
#: Q1 cache and the heap's slack. At 1.5 GiB for amphora m = 6 in two processes (1000 contacts)
#: 384 MiB left the peak at 1551 MiB, 1 % over the limit; 448 MiB at 1450 MiB.
PROCESS_BYTES = 448 * 2**20
#: [bytes] The least memory a search (or part) may give its open states.
MIN_STATES_BYTES = 64 * 2**20


def states_budget(limit_gib: float | None, parts: int) -> float | None:
    """Bytes each part of a search may give its open states under a limit on the whole search.

    Args:
        limit_gib: Most memory of the search, all its processes together [GiB]; None: unlimited.
        parts: Processes the search is dealt to.

    Raises:
        OgcpError: When the limit leaves a part less than :data:`MIN_STATES_BYTES`.
    """
    if limit_gib is None:
        return None
    budget = limit_gib * 2**30 / parts - PROCESS_BYTES
    if budget < MIN_STATES_BYTES:
        least = parts * (PROCESS_BYTES + MIN_STATES_BYTES) / 2**30
        raise OgcpError(
            f"memory_limit {limit_gib:g} GiB is too small for a search in {parts} process(es): "
            f"give at least {least:g} GiB"
        )
    return budget


def reserved_bytes(entries: int, rows: int, m: int, waiting: int) -> float:
    """Memory a search's states may take before its arrays grow again [bytes]: its open-list
    entries' and state rows' bytes times :data:`ogcp.planner.infra.arrays.GROWTH` (the size of an
    array after its next growth) plus the waiting children's."""
    return GROWTH * (entries * ENTRY_BYTES + rows * 4 * m) + waiting


def forget_threshold(edges: NDArray[np.float64], weights: NDArray[np.float64], excess: float) -> float:
    """The key from which the open entries of the largest keys free at least ``excess`` bytes.

    Args:
        edges: Edges of bins of keys, ascending, shape (bins + 1,)
            (:meth:`ogcp.planner.search.open_list.OpenList.key_weights`).
        weights: What forgetting the entries of each bin frees [bytes], shape (bins,).
        excess: Bytes to free.

    Returns:
        The lower edge of the highest bin such that the entries from it up free at least
        ``excess`` (every entry of that bin goes); the smallest key when all must go, inf when
        none need to.
    """
    if excess <= 0 or not len(weights):
        return math.inf
    freed = np.cumsum(weights[::-1])
    top = min(int(np.searchsorted(freed, excess)), len(weights) - 1)
    return float(edges[len(weights) - 1 - top])


class Forgetting(ChildRefinement):
    """Open states past a memory limit forgotten, and the certificate that counts them (a base
    of :class:`ogcp.planner.search.best_first.Search`, which provides the open list and the cutoff).

    Attributes:
        memory_limit: Most bytes the open states may take; None: unlimited.
        forgotten_key: The smallest key of the states forgotten (inf: none that could hold a
            grasp better than the best one found).
        forgotten_lower: Their smallest lower bound of f [-].
        forgotten: States forgotten so far.
        cutoff: States whose lower bound of f exceeds this are dropped [-].
    """

    memory_limit: float | None
    forgotten_key: float
    forgotten_lower: float
    forgotten: int
    cutoff: float
    dropped: int
    _ids: IdPool
    _pending: WaitingStore
    _purged: tuple[float, float]

    def lower_cutoff(self, cutoff: float) -> None:
        """Drop what a better grasp's cost (plus the margin) beats from now on, forgotten states too."""
        self.cutoff = min(self.cutoff, cutoff)
        if self.forgotten_lower > self.cutoff:  # every forgotten grasp is beaten: none is missed
            self.forgotten_key = self.forgotten_lower = math.inf

    def purge(self, open_list: OpenList, now: float) -> None:
        """Drop the open states past a cutoff that fell since the last purge (see :meth:`push`),
        at most every :data:`PURGE_SECONDS`: the entries made before a better grasp was found."""
        cutoff, last = self._purged
        if not (self.cutoff < cutoff and now >= last + PURGE_SECONDS):
            return
        self._purged = (self.cutoff, now)
        idents, stages = open_list.purge(self.cutoff)
        self.dropped += len(idents)
        for ident in idents[stages >= PARTIAL].tolist():
            self._pending.take(ident)
        self._ids.give_many(idents)

    def forget(self, open_list: OpenList, keep: int) -> None:
        """Past :attr:`memory_limit`, forget the open states of the largest keys, down to
        :data:`FORGET_TO` of the limit (see the module docstring).

        Their smallest key and lower bound of f are kept: the search stops (status ``memory``)
        before it pops a larger key, and the certificate counts the lower bound. The incumbent's
        state (or the state whose branch and bound found it) is never forgotten.

        Args:
            open_list: The open states.
            keep: The id of the state never to forget (-1: none).
        """
        limit = self.memory_limit
        if limit is None:
            return
        waiting = self._pending
        reserved = reserved_bytes(len(open_list), self._ids.high, self.m, waiting.nbytes)
        if reserved <= limit:
            return
        # A waiting record of average size per state with a branch and bound under way.
        extra = waiting.nbytes / max(len(waiting), 1)
        edges, weights = open_list.key_weights(FORGET_BINS, GROWTH * ENTRY_BYTES, PARTIAL, extra)
        threshold = forget_threshold(edges, weights, reserved - FORGET_TO * limit)
        idents, stages, key, lowest = open_list.forget(threshold, keep)
        for ident in idents[stages >= PARTIAL].tolist():
            waiting.take(ident)
        self._ids.give_many(idents)
        self.forgotten += len(idents)
        self.forgotten_key = min(self.forgotten_key, key)
        self.forgotten_lower = min(self.forgotten_lower, lowest)

    def frontier(self, open_list: OpenList) -> float:
        """The smallest key of the open and forgotten states (inf when none)."""
        return min(open_list.first_key(), self.forgotten_key)

    def lowest_lower(self, open_list: OpenList) -> float:
        """The smallest lower bound of f of the open and forgotten states (inf when none)."""
        return min(open_list.lowest_lower(), self.forgotten_lower)
