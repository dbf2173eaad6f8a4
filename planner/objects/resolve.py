"""One object argument (a built-in name, a fetched name or a mesh path) to a mesh and its source."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import trimesh

from ogcp.planner.infra.cache import file_sha256
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.builtin import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, builtin_mesh, normalise_scale
from ogcp.planner.objects.fetch import load_fetched
from ogcp.planner.objects.fetchable import FETCHABLE_OBJECTS
from ogcp.planner.objects.loading import load_mesh

#: Diagonals [m] of mesh files read at their own size beyond which the file's units are probably not
#: metres (CAD exports in millimetres): ogcp's objects span 5 cm to 2 m.
PLAUSIBLE_DIAGONAL = (0.005, 5.0)


class MeshScaleWarning(UserWarning):
    """A mesh file read at its own size is so large or so small that its units are probably not metres."""


def resolve_object(spec: str, diagonal: float | None = None) -> tuple[trimesh.Trimesh, dict[str, object]]:
    """Turn a user's object argument (a built-in name, a fetched name or a mesh path) into a mesh.

    Fetched objects (``ogcp.planner.objects.fetchable.FETCHABLE_OBJECTS``) come from the cache only;
    nothing is downloaded here (``ogcp assets fetch`` does that).

    Args:
        spec: Built-in object name, fetched object name, or path to a mesh file.
        diagonal: Bounding-box diagonal [m]. None: :data:`DEFAULT_DIAGONAL` for built-in and
            fetched objects, the file's own size for a mesh file. Given for a mesh file, the mesh
            is centred on its bounding-box centre and scaled uniformly to it (the built-ins'
            normalisation, so one frame convention), and the source records it.

    Returns:
        ``(mesh, source)`` where ``source`` describes the object for provenance records.

    Raises:
        OgcpError: If ``spec`` is none of these, names a fetched object that is not cached, or
            ``diagonal`` is not a positive number.
    """
    if diagonal is not None and not (np.isfinite(diagonal) and diagonal > 0):
        raise OgcpError(f"object diagonal must be a positive number of metres, got {diagonal!r}")
    if spec in BUILTIN_OBJECTS:
        diagonal = DEFAULT_DIAGONAL if diagonal is None else diagonal
        return builtin_mesh(spec, diagonal), {"kind": "builtin", "name": spec, "diagonal": diagonal}
    if spec in FETCHABLE_OBJECTS:
        return load_fetched(spec, DEFAULT_DIAGONAL if diagonal is None else diagonal)
    path = Path(spec)
    if path.suffix == "" and not path.exists():
        # Grouped rather than one sorted list, so that the user sees which names need a fetch first.
        raise OgcpError(
            f"unknown object {spec!r}; valid choices: built-in {', '.join(sorted(BUILTIN_OBJECTS))}; "
            f"fetched with `ogcp assets fetch` {', '.join(sorted(FETCHABLE_OBJECTS))}; "
            "or a path to a mesh file"
        )
    mesh = load_mesh(path)
    source: dict[str, object] = {"kind": "mesh", "path": str(path), "sha256": file_sha256(path)}
    if diagonal is not None:
        # Recorded only when given, so that records of mesh files at their own size are unchanged.
        mesh = normalise_scale(mesh, diagonal)
        source["diagonal"] = diagonal
    else:
        _check_units(path, float(np.linalg.norm(mesh.extents)))
    return mesh, source


def _check_units(path: Path, size: float) -> None:
    """Warn (one line) where a mesh read in metres is implausibly large or small for a grasped object."""
    low, high = PLAUSIBLE_DIAGONAL
    if low <= size <= high:
        return
    units = f"; in millimetres it would be {size / 1000:.4g} m" if size > high else ""
    warnings.warn(
        f"{path}: the mesh is {size:.4g} m across (its bounding-box diagonal, read in metres){units}: "
        f"give --diagonal with its size in metres, or scale the file",
        MeshScaleWarning,
        stacklevel=3,
    )
