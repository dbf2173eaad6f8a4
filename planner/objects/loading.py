"""Loading object meshes from files (units are metres; meshes are used as given).

A file is planned on only if all of it was read and it bounds a solid: trimesh parses it,
and the checks around the parse refuse what trimesh would silently drop or misread
(a file cut short, counts that disagree, faces pointing at missing vertices, non-finite
coordinates, flat or open surfaces). The only changes made to a mesh are re-orientations
with a single right answer and the removal of faces that name a vertex twice (no area, no
orientation), each announced by a :class:`MeshOrientationWarning`. A file of several closed
shells is one object touched only on its outer surface (:mod:`ogcp.planner.grasp.shells`), which a
:class:`MeshShellsWarning` says.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import trimesh

from ogcp.planner.grasp.shells import Shells
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.file_checks import check_mesh_file
from ogcp.planner.objects.repair import MeshOrientationWarning, require_solid

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")


class MeshShellsWarning(UserWarning):
    """A mesh file holds several closed shells: one object, touched only on its outer surface."""


def load_mesh(path: str | Path, solid: bool = True) -> trimesh.Trimesh:
    """Read a triangle mesh from a file trimesh understands, and check that it bounds a solid.

    Args:
        path: Mesh file (OBJ, STL, PLY, OFF, GLB, glTF), coordinates in metres.
        solid: Require a closed, consistently wound surface; False leaves that to the caller
            (``ogcp assets fetch`` repairs the meshes it downloads: fills holes, then checks).

    Returns:
        The mesh (scenes are concatenated into one mesh; duplicate vertices merged), with
        outward normals: a mesh whose winding was mixed or inside out is re-oriented, with a
        :class:`MeshOrientationWarning` saying so.

    Raises:
        OgcpError: One line naming the file, when it is missing, unreadable, truncated or
            inconsistent (counts, face indices), holds no triangles or non-finite
            coordinates, or is flat, open or otherwise no closed surface.
    """
    path = Path(path)
    if not path.is_file():
        raise OgcpError(f"mesh file not found: {path}")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise OgcpError(f"{path}: unsupported mesh format {path.suffix!r}; supported: {', '.join(MESH_SUFFIXES)}")
    check_mesh_file(path)
    try:
        # Unprocessed first: processing merges vertices and drops non-finite ones without a word.
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for corrupt files
        raise OgcpError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})".splitlines()[0]) from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise OgcpError(f"{path}: file holds no triangle mesh")
    _check_arrays(path, np.asarray(mesh.vertices), np.asarray(mesh.faces))
    # The same result as loading with process=True, which ogcp always used (checked on every
    # built-in object and fetched mesh): merged duplicate vertices, unreferenced ones removed.
    mesh.process()
    if mesh.area <= 0:
        raise OgcpError(f"{path}: mesh has zero surface area")
    if not solid:  # the caller repairs it (repair_mesh drops such faces too)
        return mesh
    dropped = _drop_collapsed_faces(mesh)
    try:
        mesh, steps = require_solid(mesh)
    except OgcpError as exc:
        hint = f"; `ogcp assets repair {path} --out FILE` closes its holes" if "mesh is open" in str(exc) else ""
        raise OgcpError(f"{path}: {exc}{hint}") from None
    steps = (*dropped, *steps)
    if steps:
        warnings.warn(f"{path}: {'; '.join(steps)}", MeshOrientationWarning, stacklevel=2)
    shells = Shells(mesh.vertices, mesh.faces).count
    if shells > 1:
        warnings.warn(
            f"{path}: the mesh is {shells} closed shells (bodies modelled inside or through one another, or apart): "
            "no contact is sampled where one lies inside another, and they are grasped as one rigid body",
            MeshShellsWarning,
            stacklevel=2,
        )
    return mesh


def _drop_collapsed_faces(mesh: trimesh.Trimesh) -> tuple[str, ...]:
    """Drop the faces that name one vertex twice (in place), and say how many.

    CAD and scan exports often hold slivers whose corners merge into one vertex: such a face has
    no area and no orientation, and its zero-length edge would make a closed mesh look open.
    Faces of three distinct collinear vertices stay (their edges are their neighbours').
    """
    faces = np.asarray(mesh.faces)
    collapsed = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    if not collapsed.any():
        return ()
    mesh.update_faces(~collapsed)
    mesh.remove_unreferenced_vertices()
    count = int(collapsed.sum())
    return (f"dropped {count} degenerate face{'s' if count > 1 else ''} (a vertex named twice: no area)",)


def _check_arrays(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Refuse faces that index missing vertices and vertices that are not finite.

    The file checks catch these with line numbers for OFF, OBJ and PLY; this catches them for
    every format, in the order trimesh read them (vertex and face numbers count from 0).
    """
    outside = (faces < 0) | (faces >= len(vertices))
    if outside.any():
        face = int(np.argmax(outside.any(axis=1)))
        vertex = int(faces[face][outside[face]][0])
        raise OgcpError(
            f"{path}: face {face} references vertex {vertex}, file has {len(vertices)} vertices (0 to {len(vertices) - 1})"
        )
    bad = ~np.all(np.isfinite(vertices), axis=1)
    if bad.any():
        raise OgcpError(
            f"{path}: {int(bad.sum())} of {len(vertices)} vertices have non-finite coordinates (NaN or inf), "
            f"the first is vertex {int(np.argmax(bad))} (counting from 0)"
        )
