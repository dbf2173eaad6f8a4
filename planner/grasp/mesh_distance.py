"""Exact distance from points to a triangle mesh, and which side of the surface they lie on.

One point-triangle routine serves two callers: :func:`triangle_distances` (all pairs, for
the simulation's small convex parts) and :class:`SurfaceIndex` (nearest surface point of
many points on meshes of 10^4-10^5 faces, for reach-aware contact sampling).

:class:`SurfaceIndex` avoids the all-pairs (n, f) matrix with scipy's ``cKDTree`` over the
triangles' centroids. A triangle whose centroid is at distance ``s`` from a query point and
whose corners lie within ``R`` of its centroid is at least ``s - R`` away, so once an upper
bound ``U`` on the nearest distance is known (from the triangles of the nearest centroids),
only triangles with ``s <= U + R`` can be nearer. Triangles are grouped by ``R`` (each
group's radius at most twice its smallest), one tree per group, so a few large triangles do
not widen the search for the many small ones. Every remaining candidate is measured
exactly, so the result is the exact nearest distance, not an approximation. (trimesh's
``proximity.closest_point`` needs the optional ``rtree`` package, which ogcp does not
depend on.) Measured on a shared 2-core machine (median of 3): building the index takes
0.03 s for 10k faces and 0.25 s for 74k; the nearest points of 5000 fingertip centres (4 % of
the diagonal off the surface) take 0.2 s on 10k faces and 0.3-0.4 s on 42k-74k faces, and of
5000 points spread over 1.5x the bounding box 0.3-0.6 s. The all-pairs matrix would hold
2-4 x 10^8 pairs.

Which side a point lies on comes from the angle-weighted pseudonormal of the surface
feature (face, edge or vertex) that holds its nearest point (Baerentzen and Aanaes, IEEE
TVCG 2005): for a closed, consistently oriented mesh its sign is the exact inside test. It
is local, so on an open mesh it still gives the side of the nearest sheet, and a hole far
away does not flip it the way it flips a ray-parity or winding-number count.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ogcp.planner.grasp.shells import Shells
from ogcp.planner.infra.errors import OgcpError

#: Feature of a triangle that holds the nearest point: its interior, an edge or a corner.
FACE, EDGE_AB, EDGE_BC, EDGE_CA, CORNER_A, CORNER_B, CORNER_C = range(7)
_PAIRS_PER_BLOCK = 200_000  # point-triangle pairs per vectorised block: bounds memory to a few tens of MB
_SLACK = 1e-9  # relative widening of pruning radii, so rounding never prunes the nearest triangle
_MAX_GROUPS = 12  # triangle-size groups; the last one takes every smaller triangle


def _dot(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.einsum("...k,...k->...", u, v)


def _segment(
    p: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance from p to segment a-b and the clipped parameter t of the nearest point (broadcast)."""
    ab = b - a
    length2 = _dot(ab, ab)
    t = _dot(p - a, ab) / np.where(length2 > 0, length2, 1.0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1), t


def _point_triangle(
    p: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64], nearest: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.int8] | None]:
    """Exact distance from points to triangles, broadcast over the leading axes.

    The nearest point is the foot of the perpendicular when the foot lies in the triangle
    (left of every edge, seen along the normal), else the nearest point of the nearest edge.

    Args:
        p: Points, shape (..., 3) [m].
        a: First corners, shape (..., 3) [m]; ``b`` and ``c`` likewise.
        nearest: Also return the nearest points and their features.

    Returns:
        ``(distance (...,) [m], nearest point (..., 3) [m] or None, feature (...,) or None)``,
        the feature one of :data:`FACE` ... :data:`CORNER_C`.
    """
    normal = np.cross(b - a, c - a)
    area2 = np.linalg.norm(normal, axis=-1)
    inside = area2 > 0
    for start, end in ((a, b), (b, c), (c, a)):
        inside = inside & (_dot(np.cross(end - start, p - start), normal) >= 0)
    height = _dot(p - a, normal) / np.where(area2 > 0, area2, 1.0)
    (d_ab, t_ab), (d_bc, t_bc), (d_ca, t_ca) = _segment(p, a, b), _segment(p, b, c), _segment(p, c, a)
    distance = np.where(inside, np.abs(height), np.minimum(np.minimum(d_ab, d_bc), d_ca))
    if not nearest:
        return distance, None, None
    edge = np.argmin(np.stack([d_ab, d_bc, d_ca]), axis=0)
    t = np.choose(edge, [t_ab, t_bc, t_ca])
    start = np.choose(edge[..., None], [a, b, c])
    end = np.choose(edge[..., None], [b, c, a])
    on_edge = start + t[..., None] * (end - start)
    unit = normal / np.where(area2 > 0, area2, 1.0)[..., None]
    point = np.where(inside[..., None], p - height[..., None] * unit, on_edge)
    # A clipped parameter puts the nearest point on a corner: t = 0 at the edge's start
    # corner (index = edge), t = 1 at its end corner (index = edge + 1 mod 3).
    corner = np.where(t <= 0.0, edge, (edge + 1) % 3)
    feature = np.where(inside, FACE, np.where((t <= 0.0) | (t >= 1.0), CORNER_A + corner, EDGE_AB + edge))
    return distance, point, feature.astype(np.int8)


def triangle_distances(points: NDArray[np.float64], triangles: NDArray[np.float64]) -> NDArray[np.float64]:
    """Exact Euclidean distance of every point to every triangle (the all-pairs matrix).

    Suits tens to hundreds of triangles; for whole meshes use :class:`SurfaceIndex`.

    Args:
        points: Query points, shape (n, 3) [m].
        triangles: Triangle corners, shape (f, 3, 3) [m].

    Returns:
        Distances, shape (n, f) [m].
    """
    p = points[:, None, :]
    a, b, c = (triangles[None, :, i, :] for i in range(3))
    return _point_triangle(p, a, b, c, nearest=False)[0]


def nearest_on_triangles(
    points: NDArray[np.float64], triangles: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nearest point of a small triangle set to each query point (all pairs, exact).

    Args:
        points: Query points, shape (n, 3) [m].
        triangles: Triangle corners, shape (f, 3, 3) [m], f >= 1.

    Returns:
        ``(distance (n,) [m], nearest point (n, 3) [m])``.
    """
    p = points[:, None, :]
    a, b, c = (triangles[None, :, i, :] for i in range(3))
    distance, point, _ = _point_triangle(p, a, b, c, nearest=True)
    assert point is not None
    best = np.argmin(distance, axis=1)
    rows = np.arange(len(points))
    return distance[rows, best], point[rows, best]


@dataclass(frozen=True, eq=False)
class Nearest:
    """Nearest surface points of query points.

    Attributes:
        distance: Distance to the surface, shape (n,) [m]; inf where nothing lies within
            the search radius.
        face: Face holding the nearest point, shape (n,); -1 where none was found.
        point: Nearest surface point, shape (n, 3) [m]; NaN where none was found.
        outside: Whether each query point lies on the outer side of the surface, shape (n,)
            (False where none was found or the point is on the surface).
    """

    distance: NDArray[np.float64]
    face: NDArray[np.intp]
    point: NDArray[np.float64]
    outside: NDArray[np.bool_]


def _pseudonormals(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], normals: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Angle-weighted vertex and summed edge pseudonormals, per face corner and face edge.

    Vertices at identical positions count as one, so a mesh loaded without merging (an STL
    read with ``process=False``) still has shared edges and corners.

    Returns:
        ``(corner (f, 3, 3), edge (f, 3, 3))``: the pseudonormal at corner i, and along edge
        i (corner i to corner i+1), of every face; not normalised (only signs are used).
    """
    _, merged = np.unique(vertices, axis=0, return_inverse=True)
    ids = merged.reshape(-1)[faces]
    corners = trimesh.triangles.angles(vertices[faces])  # (f, 3) [rad]
    vertex_sum = np.zeros((int(ids.max()) + 1, 3))
    np.add.at(vertex_sum, ids.reshape(-1), (corners[:, :, None] * normals[:, None, :]).reshape(-1, 3))
    edges = np.sort(np.stack([ids, np.roll(ids, -1, axis=1)], axis=-1), axis=-1).reshape(-1, 2)
    _, edge_id = np.unique(edges, axis=0, return_inverse=True)
    edge_sum = np.zeros((int(edge_id.max()) + 1, 3))
    np.add.at(edge_sum, edge_id.reshape(-1), np.repeat(normals, 3, axis=0))
    return vertex_sum[ids], edge_sum[edge_id.reshape(-1, 3)]


class SurfaceIndex:
    """A triangle mesh prepared for exact nearest-point queries of many points.

    Args:
        mesh: The surface; faces oriented outwards for :attr:`Nearest.outside` to mean
            outside (a mesh with inward faces swaps the sides).

    Raises:
        OgcpError: For a mesh without faces.
    """

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        faces = np.asarray(mesh.faces, dtype=np.int64)
        if faces.ndim != 2 or len(faces) == 0:
            raise OgcpError("cannot measure distance to a mesh without faces")
        self.triangles = vertices[faces]
        self._vertices, self._faces = vertices, faces
        normals = np.cross(self.triangles[:, 1] - self.triangles[:, 0], self.triangles[:, 2] - self.triangles[:, 0])
        lengths = np.linalg.norm(normals, axis=1)
        self.normals = normals / np.where(lengths > 0, lengths, 1.0)[:, None]
        self.corner_normals, self.edge_normals = _pseudonormals(vertices, faces, self.normals)
        self.centroids = self.triangles.mean(axis=1)
        # Each triangle lies within its radius of its centroid; the slack covers rounding.
        radii = np.linalg.norm(self.triangles - self.centroids[:, None], axis=2).max(axis=1)
        self.radii = radii * (1 + _SLACK) + _SLACK * float(np.max(np.abs(self.triangles)))
        # Groups of similar size: group k holds radii in (R_max / 2^(k+1), R_max / 2^k].
        levels = np.floor(np.log2(self.radii.max() / np.maximum(self.radii, 1e-300))).astype(np.int64)
        levels = np.minimum(levels, _MAX_GROUPS - 1)
        self.groups: list[tuple[NDArray[np.intp], cKDTree, float]] = []
        for level in np.unique(levels):
            members = np.flatnonzero(levels == level)
            self.groups.append((members, cKDTree(self.centroids[members]), float(self.radii[members].max())))

    @functools.cached_property
    def shells(self) -> Shells:
        """The mesh's closed shells (a point near one may lie inside another: :meth:`Shells.enclosed`)."""
        return Shells(self._vertices, self._faces)

    def _measure(
        self, query: NDArray[np.intp], faces: NDArray[np.intp], points: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int8]]:
        """Exact distance, nearest point and feature of pairs (point ``query[i]``, face ``faces[i]``)."""
        distance = np.empty(len(query))
        nearest = np.empty((len(query), 3))
        feature = np.empty(len(query), dtype=np.int8)
        for start in range(0, len(query), _PAIRS_PER_BLOCK):
            block = slice(start, start + _PAIRS_PER_BLOCK)
            tri = self.triangles[faces[block]]
            d, q, f = _point_triangle(points[query[block]], tri[:, 0], tri[:, 1], tri[:, 2], nearest=True)
            assert q is not None and f is not None
            distance[block], nearest[block], feature[block] = d, q, f
        return distance, nearest, feature

    def _upper_bounds(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Distance to the triangle of the nearest centroid in each group, minimised: >= the nearest distance."""
        picks = [members[tree.query(points)[1]] for members, tree, _ in self.groups]
        faces = np.concatenate(picks)
        query = np.tile(np.arange(len(points)), len(picks))
        return self._measure(query, faces, points)[0].reshape(len(picks), -1).min(axis=0)

    def nearest(self, points: ArrayLike, max_distance: float | None = None) -> Nearest:
        """Exact nearest surface point of every query point.

        Args:
            points: Query points, shape (n, 3) [m].
            max_distance: Search radius [m]; points farther from the surface report inf
                (up to a relative 1e-9). None searches without limit.

        Returns:
            The nearest points, their faces and distances, and each point's side.

        Raises:
            OgcpError: For points that are not finite with shape (n, 3).
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3 or not np.all(np.isfinite(points)):
            raise OgcpError(f"query points must be finite with shape (n, 3), got {points.shape}")
        n = len(points)
        distance = np.full(n, np.inf)
        face = np.full(n, -1, dtype=np.intp)
        point = np.full((n, 3), np.nan)
        outside = np.zeros(n, dtype=bool)
        if n == 0:
            return Nearest(distance, face, point, outside)
        # The search radius adapts to each point: the distance to some nearby triangle.
        bound = self._upper_bounds(points)
        if max_distance is not None:
            bound = np.minimum(bound, float(max_distance))
        query_parts, face_parts = [], []
        for members, tree, group_radius in self.groups:
            found = tree.query_ball_point(points, bound + group_radius, return_sorted=False)
            counts = np.fromiter((len(f) for f in found), dtype=np.intp, count=n)
            if not counts.sum():
                continue
            faces = members[np.fromiter(itertools.chain.from_iterable(found), dtype=np.intp, count=int(counts.sum()))]
            query = np.repeat(np.arange(n), counts)
            # The group's radius bounds every member; each triangle's own radius prunes more.
            gap = np.linalg.norm(points[query] - self.centroids[faces], axis=1) - self.radii[faces]
            keep = gap <= bound[query]
            query_parts.append(query[keep])
            face_parts.append(faces[keep])
        if not sum(len(q) for q in query_parts):
            return Nearest(distance, face, point, outside)
        query, faces = np.concatenate(query_parts), np.concatenate(face_parts)
        d, q, feature = self._measure(query, faces, points)
        # The slack keeps the triangle that set an upper bound, whatever the rounding.
        within = d <= bound[query] * (1 + _SLACK)
        query, faces, d, q, feature = query[within], faces[within], d[within], q[within], feature[within]
        order = np.lexsort((faces, d, query))  # ties go to the lowest face index, for determinism
        hit, first = np.unique(query[order], return_index=True)
        best = order[first]
        distance[hit], face[hit], point[hit] = d[best], faces[best], q[best]
        outside[hit] = self._side(points[hit], q[best], faces[best], feature[best]) > 0
        return Nearest(distance, face, point, outside)

    def _side(
        self,
        points: NDArray[np.float64],
        nearest: NDArray[np.float64],
        faces: NDArray[np.intp],
        feature: NDArray[np.int8],
    ) -> NDArray[np.float64]:
        """Signed offset of points along the pseudonormal of their nearest feature: > 0 outside."""
        normal = self.normals[faces].copy()
        on_edge = (feature >= EDGE_AB) & (feature <= EDGE_CA)
        normal[on_edge] = self.edge_normals[faces[on_edge], feature[on_edge] - EDGE_AB]
        on_corner = feature >= CORNER_A
        normal[on_corner] = self.corner_normals[faces[on_corner], feature[on_corner] - CORNER_A]
        return _dot(points - nearest, normal)

    def distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Exact unsigned distance of points to the surface, shape (n,) [m]."""
        return self.nearest(points).distance
