"""The surface the simulator collides with (the union of convex parts), measured where the fingers touch.

A plan's contacts lie on the mesh; the simulator collides with convex parts that approximate
it. Two questions follow, both answered here against the exact parts (the same vertices MuJoCo
takes as mesh geoms, which it hulls):

* How far is the collision surface from the mesh at a contact? :meth:`CollisionSurface.offsets`
  walks along the contact normal and reports where the ray first enters a part, relative to the
  contact: the decomposition's error where a finger touches.
* Where does a fingertip touch? :func:`place_tips` starts each tip at its planned place and
  moves it along the contact normal until it just touches the parts, so that no tip starts
  inside the collision geometry; the point it then touches is the realized contact.

Each part is a closed convex mesh with outward faces, so its signed distance is exact: outside,
the distance to its nearest triangle; inside, minus the distance to its nearest facet plane.
The minimum over the parts is 1-Lipschitz, which makes the placement's steps safe (a step of the
current distance never crosses the surface).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.grasp.mesh_distance import nearest_on_triangles, triangle_distances
from ogcp.planner.infra.errors import OgcpError

Part = tuple[NDArray[np.float64], NDArray[np.int64]]
PLACEMENT_ITERATIONS = 200  # conservative-advancement steps; a few suffice unless the normal grazes the part
PLACEMENT_TOLERANCE = 1e-4  # touching: the tip's gap to the parts lies in [0, this x radius]


def _unit_rows(vectors: ArrayLike, name: str, shape: tuple[int, ...]) -> NDArray[np.float64]:
    array = np.asarray(vectors, dtype=np.float64)
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise OgcpError(f"{name} must be finite with shape {shape}, got {array.shape}")
    lengths = np.linalg.norm(array, axis=1)
    if np.any(lengths == 0):
        raise OgcpError(f"{name} must not be zero")
    return array / lengths[:, None]


@dataclass(frozen=True, eq=False)
class CollisionSurface:
    """The union of an object's convex parts, ready for distance and ray queries.

    Attributes:
        triangles: Each part's triangles, shape (f_k, 3, 3) [m].
        planes: Each part's facet planes ``(unit outward normal, offset)``, shape (f_k, 4):
            ``normal · x + offset`` is the signed distance to the plane [m].
    """

    triangles: tuple[NDArray[np.float64], ...]
    planes: tuple[NDArray[np.float64], ...]

    @classmethod
    def from_parts(cls, parts: Sequence[Part]) -> CollisionSurface:
        """Prepare the parts ``(vertices (v, 3) [m], faces (f, 3))``, each closed, convex, outward-facing."""
        if len(parts) == 0:
            raise OgcpError("cannot collide with an empty set of convex parts")
        triangles, planes = [], []
        for k, (vertices, faces) in enumerate(parts):
            corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
            normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
            area = np.linalg.norm(normal, axis=1)
            keep = area > 0
            if not np.any(keep):
                raise OgcpError(f"convex part {k} has no faces with area")
            unit = normal[keep] / area[keep, None]
            triangles.append(corners[keep])
            planes.append(np.column_stack([unit, -np.einsum("ij,ij->i", unit, corners[keep, 0])]))
        return cls(tuple(triangles), tuple(planes))

    def signed_distance(
        self, points: ArrayLike, nearest: bool = True
    ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
        """Signed distance of points to the union, and the nearest surface point of the nearest part.

        Args:
            points: Query points, shape (n, 3) [m].
            nearest: Also return the nearest points.

        Returns:
            ``(distance (n,) [m], nearest point (n, 3) [m] or None when not asked for)``: the
            minimum over the parts of each part's exact signed distance (positive outside
            every part); the nearest point is on the part that attains it (for points inside,
            the projection onto its nearest facet plane). Inside the union this bounds the
            depth from below (a point deep in the union may lie near each part's boundary).

        Raises:
            OgcpError: For points that are not finite (n, 3).
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3 or not np.all(np.isfinite(points)):
            raise OgcpError(f"query points must be finite with shape (n, 3), got {points.shape}")
        best = np.full(len(points), np.inf)
        closest = np.zeros((len(points), 3))
        for triangles, planes in zip(self.triangles, self.planes, strict=True):
            heights = points @ planes[:, :3].T + planes[:, 3]
            top = heights.max(axis=1)
            inside = top <= 0
            distance = top.copy()
            point = np.empty_like(points)
            if np.any(inside):
                facet = np.argmax(heights[inside], axis=1)
                point[inside] = points[inside] - top[inside, None] * planes[facet, :3]
            if np.any(~inside) and nearest:
                distance[~inside], point[~inside] = nearest_on_triangles(points[~inside], triangles)
            elif np.any(~inside):
                distance[~inside] = triangle_distances(points[~inside], triangles).min(axis=1)
            closer = distance < best
            best[closer], closest[closer] = distance[closer], point[closer]
        return best, (closest if nearest else None)

    def offsets(self, positions: ArrayLike, inward_normals: ArrayLike, reach: float) -> NDArray[np.float64]:
        """Where the collision surface lies along each contact's normal, relative to the contact.

        A ray from ``p - reach n`` along the inward normal n enters the union at ``p + s n``;
        ``s`` is the offset: negative where the parts stand proud of the mesh (a tip placed at
        the contact would start inside them), positive where they fall short of it.

        Args:
            positions: Contacts on the mesh, shape (m, 3) [m].
            inward_normals: Inward unit normals there, shape (m, 3).
            reach: How far to look on either side of the contact [m] (> 0).

        Returns:
            Offsets, shape (m,) [m]: ``-reach`` where the ray starts inside a part already
            (the parts stand out by at least that much), NaN where no part lies within
            ``reach`` beyond the contact.
        """
        positions = np.asarray(positions, dtype=np.float64)
        normals = _unit_rows(inward_normals, "contact normals", positions.shape)
        if not reach > 0:
            raise OgcpError(f"reach must be a positive length, got {reach!r}")
        origins = positions - reach * normals
        entry = np.full(len(positions), np.inf)
        for planes in self.planes:
            start = origins @ planes[:, :3].T + planes[:, 3]  # (m, f): > 0 outside that facet
            rate = normals @ planes[:, :3].T
            with np.errstate(divide="ignore", invalid="ignore"):
                crossing = -start / rate
            # Entering facets (rate < 0) bound the ray's parameter below, leaving ones above;
            # a parallel facet the origin lies outside of rules the part out.
            lower = np.where(rate < 0, crossing, -np.inf).max(axis=1)
            upper = np.where(rate > 0, crossing, np.inf).min(axis=1)
            missed = np.any((rate == 0) & (start > 0), axis=1)
            hit = ~missed & (lower <= upper) & (upper >= 0)
            entry = np.where(hit, np.minimum(entry, np.maximum(lower, 0.0)), entry)
        offset = entry - reach
        return np.where(entry <= 2 * reach, offset, np.nan)


@dataclass(frozen=True, eq=False)
class TipPlacement:
    """Where each fingertip starts and what it touches there.

    Attributes:
        planned_points: The planned contacts, shape (m, 3) [m].
        planned_normals: Their inward unit normals, shape (m, 3).
        centres: Tip centres, shape (m, 3) [m].
        points: Realized contacts: the nearest point of the parts to each centre, shape (m, 3) [m].
        normals: Realized inward normals (from the centre towards the realized contact), shape (m, 3).
        travel: How far each tip moved from its planned start, outward positive, shape (m,) [m].
        gap: Final distance between each tip's sphere and the parts, shape (m,) [m]: within
            ``[0, PLACEMENT_TOLERANCE x radius]`` where placed.
        placed: Whether each tip touches the parts within the allowed travel, shape (m,).
    """

    planned_points: NDArray[np.float64]
    planned_normals: NDArray[np.float64]
    centres: NDArray[np.float64]
    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    travel: NDArray[np.float64]
    gap: NDArray[np.float64]
    placed: NDArray[np.bool_]

    @property
    def offsets(self) -> NDArray[np.float64]:
        """Distance of each realized contact from its planned one, shape (m,) [m]."""
        return np.linalg.norm(self.points - self.planned_points, axis=1)

    @property
    def normal_angles(self) -> NDArray[np.float64]:
        """Angle between each realized and planned normal, shape (m,) [deg]."""
        cosine = np.clip(np.einsum("ij,ij->i", self.planned_normals, self.normals), -1.0, 1.0)
        return np.degrees(np.arccos(cosine))


def place_tips(
    surface: CollisionSurface,
    positions: ArrayLike,
    inward_normals: ArrayLike,
    radius: float,
    max_inward: float,
) -> TipPlacement:
    """Start every tip on the collision surface: moved along its contact normal until it just touches.

    The planned start is the sphere touching the mesh at the contact (centre ``p - r n``).
    Each step moves the centre along the normal by the sphere's current signed gap to the
    parts minus half the tolerance; since that gap is 1-Lipschitz the step never carries a
    touching-or-outside tip into penetration, and from inside it ends within half a tolerance
    of touching. The tip comes out of parts that stand proud of the mesh, and goes in (at
    most ``max_inward``) where they fall short of it.

    Args:
        surface: The parts.
        positions: Planned contacts, shape (m, 3) [m].
        inward_normals: Planned inward normals, shape (m, 3).
        radius: Fingertip sphere radius r [m].
        max_inward: Farthest a tip may move inward from its planned start [m].

    Returns:
        The placement; a tip that finds no part within ``max_inward`` stays at its planned
        start with ``placed`` False.
    """
    positions = np.asarray(positions, dtype=np.float64)
    normals = _unit_rows(inward_normals, "contact normals", positions.shape)
    if not (np.isfinite(radius) and radius > 0):
        raise OgcpError(f"fingertip radius must be a positive length, got {radius!r}")
    tolerance = PLACEMENT_TOLERANCE * radius
    travel = np.zeros(len(positions))
    active = np.ones(len(positions), dtype=bool)
    for _iteration in range(PLACEMENT_ITERATIONS):
        centres = positions - (radius + travel)[:, None] * normals
        gap = surface.signed_distance(centres[active], nearest=False)[0] - radius
        done = (gap >= 0) & (gap <= tolerance)
        step = gap - 0.5 * tolerance
        travel[active] = np.where(done, travel[active], travel[active] - step)
        active[np.flatnonzero(active)[done]] = False
        if not np.any(active) or np.all(travel[active] < -max_inward):
            break
    lost = travel < -max_inward
    travel[lost] = 0.0
    centres = positions - (radius + travel)[:, None] * normals
    distance, nearest = surface.signed_distance(centres)
    assert nearest is not None
    gap, points = distance - radius, nearest
    toward = points - centres
    length = np.linalg.norm(toward, axis=1)
    realized = np.where(length[:, None] > 0, toward / np.where(length > 0, length, 1.0)[:, None], normals)
    placed = ~lost & (gap >= -tolerance) & (gap <= 2 * tolerance)
    return TipPlacement(positions, normals, centres, points, realized, travel, gap, placed)
