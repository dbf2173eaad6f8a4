"""Object meshes: built-in procedural objects and loading meshes from files.

Built-in objects are watertight, centred on their bounding-box centre and scaled to a
bounding-box diagonal of ``DEFAULT_DIAGONAL`` (0.2 m). User meshes are used as given
(units are metres).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from planner.asset_registry import FETCHABLE_OBJECTS
from planner.errors import OgcpError, choice_error

DEFAULT_DIAGONAL = 0.2  # [m]
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")


def _box() -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(3.0, 2.0, 1.4))


def _sphere() -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=4, radius=1.0)


def _donut() -> trimesh.Trimesh:
    return trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=64, minor_sections=32)


def _amphora() -> trimesh.Trimesh:
    # Profile (radius, height) of a vase: foot, belly, shoulder, neck and lip, closed on
    # the axis at both ends so the surface of revolution is watertight.
    heights = np.linspace(0.0, 1.0, 41)
    radius = (
        0.16
        + 0.26 * np.exp(-(((heights - 0.38) / 0.2) ** 2))
        - 0.06 * np.exp(-(((heights - 0.8) / 0.06) ** 2))
        + 0.05 * np.exp(-(((heights - 0.98) / 0.03) ** 2))
    )
    profile = np.column_stack([radius, heights * 1.6])
    profile = np.vstack([[0.0, 0.0], profile, [0.0, 1.6]])
    return trimesh.creation.revolve(profile, sections=64)


#: Registry of built-in procedural objects: name -> factory of an unscaled mesh.
BUILTIN_OBJECTS: dict[str, Callable[[], trimesh.Trimesh]] = {
    "amphora": _amphora,
    "box": _box,
    "donut": _donut,
    "sphere": _sphere,
}


def normalise_scale(mesh: trimesh.Trimesh, diagonal: float = DEFAULT_DIAGONAL) -> trimesh.Trimesh:
    """Centre a mesh on its bounding-box centre and scale it to a bounding-box diagonal.

    Args:
        mesh: Input mesh (not modified).
        diagonal: Target bounding-box diagonal [m].

    Returns:
        A scaled copy.
    """
    out = mesh.copy()
    lo, hi = out.bounds
    out.apply_translation(-(lo + hi) / 2.0)
    out.apply_scale(diagonal / float(np.linalg.norm(hi - lo)))
    return out


def builtin_mesh(name: str, diagonal: float = DEFAULT_DIAGONAL) -> trimesh.Trimesh:
    """Build a built-in procedural object.

    Args:
        name: One of :data:`BUILTIN_OBJECTS`.
        diagonal: Bounding-box diagonal [m].

    Returns:
        A watertight mesh.

    Raises:
        OgcpError: For an unknown name.
    """
    if name not in BUILTIN_OBJECTS:
        raise choice_error("object", name, BUILTIN_OBJECTS)
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise OgcpError(f"object diagonal must be a positive number of metres, got {diagonal!r}")
    return normalise_scale(BUILTIN_OBJECTS[name](), diagonal)


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


def resolve_object(spec: str, diagonal: float = DEFAULT_DIAGONAL) -> tuple[trimesh.Trimesh, dict[str, object]]:
    """Turn a user's object argument (a built-in name, a fetched name or a mesh path) into a mesh.

    Fetched objects (``planner.asset_registry.FETCHABLE_OBJECTS``) come from the cache only;
    nothing is downloaded here (``ogcp assets fetch`` does that).

    Args:
        spec: Built-in object name, fetched object name, or path to a mesh file.
        diagonal: Bounding-box diagonal for built-in and fetched objects [m].

    Returns:
        ``(mesh, source)`` where ``source`` describes the object for provenance records.

    Raises:
        OgcpError: If ``spec`` is none of these, or names a fetched object that is not cached.
    """
    if spec in BUILTIN_OBJECTS:
        return builtin_mesh(spec, diagonal), {"kind": "builtin", "name": spec, "diagonal": diagonal}
    if spec in FETCHABLE_OBJECTS:
        # Imported here because planner.assets builds on this module.
        from planner.assets import load_fetched

        return load_fetched(spec, diagonal)
    path = Path(spec)
    if path.suffix == "" and not path.exists():
        # Grouped rather than one sorted list, so that the user sees which names need a fetch first.
        raise OgcpError(f"unknown object {spec!r}; valid choices: built-in {', '.join(sorted(BUILTIN_OBJECTS))}; "
                        f"fetched with `ogcp assets fetch` {', '.join(sorted(FETCHABLE_OBJECTS))}; "
                        "or a path to a mesh file")
    mesh = load_mesh(path)
    return mesh, {"kind": "mesh", "path": str(path), "sha256": file_sha256(path)}
