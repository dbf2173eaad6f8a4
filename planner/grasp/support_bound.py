"""Cheap upper bounds on Q1 from support values along a growing set of directions.

For any unit direction u, Q1(S) <= h_S(u) = max_{w in W(S)} u.w (the ball of radius Q1
fits inside the hull, so the hull reaches at least that far along u). Hence
``U_D(S) = min_{u in D} h_S(u)`` is an upper bound of Q1 for every direction set D, it is
monotone in S, and a negative value proves the origin lies outside the hull (Q1 = 0).

Support values are tabulated per contact, so the vector of a super-contact is a max over
its members and the bound of a union of super-contacts is an elementwise max over their
vectors: microseconds instead of a hull. The set D starts with the 12 signed axes and
seeded random directions and grows with the weakest-wrench directions certified by exact
Q1 evaluations, which makes the bounds tight where the search is working.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Vector = NDArray[np.float64]


class SupportBound:
    """Support-function upper bounds of Q1 for subsets of one contact set.

    Args:
        wrenches: Cone-edge wrenches of every contact, shape (n, k, 6).
        seed: Seed of the initial random directions.
        random_directions: Number of initial random directions.
        max_directions: Capacity of the direction set.
    """

    def __init__(
        self, wrenches: NDArray[np.float64], seed: int = 0, random_directions: int = 116, max_directions: int = 640
    ) -> None:
        self._wrenches = wrenches
        self.capacity = max_directions
        self.directions = np.zeros((max_directions, 6))
        self._support = np.zeros((len(wrenches), max_directions))
        self.count = 0
        rng = np.random.default_rng([seed, 6])
        random = rng.normal(size=(random_directions, 6))
        self.add(np.vstack([np.eye(6), -np.eye(6), random / np.linalg.norm(random, axis=1, keepdims=True)]))

    def add(self, directions: NDArray[np.float64]) -> None:
        """Append unit directions (shape (j, 6)) that are not near-duplicates, up to capacity."""
        if self.count >= self.capacity:
            return  # full after a few hundred evaluations; the search calls this after every one
        for u in np.atleast_2d(directions):
            if self.count >= self.capacity or not np.all(np.isfinite(u)):
                return
            if self.count and np.max(self.directions[: self.count] @ u) > 1.0 - 1e-9:
                continue
            self.directions[self.count] = u
            self._support[:, self.count] = np.max(self._wrenches @ u, axis=1)
            self.count += 1

    def vector(self, members: NDArray[np.intp], cached: Vector | None = None) -> Vector:
        """Support vector of a set of contacts over the current directions, shape (count,).

        Args:
            members: Contact indices.
            cached: A vector previously returned for the same members; only the
                directions added since are computed.
        """
        done = 0 if cached is None else len(cached)
        if done == self.count:
            return cached  # type: ignore[return-value]
        fresh = self._support[members, done : self.count].max(axis=0)
        return fresh if cached is None else np.concatenate([cached, fresh])

    def extend(self, members: NDArray[np.intp], row: Vector, done: int) -> None:
        """Write the support of a set of contacts along directions ``done`` to ``count - 1``
        into ``row[done:count]`` (the directions before are the caller's, already there)."""
        row[done : self.count] = self._support[members, done : self.count].max(axis=0)

    def facet_bound(
        self, union: NDArray[np.uint8], vectors: Sequence[Vector], first: int, last: int
    ) -> tuple[float, NDArray[np.float64]]:
        """The best facet bound of Q1 of a union of contacts and the unit direction whose
        support it is (:func:`~ogcp.planner.grasp.kernel.ray_bound.union_facet_bound`): ([-], shape (6,)).

        Args:
            union: The union's membership flags, packed (``numpy.packbits``).
            vectors: Support vectors of the super-contacts whose union it is (their common
                directions rank the starts).
            first: Rank (lowest support first) of the first direction that starts a facet bound.
            last: One past the rank of the last.
        """
        from ogcp.planner.grasp.kernel.ray_bound import union_facet_bound

        length = min(len(v) for v in vectors)
        rows = np.stack([v[:length] for v in vectors])
        bound, normal = union_facet_bound(self._wrenches, union, rows, self.directions, length, first, last)
        return float(bound), normal

    def facet_bound_along(self, union: NDArray[np.uint8], start: int) -> tuple[float, NDArray[np.float64]]:
        """The facet bound of Q1 of a union of contacts from direction ``start`` of D and the unit
        direction whose support it is (:func:`~ogcp.planner.grasp.kernel.ray_bound.union_facet_bound_along`):
        ([-], shape (6,))."""
        from ogcp.planner.grasp.kernel.ray_bound import union_facet_bound_along

        bound, normal = union_facet_bound_along(self._wrenches, union, self.directions[start])
        return float(bound), normal

    def lowest_directions(self, vectors: Sequence[Vector], count: int) -> NDArray[np.float64]:
        """The ``count`` directions along which the union's support is smallest, shape (count, 6)."""
        joint = SupportBound.joint(vectors)
        take = min(count, len(joint))
        return self.directions[np.argpartition(joint, take - 1)[:take]]

    @staticmethod
    def lowest(vectors: Sequence[Vector]) -> tuple[float, int]:
        """:meth:`bound` and the direction of D that gives it (the first of equal ones): ([-], index)."""
        joint = SupportBound.joint(vectors)
        index = int(joint.argmin())
        return float(joint[index]), index

    @staticmethod
    def bound(vectors: Sequence[Vector]) -> float:
        """Upper bound of Q1 of the union of sets with the given support vectors [-].

        Vectors may differ in length (computed at different times); the common prefix of
        directions is used, which is still a valid bound.
        """
        return float(SupportBound.joint(vectors).min())

    @staticmethod
    def joint(vectors: Sequence[Vector]) -> Vector:
        """Support vector of the union of sets with the given vectors, on their common directions."""
        length = min(len(v) for v in vectors)
        joint = vectors[0][:length]
        for v in vectors[1:]:  # pairwise maxima: no stacked copy (this is the search's inner loop)
            joint = np.maximum(joint, v[:length])
        return joint
