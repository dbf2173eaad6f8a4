"""Grasps dealt to the parts of one search, a part per process (see :mod:`ogcp.planner.search.parts`).

A state's parent is the tuple of its nodes' parents, so the states at one depth root disjoint
subtrees that hold every grasp below that depth. Dealing those states to parts by a hash of
their nodes splits the grasps into disjoint parts; the few states above the depth are searched
by every part. Each part publishes its best exact Q1 and its certified bound in shared memory,
so that a part stops once nothing left in it can beat a grasp another part found.
"""

from __future__ import annotations

import math
import mmap
import os
import zlib
from dataclasses import dataclass

import numpy as np

#: Depth of the states dealt to parts: about 10,000 states at m = 5 on 1000 contacts (amphora),
#: enough for an even deal, with about 500 expansions above it that every part repeats.
DEAL_DEPTH = 4


def owner(firsts: list[int], parts: int) -> int:
    """The part that owns a state at :data:`DEAL_DEPTH`, by the first contact of each node.

    Node ids number nodes in the order a process splits them, which differs between parts;
    a node's first (smallest) contact does not, and tells it from every other node a state
    at that depth can hold (they are disjoint). A crc32, not Python's hash: the same in
    every process.
    """
    return zlib.crc32(np.array(sorted(firsts), dtype=np.int64).tobytes()) % parts


class PartDone(Exception):
    """A part ended without a grasp of its own: none beats ``bound`` [-] (0: it holds no valid grasp)."""

    def __init__(self, bound: float) -> None:
        super().__init__(f"no grasp of this part beats {bound:.6f}")
        self.bound = bound


class Board:
    """Values every part reads and writes: a small file mapped into each process's memory.

    Doubles: a stop flag, then each part's best exact Q1 (-inf before its first), then each
    part's latest certified bound (+inf before its first report). A part writes its own slots
    only, so no lock is needed: a reader may see a value a moment late, never a torn one (an
    aligned double is written at once).

    Args:
        path: The file (created by :meth:`create`).
        parts: Number of parts.
    """

    def __init__(self, path: str | os.PathLike[str], parts: int) -> None:
        self.parts = parts
        with open(path, "r+b") as handle:
            self._map = mmap.mmap(handle.fileno(), 8 * (1 + 2 * parts))
        self.values = np.frombuffer(self._map, dtype=np.float64)
        self.bests = self.values[1 : 1 + parts]
        self.bounds = self.values[1 + parts :]

    @staticmethod
    def create(path: str | os.PathLike[str], parts: int) -> Board:
        """Write a fresh board to ``path`` and map it."""
        initial = np.concatenate([[0.0], np.full(parts, -math.inf), np.full(parts, math.inf)])
        with open(path, "wb") as handle:
            handle.write(initial.tobytes())
        return Board(path, parts)

    def is_set(self) -> bool:
        """Whether the parts are asked to stop (a ``threading.Event``'s test, for the search)."""
        return bool(self.values[0] != 0.0)

    def set(self) -> None:
        """Ask every part to stop."""
        self.values[0] = 1.0

    def best(self) -> float:
        """The best exact Q1 any part has found [-] (-inf before the first)."""
        return float(self.bests.max())

    def bound(self) -> float:
        """The certified bound over all parts [-] (+inf until each has reported)."""
        return float(self.bounds.max())


@dataclass(frozen=True)
class Part:
    """One part of a search: which states it keeps, and the board all parts share.

    Attributes:
        rank: This part, 0 <= rank < parts.
        board: The shared values.
        depth: Depth of the dealt states.
    """

    rank: int
    board: Board
    depth: int = DEAL_DEPTH

    def owns(self, firsts: list[int]) -> bool:
        """Whether a state at the dealt depth, given by its nodes' first contacts, lies in this part.

        States above the depth lie in every part, those below in their ancestor's.
        """
        return owner(firsts, self.board.parts) == self.rank

    def publish(self, q: float) -> None:
        """Share this part's best exact Q1 [-]."""
        bests = self.board.bests
        bests[self.rank] = max(bests[self.rank], q)

    def beaten(self, bound: float) -> bool:
        """Whether a grasp found in some part is at least as good as ``bound`` [-]."""
        return bound <= self.board.best()

    def report(self, bound: float) -> None:
        """Share this part's certified bound [-]."""
        self.board.bounds[self.rank] = bound

    def overall(self) -> tuple[float | None, float]:
        """(best Q1 of all parts or None, certified bound of all parts) [-], for progress reports."""
        best = self.board.best()
        return (None if math.isinf(best) else best), self.board.bound()
