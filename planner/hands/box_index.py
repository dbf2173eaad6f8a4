"""Is any point within a distance of an axis-aligned box? Answered from leaves of points, not every point.

The reachability constraint asks this of every state a search expands (:meth:`HandReachability.admits`):
a box of pair codes that a super-contact can take, against thousands of sampled codes. Points are
split once into leaves of at most :data:`LEAF_SIZE` by median cuts along the widest dimension; a
box is compared with each leaf's bounding box first, and only the points of leaves that come within
the distance are compared one by one. The answer is the same as comparing every point.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Most points in one leaf.
LEAF_SIZE = 64


class BoxIndex:
    """Points split into leaves with bounding boxes.

    Args:
        points: The points, shape (N, D), N >= 1.
    """

    def __init__(self, points: NDArray[np.float64]) -> None:
        points = np.asarray(points, dtype=float)
        order = np.arange(len(points))
        pending, leaves = [order], []
        while pending:
            members = pending.pop()
            if len(members) <= LEAF_SIZE:
                leaves.append(members)
                continue
            values = points[members]
            axis = int(np.argmax(values.max(axis=0) - values.min(axis=0)))
            ranked = members[np.argsort(values[:, axis], kind="stable")]
            half = len(ranked) // 2
            pending.extend([ranked[:half], ranked[half:]])
        self.points = np.concatenate([points[leaf] for leaf in leaves])
        sizes = np.array([len(leaf) for leaf in leaves])
        self.low = np.array([points[leaf].min(axis=0) for leaf in leaves])
        self.high = np.array([points[leaf].max(axis=0) for leaf in leaves])
        self.leaf_of = np.repeat(np.arange(len(leaves)), sizes)

    def any_within(self, low: NDArray[np.float64], high: NDArray[np.float64], radius: float) -> bool:
        """Whether some point lies within ``radius`` of some box ``[low[b], high[b]]``.

        Args:
            low: Boxes' lower corners, shape (B, D).
            high: Boxes' upper corners, shape (B, D).
            radius: The distance (Euclidean, >= 0).
        """
        low, high = np.atleast_2d(low), np.atleast_2d(high)
        outside = np.maximum(low[:, None, :] - self.high[None], 0.0) + np.maximum(
            self.low[None] - high[:, None, :], 0.0
        )
        near = np.einsum("bld,bld->bl", outside, outside) <= radius**2
        for box in np.flatnonzero(near.any(axis=1)):
            points = self.points[near[box][self.leaf_of]]
            gap = np.maximum(low[box] - points, 0.0) + np.maximum(points - high[box], 0.0)
            if np.min(np.einsum("ij,ij->i", gap, gap)) <= radius**2:
                return True
        return False
