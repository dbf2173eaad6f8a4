"""Is any point within a distance of an axis-aligned box? Answered from leaves of points, not every point.

The reachability constraint asks this of every state a search expands (:meth:`HandReachability.admits`):
a box of pair codes that a super-contact can take, against thousands of sampled codes. Points are
split once into leaves of at most :data:`LEAF_SIZE` by median cuts along the widest dimension; a
box is compared with each leaf's bounding box first, and only the points of leaves that come within
the distance are compared one by one. The answer is the same as comparing every point.

The comparisons, and the boxes of a search state (:func:`pair_bounds`, :func:`boxes_within`), are
compiled: in numpy they took about 1 ms per state, three quarters of a Shadow hand search.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel.jit import cached_njit

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
        self.points = np.ascontiguousarray(np.concatenate([points[leaf] for leaf in leaves]))
        sizes = np.array([len(leaf) for leaf in leaves], dtype=np.int64)
        self.low = np.array([points[leaf].min(axis=0) for leaf in leaves])
        self.high = np.array([points[leaf].max(axis=0) for leaf in leaves])
        #: Leaf k holds points ``starts[k]:starts[k + 1]``.
        self.starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)

    def any_within(self, low: NDArray[np.float64], high: NDArray[np.float64], radius: float) -> bool:
        """Whether some point lies within ``radius`` of some box ``[low[b], high[b]]``.

        Args:
            low: Boxes' lower corners, shape (B, D).
            high: Boxes' upper corners, shape (B, D).
            radius: The distance (Euclidean, >= 0).
        """
        low = np.ascontiguousarray(np.atleast_2d(low), dtype=np.float64)
        high = np.ascontiguousarray(np.atleast_2d(high), dtype=np.float64)
        for box in range(len(low)):
            if _box_within(low[box], high[box], radius * radius, self.low, self.high, self.points, self.starts):
                return True
        return False


@cached_njit(nogil=True)
def _box_within(
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    radius2: float,
    leaf_low: NDArray[np.float64],
    leaf_high: NDArray[np.float64],
    points: NDArray[np.float64],
    starts: NDArray[np.int64],
) -> bool:  # pragma: no cover - compiled
    """Whether a point of the index lies within sqrt(``radius2``) of the box ``[low, high]``."""
    dims = low.shape[0]
    for leaf in range(leaf_low.shape[0]):
        gap2 = 0.0
        for d in range(dims):
            g = max(low[d] - leaf_high[leaf, d], 0.0) + max(leaf_low[leaf, d] - high[d], 0.0)
            gap2 += g * g
            if gap2 > radius2:
                break
        if gap2 > radius2:
            continue
        for p in range(starts[leaf], starts[leaf + 1]):
            gap2 = 0.0
            for d in range(dims):
                g = max(low[d] - points[p, d], 0.0) + max(points[p, d] - high[d], 0.0)
                gap2 += g * g
                if gap2 > radius2:
                    break
            if gap2 <= radius2:
                return True
    return False


@cached_njit(nogil=True)
def pair_bounds(
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    members: NDArray[np.int64],
    offsets: NDArray[np.int64],
) -> NDArray[np.float64]:  # pragma: no cover - compiled
    """The range of each pair invariant over two super-contacts, shape (m, m, 2, 4).

    ``[x, y, 0]`` and ``[x, y, 1]`` are the least and greatest, over a contact i of super-contact
    x and a contact j of y (x != y; ``members[offsets[x]:offsets[x + 1]]``), of the distance
    ``|p_j - p_i|``, the normal difference ``|n_i - n_j|`` and both normals' cosines with
    ``u = (p_j - p_i) / |p_j - p_i|`` (the codes of :func:`~ogcp.planner.hands.reachability.pair_code`).
    """
    m = offsets.shape[0] - 1
    bounds = np.zeros((m, m, 2, 4))
    for x in range(m):
        for y in range(m):
            if x == y:
                continue
            for d in range(4):
                bounds[x, y, 0, d] = math.inf
                bounds[x, y, 1, d] = -math.inf
            for a in range(offsets[x], offsets[x + 1]):
                i = members[a]
                for b in range(offsets[y], offsets[y + 1]):
                    j = members[b]
                    l0 = positions[j, 0] - positions[i, 0]
                    l1 = positions[j, 1] - positions[i, 1]
                    l2 = positions[j, 2] - positions[i, 2]
                    length = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
                    inverse = 1.0 / max(length, 1e-12)
                    e0 = normals[i, 0] - normals[j, 0]
                    e1 = normals[i, 1] - normals[j, 1]
                    e2 = normals[i, 2] - normals[j, 2]
                    values = (
                        length,
                        math.sqrt(e0 * e0 + e1 * e1 + e2 * e2),
                        (normals[i, 0] * l0 + normals[i, 1] * l1 + normals[i, 2] * l2) * inverse,
                        (normals[j, 0] * l0 + normals[j, 1] * l1 + normals[j, 2] * l2) * inverse,
                    )
                    for d in range(4):
                        bounds[x, y, 0, d] = min(bounds[x, y, 0, d], values[d])
                        bounds[x, y, 1, d] = max(bounds[x, y, 1, d], values[d])
    return bounds


@cached_njit(nogil=True)
def boxes_within(
    bounds: NDArray[np.float64],
    assignments: NDArray[np.int64],
    pairs: NDArray[np.int64],
    scale: NDArray[np.float64],
    radius2: float,
    spans: NDArray[np.float64],
    span_scale: float,
    leaf_low: NDArray[np.float64],
    leaf_high: NDArray[np.float64],
    points: NDArray[np.float64],
    starts: NDArray[np.int64],
) -> bool:  # pragma: no cover - compiled
    """Whether some assignment's box of codes comes within sqrt(``radius2``) of a point of the index.

    Assignment ``a`` puts super-contact ``assignments[a, f]`` under finger f; its box spans, for
    each finger pair ``pairs[k] = (f, g)``, the invariants' ranges ``bounds[x, y]`` of those
    super-contacts, divided by ``scale`` (4 values per pair). The least distance of a pair's
    interval of pad distances from that pair's span ``spans[k]`` ([m], low and high), divided by
    ``span_scale`` [m], counts as a further dimension of the code's distance (the residual of
    :func:`~ogcp.planner.hands.sampled_model.residuals`).
    """
    dims = 4 * pairs.shape[0]
    low = np.empty(dims)
    high = np.empty(dims)
    for a in range(assignments.shape[0]):
        beyond2 = 0.0
        for k in range(pairs.shape[0]):
            x = assignments[a, pairs[k, 0]]
            y = assignments[a, pairs[k, 1]]
            for d in range(4):
                low[4 * k + d] = bounds[x, y, 0, d] / scale[4 * k + d]
                high[4 * k + d] = bounds[x, y, 1, d] / scale[4 * k + d]
            g = (max(spans[k, 0] - bounds[x, y, 1, 0], 0.0) + max(bounds[x, y, 0, 0] - spans[k, 1], 0.0)) / span_scale
            beyond2 += g * g
        if beyond2 <= radius2 and _box_within(low, high, radius2 - beyond2, leaf_low, leaf_high, points, starts):
            return True
    return False
