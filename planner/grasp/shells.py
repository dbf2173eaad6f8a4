"""The closed shells of a mesh, and which surface points lie inside another shell.

A CAD export is often several closed bodies in one file: a part modelled inside another, two
bodies that overlap where a union was never computed, or a cavity (an inner shell facing inward).
Each shell is a closed surface, so the mesh passes as a solid, but the surface of one shell inside
another is inside the object: a fingertip cannot touch it. The nearest-triangle test of
:class:`~ogcp.planner.grasp.mesh_distance.SurfaceIndex` sees only the shell it is nearest to;
:meth:`Shells.enclosed` asks every other shell, by its generalised winding number (the solid angle
it subtends over 4 pi: 1 inside a closed shell, 0 outside, -1 inside one facing inward), so a point
inside any other shell, of either orientation, is enclosed. Only shells whose bounding box holds a
point are asked, so a mesh of one shell, or of shells apart, costs nothing more.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["Shells"]

#: Triangle-point pairs whose solid angles one batch computes (bounds its memory, about 0.1 GB).
_BATCH = 1_000_000
#: Vertices of a shell asked whether they lie inside another before the shell is taken as enclosed.
OUTER_PROBES = 32


class Shells:
    """The face-connected shells of a triangle mesh.

    Args:
        vertices: Vertex positions, shape (V, 3) [m].
        faces: Triangles, shape (F, 3), wound outward.

    Attributes:
        labels: The shell of each face, shape (F,).
        count: Number of shells.
    """

    def __init__(self, vertices: ArrayLike, faces: ArrayLike) -> None:
        self.vertices = np.asarray(vertices, dtype=np.float64)
        self.faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        self.count, self.labels = _face_components(self.faces)
        corners = self.vertices[self.faces].reshape(-1, 3)  # (3F, 3)
        if self.count < 2:  # nothing to ask of another shell
            self.low, self.high = corners.min(axis=0)[None], corners.max(axis=0)[None]
            return
        owner = np.repeat(self.labels, 3)
        order = np.argsort(owner, kind="stable")
        starts = np.searchsorted(owner[order], np.arange(self.count))
        self.low = np.minimum.reduceat(corners[order], starts, axis=0)
        self.high = np.maximum.reduceat(corners[order], starts, axis=0)

    def enclosed(self, points: ArrayLike, own_faces: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point lies inside a shell other than the one of its own face.

        Args:
            points: Points just off the surface (a fingertip's centre), shape (n, 3) [m].
            own_faces: The face each point belongs to, shape (n,); its shell is not asked.

        Returns:
            Mask, shape (n,).
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        own = self.labels[np.asarray(own_faces, dtype=np.intp)]
        inside = np.zeros(len(points), dtype=bool)
        if self.count < 2:
            return inside
        for shell in range(self.count):
            boxed = np.all((points >= self.low[shell]) & (points <= self.high[shell]), axis=1) & (own != shell)
            asked = np.flatnonzero(boxed & ~inside)
            if len(asked):
                triangles = self.vertices[self.faces[self.labels == shell]]
                inside[asked] = np.abs(_winding_numbers(triangles, points[asked])) >= 0.5
        return inside

    def outer(self, probes: int = OUTER_PROBES) -> list[tuple[NDArray[np.float64], NDArray[np.int64]]]:
        """The shells not wholly inside another, each as its own (vertices (V, 3) [m], faces (F, 3)).

        A shell counts as inside when ``probes`` of its vertices, spread over it, all are: a part
        modelled inside the object or a cavity's wall. Overlapping shells and shells apart are kept.
        """
        if self.count < 2:
            return [(self.vertices, self.faces)]
        kept = []
        for shell in range(self.count):
            faces = self.faces[self.labels == shell]
            used = np.unique(faces)
            probe = used[np.linspace(0, len(used) - 1, min(probes, len(used))).astype(np.intp)]
            own = np.full(len(probe), int(np.flatnonzero(self.labels == shell)[0]))
            if self.enclosed(self.vertices[probe], own).all():
                continue
            index = np.full(len(self.vertices), -1, dtype=np.int64)
            index[used] = np.arange(len(used))
            kept.append((self.vertices[used], index[faces]))
        return kept


def _face_components(faces: NDArray[np.int64]) -> tuple[int, NDArray[np.intp]]:
    """Shells as sets of faces joined by shared vertices: (count, label of each face (F,)).

    Vertices, not edges: linear in the faces (0.03 s for 327,680), and a loaded mesh has its
    duplicate vertices merged, so two shells share a vertex only where they touch.
    """
    size = int(faces.max()) + 1 if len(faces) else 0
    a = np.concatenate([faces[:, 0], faces[:, 1]])
    b = np.concatenate([faces[:, 1], faces[:, 2]])
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(size, size))
    _, vertex_labels = connected_components(graph, directed=False)
    used = np.unique(vertex_labels[faces[:, 0]], return_inverse=True)[1]  # unused vertices form no shell
    return int(used.max()) + 1 if len(faces) else 0, np.asarray(used, dtype=np.intp).reshape(-1)


def _winding_numbers(triangles: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Generalised winding number of a closed triangle surface (T, 3, 3) at points (n, 3), shape (n,).

    The solid angle of each triangle seen from a point (Van Oosterom and Strackee), summed over
    the triangles and divided by 4 pi, in batches of :data:`_BATCH` triangle-point pairs.
    """
    out = np.empty(len(points))
    step = max(1, _BATCH // max(len(triangles), 1))
    for start in range(0, len(points), step):
        rel = triangles[None, :, :, :] - points[start : start + step, None, None, :]  # (k, T, 3, 3)
        a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
        la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
        det = _dot(a, np.cross(b, c))
        denominator = la * lb * lc + _dot(a, b) * lc + _dot(b, c) * la + _dot(c, a) * lb
        out[start : start + step] = 2.0 * np.arctan2(det, denominator).sum(axis=1) / (4.0 * np.pi)
    return out


def _dot(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise dot products of (k, T, 3) arrays, shape (k, T)."""
    return np.asarray(np.einsum("ktj,ktj->kt", u, v))
