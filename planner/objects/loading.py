"""Loading object meshes from files (units are metres; meshes are used as given)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import trimesh

from planner.infra.errors import OgcpError

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")


def file_sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def load_mesh(path: str | Path) -> trimesh.Trimesh:
    """Read a triangle mesh from a file trimesh understands.

    Args:
        path: Mesh file (OBJ, STL, PLY, OFF, GLB, glTF).

    Returns:
        The mesh (scenes are concatenated into one mesh).

    Raises:
        OgcpError: When the file is missing, unreadable, or holds no triangles.
    """
    path = Path(path)
    if not path.is_file():
        raise OgcpError(f"mesh file not found: {path}")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise OgcpError(f"{path}: unsupported mesh format {path.suffix!r}; supported: {', '.join(MESH_SUFFIXES)}")
    try:
        mesh = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types for corrupt files
        raise OgcpError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})".splitlines()[0]) from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise OgcpError(f"{path}: file holds no triangle mesh")
    if not np.all(np.isfinite(mesh.vertices)):
        raise OgcpError(f"{path}: mesh has non-finite vertex coordinates")
    if mesh.area <= 0:
        raise OgcpError(f"{path}: mesh has zero surface area")
    return mesh
