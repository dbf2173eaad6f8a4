"""Deterministic mesh repair with numpy and scipy: winding, holes and inward-facing meshes.

trimesh's own repair functions need networkx, which ogcp does not depend on. Every fetched mesh
goes through :func:`repair_mesh` before its normals and centroid are used; every mesh file a
user names goes through :func:`require_solid`, which fixes only what has one right answer
(winding, inside-out) and refuses what ogcp cannot plan on (flat or open surfaces).
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.tolerance import TOL

__all__ = ["MeshOrientationWarning", "repair_mesh", "require_solid"]

#: What every refusal of :func:`require_solid` asks for.
_NEEDS = "ogcp needs a closed, watertight surface for the object's volume, centre of mass and inward normals"


class MeshOrientationWarning(UserWarning):
    """A mesh's faces were re-oriented: their winding disagreed, or they pointed inward."""


def _traverses(faces: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Whether each face (row of ``faces``, shape (P, 3)) runs along its edge from ``u`` to ``v``."""
    at_u = np.argmax(faces == u[:, None], axis=1)
    at_v = np.argmax(faces == v[:, None], axis=1)
    return (at_u + 1) % 3 == at_v


def _orient_consistently(mesh: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """Flip faces so that neighbours run along shared edges in opposite directions.

    Each connected component keeps the orientation of the majority of its faces. Returns the
    re-oriented mesh, or ``None`` when no face needs flipping.
    """
    faces = np.array(mesh.faces)
    pairs, shared = mesh.face_adjacency, mesh.face_adjacency_edges
    same = _traverses(faces[pairs[:, 0]], shared[:, 0], shared[:, 1]) == _traverses(
        faces[pairs[:, 1]], shared[:, 0], shared[:, 1]
    )
    n = len(faces)
    # Edge weights 1 (keep relative orientation) and 2 (flip): a stored zero would vanish from the graph.
    weights = np.concatenate([same, same]).astype(np.int8) + 1
    graph = coo_matrix(
        (weights, (np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]]))),
        shape=(n, n),
    ).tocsr()
    flip = np.zeros(n, dtype=bool)
    _, labels = connected_components(graph, directed=False)
    for label in np.unique(labels):
        root = int(np.flatnonzero(labels == label)[0])
        order, predecessors = breadth_first_order(graph, root, directed=False)
        children = order[1:]
        parents = predecessors[children]
        relative = np.asarray(graph[parents, children]).ravel() == 2
        # Parents come before children in breadth-first order, so one pass settles every face.
        for face, parent, change in zip(children.tolist(), parents.tolist(), relative.tolist()):
            flip[face] = flip[parent] ^ change
        if flip[order].sum() * 2 > len(order):
            flip[order] = ~flip[order]
    if not flip.any():
        return None
    faces[flip] = faces[flip][:, ::-1]
    return trimesh.Trimesh(mesh.vertices, faces, process=False)


def _fill_holes(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int, int]:
    """Close every simple boundary loop: one triangle for a 3-loop, else a fan around the loop's centroid.

    Needs consistent winding: a boundary edge a->b of the mesh becomes b->a in the fill, so the
    new faces continue the orientation. Loops through a pinched vertex (one that starts two
    boundary edges) are left open, since their pairing of edges is ambiguous.

    Returns:
        ``(mesh, holes filled, faces added)``; the input mesh itself when nothing was filled.
    """
    edges = mesh.edges
    _, inverse, counts = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True, return_counts=True)
    following: dict[int, int] = {}
    pinched: set[int] = set()
    for a, b in edges[counts[inverse.ravel()] == 1].tolist():
        if a in following:
            pinched.add(a)
        following[a] = b
    points = np.asarray(mesh.vertices)
    vertices, faces, seen = [points], [np.asarray(mesh.faces)], set(pinched)
    for start in sorted(following):
        if start in seen:
            continue
        loop = [start]
        while (nxt := following.get(loop[-1])) is not None and nxt != start and nxt not in seen and nxt not in loop:
            loop.append(nxt)
        seen.update(loop)
        if nxt != start:
            continue
        ring = np.array(loop)
        if len(ring) == 3:
            faces.append(ring[::-1][None, :])
        else:
            centre = sum(len(v) for v in vertices)
            vertices.append(points[ring].mean(axis=0)[None, :])
            faces.append(np.column_stack([np.roll(ring, -1), ring, np.full(len(ring), centre)]))
    if len(faces) == 1:
        return mesh, 0, 0
    filled = trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), process=False)
    return filled, len(faces) - 1, sum(len(f) for f in faces[1:])


def repair_mesh(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, tuple[str, ...]]:
    """Deterministic repair so that the volume centroid and the outward normals are defined.

    Steps, each applied only when needed: drop degenerate and duplicate faces, make the winding
    consistent (per connected component, towards its majority), fill holes, and invert a closed
    mesh whose faces point inward (negative signed volume), because inward contact normals are
    derived from outward face normals. Written with numpy and scipy only, because trimesh's own
    repair functions need networkx, which ogcp does not depend on.

    Args:
        mesh: Input mesh (not modified); vertices shape (V, 3), any unit.

    Returns:
        ``(repaired copy, descriptions of the steps that changed something)``.
    """
    out = mesh.copy()
    steps: list[str] = []
    faces = len(out.faces)
    out.update_faces(out.nondegenerate_faces())
    out.update_faces(out.unique_faces())
    out.remove_unreferenced_vertices()
    if len(out.faces) != faces:
        steps.append(f"removed {faces - len(out.faces)} degenerate or duplicate faces")
    if not out.is_winding_consistent and (oriented := _orient_consistently(out)) is not None:
        flipped = int(np.sum(np.any(oriented.faces != out.faces, axis=1)))
        out = oriented
        steps.append(f"made the winding consistent (flipped {flipped} faces)")
    if not out.is_watertight:
        out, holes, added = _fill_holes(out)
        if holes:
            steps.append(f"filled {holes} holes with {added} faces")
    if out.is_watertight and out.volume < 0:
        out.invert()
        steps.append("inverted the winding (faces pointed inward)")
    return out, tuple(steps)


def _faces(count: int) -> str:
    return f"{count} face" if count == 1 else f"{count} faces"


def _point(vertex: NDArray[np.float64]) -> str:
    """A vertex [m] for a message: 4 significant digits locate it in any mesh a user can open."""
    return "[" + ", ".join(f"{x:.4g}" for x in vertex) + "]"


def require_solid(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, tuple[str, ...]]:
    """Check that a mesh bounds a solid; re-orient faces where only one orientation is right.

    A closed, orientable surface has exactly two consistent orientations, and the sign of the
    enclosed volume tells them apart, so a mixed or inward winding is fixed rather than
    refused. Flat, open, non-manifold and one-sided surfaces have no volume centroid and no
    inside, so no contact normal can be trusted: they are refused.

    Args:
        mesh: Mesh with finite vertices, shape (V, 3) [m] (not modified).

    Returns:
        ``(mesh, descriptions of the re-orientations)``: the input itself when nothing changed.

    Raises:
        OgcpError: One line, without the file name, saying why the mesh is no solid.
    """
    vertices = np.asarray(mesh.vertices, dtype=float)
    # Singular values of the centred cloud: the smallest is its thickness across the best plane.
    spread = np.linalg.svd(vertices - vertices.mean(axis=0), compute_uv=False)
    if spread[-1] <= TOL.rank * spread[0]:
        raise _refusal(f"mesh is flat (all {len(vertices)} vertices lie in one plane, so it encloses no volume)")
    edges, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    for kind, bad in (("open", counts == 1), ("not a closed surface", counts > 2)):
        if bad.any():
            first = edges[np.argmax(bad)]
            many = int(bad.sum())
            if kind == "open":
                problem = "edges border only one face" if many > 1 else "edge borders only one face"
            else:
                problem = (
                    "edges are shared by more than two faces" if many > 1 else "edge is shared by more than two faces"
                )
            where = f"the first from {_point(vertices[first[0]])} to {_point(vertices[first[1]])}"
            raise _refusal(f"mesh is {kind} ({many} {problem}, {where})")
    steps: list[str] = []
    out = mesh
    if not out.is_winding_consistent:
        oriented = _orient_consistently(out)
        if oriented is None or not oriented.is_winding_consistent:
            raise _refusal("mesh is one-sided (its faces cannot be oriented consistently, like a Klein bottle)")
        flipped = int(np.sum(np.any(oriented.faces != out.faces, axis=1)))
        steps.append(f"winding was mixed: flipped {_faces(flipped)} that disagreed with their neighbours")
        out = oriented
    # Signed volume from the divergence theorem, summed here: trimesh's also divides by it for
    # the centroid, which warns (divide by zero) on exactly the meshes refused next.
    corners = np.asarray(out.vertices, dtype=float)[np.asarray(out.faces)]
    volume = float(np.einsum("ij,ij->", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])) / 6.0)
    diagonal = float(np.linalg.norm(out.extents))
    # Relative to the bounding box, so that millimetre and metre files are judged alike.
    if abs(volume) <= TOL.rank * diagonal**3:
        raise _refusal(
            f"mesh encloses no volume (signed volume {volume:.3g} m^3, bounding-box diagonal {diagonal:.3g} m)"
        )
    if volume < 0:
        out = out.copy()
        out.invert()
        steps.append(
            f"mesh is inside out (its faces point inward, signed volume {volume:.3g} m^3): "
            f"flipped all {_faces(len(out.faces))} so that they point outward"
        )
    return out, tuple(steps)


def _refusal(problem: str) -> OgcpError:
    return OgcpError(f"{problem}; {_NEEDS}")
