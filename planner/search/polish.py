"""Local search for good grasps while a search runs: an early cutoff and better stopped results.

A best-first search at m >= 5 evaluates its first grasps late, and far from the best
(amphora, 1000 contacts, m = 5: none after 30 s, 0.18 after two minutes, against an optimum of
0.207). Moving one finger to any other contact, or two fingers to contacts near theirs, and
keeping each move that raises Q1, climbs from the best of a few thousand random grasps to
within a few per cent of the optimum in seconds. The grasp found serves the search three
ways: states whose bounds it beats are dropped (:attr:`ogcp.planner.search.best_first.Search.cutoff`),
parts of a search on several cores stop sooner, and a stopped search returns it. It never
proves anything: optimality stays the search's own certificate.

The climb reads nothing of the search (its own Q1 of whole grasps, its own random numbers), so
a search's tree, expansions and finished result are the same with it or without it.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.constraints import Constraint, accepts_many
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel import default_directions, support_table
from ogcp.planner.grasp.quality import exact_q1_batch

#: Contacts near each contact that a pair move may put a finger on.
NEIGHBOURS = 12
#: Random grasps the climb starts from the best of, when the search has none yet.
RANDOM_STARTS = 4096
#: Sets of random grasps in a row without a valid one in force closure after which climbing stops.
BARREN = 4
#: Grasps evaluated at once: a chunk's time is where a deadline can stop the climb.
CHUNK = 256
#: Kinds of candidate sets, in the order a climb tries them from a grasp.
RANDOM, SINGLE, PAIR = 0, 1, 2

Grasp = tuple[int, ...]


class Polisher:
    """Hill climbing over the grasps of one contact set, under the search's constraints.

    Args:
        contacts: The contact set C.
        m: Number of fingers.
        constraints: Grasp constraints, distinct contacts included; each must accept or
            reject a grasp whatever the order of its contacts.
        seed: Seed of the random starting grasps.
        stream: Number of this climber's own random stream (one per part of a search).
        neighbours: Nearby contacts per contact for pair moves (by position, scaled by the
            contact set's extent, and by normal).

    Attributes:
        evaluations: Grasps whose Q1 (or a bound below the best so far) was computed.
        seconds: Time spent climbing [s].
    """

    def __init__(
        self,
        contacts: ContactSet,
        m: int,
        constraints: list[Constraint],
        seed: int,
        stream: int = 0,
        neighbours: int = NEIGHBOURS,
    ) -> None:
        self.contacts = contacts
        self.m = m
        self.constraints = constraints
        self.neighbours = neighbours
        self.evaluations = 0
        self.seconds = 0.0
        self._table: NDArray[np.float64] | None = None
        self._near: NDArray[np.intp] | None = None
        self._rng = np.random.default_rng([seed, 0x504F4C, stream])  # the search draws none of these
        self._best: tuple[Grasp, float] = ((), 0.0)
        # Where the climb stands: its grasp and Q1, the kind of candidates tried and the next
        # chunk of them, so a climb cut short by its deadline goes on where it stopped.
        self._at: Grasp = ()
        self._q = 0.0
        self._kind = RANDOM
        self._cursor = 0
        self._candidates: NDArray[np.int64] | None = None
        self._barren = 0  # sets of random grasps in a row without a valid one in force closure

    def climb(
        self, start: tuple[Grasp, float] | None, deadline: float, chunks: int | None = None
    ) -> tuple[Grasp, float, bool]:
        """Climb while the clock allows: from ``start`` while moves raise Q1, then from the
        best of fresh random grasps, again and again (random restarts).

        Args:
            start: A valid grasp's contact indices, shape (m,), and its exact Q1 [-]: the
                climb restarts from it when it beats the best grasp reached so far. None:
                go on where the last call stopped.
            deadline: ``time.perf_counter()`` reading after which no new chunk starts [s].
            chunks: Most chunks of :data:`CHUNK` candidates to evaluate in this call, or None:
                as many as the deadline allows. A count makes the climb the same on any machine.

        Returns:
            (grasp, Q1 [-], done): the best grasp reached so far, sorted, with the exact value
            every method reports for it (``()`` and 0 while none was valid and in force
            closure); whether climbing is pointless (:data:`BARREN` sets of random grasps in
            a row held none).
        """
        began = time.perf_counter()
        if start is not None and start[1] > self._best[1]:
            grasp = tuple(sorted(int(c) for c in start[0]))
            self._best = (grasp, start[1])
            self._restart(grasp, start[1])
            self._barren = 0
        try:
            left = math.inf if chunks is None else chunks
            while time.perf_counter() < deadline and self._barren < BARREN and left > 0:
                if self._candidates is None:
                    self._candidates = self._moves()
                if self._cursor >= len(self._candidates):
                    if self._kind == RANDOM:
                        self._barren += 1
                    # Singles done: pairs; pairs done (a local optimum) or no valid random grasp: new random grasps.
                    self._kind = PAIR if self._kind == SINGLE else RANDOM
                    self._cursor, self._candidates = 0, None
                    if self._kind == RANDOM:
                        self._q = 0.0
                    continue
                chunk = self._candidates[self._cursor : self._cursor + CHUNK]
                self._cursor += CHUNK
                left -= 1
                found = self._best_of(chunk)
                if found is not None:
                    self._barren = 0
                    self._restart(*found)
                    if found[1] > self._best[1]:
                        self._best = found
            return (*self._best, self._barren >= BARREN)
        finally:
            self.seconds += time.perf_counter() - began

    def _restart(self, grasp: Grasp, q: float) -> None:
        self._at, self._q = grasp, q
        self._kind, self._cursor, self._candidates = SINGLE, 0, None

    def _moves(self) -> NDArray[np.int64]:
        """The candidates of the current kind, rows sorted, each grasp once, shape (g, m)."""
        n, m = len(self.contacts), self.m
        if self._kind == RANDOM:
            grasps = self._rng.integers(0, n, size=(RANDOM_STARTS, m))
        elif self._kind == SINGLE:
            # Every grasp with one finger moved to any contact.
            at = np.array(self._at, dtype=np.int64)
            grasps = np.repeat(at[None], m * n, axis=0)
            for finger in range(m):
                grasps[finger * n : (finger + 1) * n, finger] = np.arange(n)
        else:
            # Every grasp with two fingers moved to contacts near theirs.
            at = np.array(self._at, dtype=np.int64)
            near = self._nearby()
            rows = []
            for a, b in itertools.combinations(range(m), 2):
                pairs = np.array(list(itertools.product(near[at[a]], near[at[b]])), dtype=np.int64)
                moved = np.repeat(at[None], len(pairs), axis=0)
                moved[:, a], moved[:, b] = pairs[:, 0], pairs[:, 1]
                rows.append(moved)
            grasps = np.concatenate(rows) if rows else np.empty((0, m), dtype=np.int64)
        # Each grasp once, in the order drawn: the first chunks of sorted rows would all start
        # at the lowest contacts.
        ordered = np.sort(grasps, axis=1)
        ordered = ordered[(ordered[:, 1:] != ordered[:, :-1]).all(axis=1)]
        _, first = np.unique(ordered, axis=0, return_index=True)
        return ordered[np.sort(first)]

    def _best_of(self, chunk: NDArray[np.int64]) -> tuple[Grasp, float] | None:
        """The best valid grasp of a chunk above the climb's Q1, or None."""
        if self._table is None:
            self._table = support_table(self.contacts.wrenches, default_directions())
        # Values below the cut may be bounds; those above it are exact.
        values, _ = exact_q1_batch(self.contacts.wrenches, chunk, self._table, self._q)
        self.evaluations += len(chunk)
        better = np.flatnonzero(values > self._q)
        if not len(better):
            return None
        better = better[np.argsort(-values[better], kind="stable")]
        valid = np.ones(len(better), dtype=bool)
        for constraint in self.constraints:
            valid &= accepts_many(constraint, chunk[better], self.contacts)
        if not valid.any():
            return None
        i = int(better[np.argmax(valid)])
        return tuple(int(c) for c in chunk[i]), float(values[i])

    def _nearby(self) -> NDArray[np.intp]:
        """The nearest contacts of each contact (itself excluded), shape (n, k)."""
        if self._near is None:
            from scipy.spatial import cKDTree  # scipy.spatial costs ogcp's CLI start-up a tenth of a second

            positions = self.contacts.positions
            extent = float(np.ptp(positions, axis=0).max()) or 1.0
            features = np.hstack([positions / extent, self.contacts.normals])
            k = min(self.neighbours + 1, len(positions))
            _, near = cKDTree(features).query(features, k=k)
            self._near = np.asarray(near, dtype=np.intp).reshape(len(positions), k)[:, 1:]
        return self._near
